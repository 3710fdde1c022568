// The table cache (include/atmo/table_cache.h) and its files (io/table_cache_file.h).
#include "atmo/table_cache.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <new>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <mutex>
#include <system_error>

#include "atmo/error.h"
#include "atmo/image.h"
#include "atmo/memory.h"
#include "atmo_build_id.h"  // generated: ATMO_BUILD_ID (cmake/BuildId.cmake)
#include "io/table_cache_file.h"

namespace atmo {

namespace fs = std::filesystem;

namespace {

std::mutex cache_mutex;
bool cache_set = false;  // before SetTableCache: the shipped tables only
std::optional<TableCache> process_cache;

constexpr char kMagic[8] = {'A', 'T', 'M', 'O', 'T', 'B', 'L', '1'};
constexpr std::uint32_t kByteOrderMarker = 0x01020304u;
constexpr const char* kExtension = ".atmotables";

// FNV-1a, 64 bit, continuing from `hash` (the offset basis 14695981039346656037 to start).
std::uint64_t Fnv1a(const unsigned char* data, std::size_t size, std::uint64_t hash = 14695981039346656037ull) {
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= data[i];
    hash *= 1099511628211ull;
  }
  return hash;
}

std::uint64_t Fnv1a(const std::string& text, std::uint64_t hash = 14695981039346656037ull) {
  return Fnv1a(reinterpret_cast<const unsigned char*>(text.data()), text.size(), hash);
}

// The files' checksum: FNV-1a's step (xor, then multiply by its prime) over 64-bit words of the
// payload, the last one zero-padded, starting from the key's FNV-1a; eight times fewer
// multiplications than byte-wise FNV-1a over tens of MB, and a flipped bit still changes it.
std::uint64_t Checksum(const std::string& key, std::span<const unsigned char> payload) {
  std::uint64_t hash = Fnv1a(key);
  const std::size_t words = payload.size() / 8;
  for (std::size_t i = 0; i < words; ++i) {
    std::uint64_t word;
    std::memcpy(&word, payload.data() + 8 * i, 8);
    hash = (hash ^ word) * 1099511628211ull;
  }
  std::uint64_t last = 0;
  if (payload.size() > 8 * words) std::memcpy(&last, payload.data() + 8 * words, payload.size() - 8 * words);
  hash = (hash ^ last ^ (static_cast<std::uint64_t>(payload.size()) << 56)) * 1099511628211ull;
  return hash;
}

std::string Hex(std::uint64_t value) {
  static const char digits[] = "0123456789abcdef";
  std::string text(16, '0');
  for (int i = 15; i >= 0; --i, value >>= 4) text[i] = digits[value & 15];
  return text;
}

template <typename T>
void Append(std::string& out, const T& value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof value);
}

// Removes the least recently used cache files (by modification time, which a hit renews) while
// the folder holds more than `max_bytes`; `keep` stays.
void Trim(const TableCache& cache, const fs::path& keep) {
  struct Entry {
    fs::file_time_type used;
    std::uintmax_t bytes;
    fs::path path;
  };
  std::vector<Entry> entries;
  std::uintmax_t total = 0;
  std::error_code ec;
  for (fs::directory_iterator it(cache.folder, ec), end; !ec && it != end; it.increment(ec)) {
    const fs::path& path = it->path();
    if (path.extension() != kExtension || !it->is_regular_file(ec)) continue;
    const std::uintmax_t bytes = it->file_size(ec);
    if (ec) continue;
    const fs::file_time_type used = it->last_write_time(ec);
    if (ec) continue;
    entries.push_back({used, bytes, path});
    total += bytes;
  }
  std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) { return a.used < b.used; });
  for (const Entry& entry : entries) {
    if (total <= cache.max_bytes) break;
    if (entry.path == keep) continue;
    if (fs::remove(entry.path, ec)) total -= entry.bytes;
  }
}

}  // namespace

std::vector<fs::path> ShippedTableFolders() {
  std::vector<fs::path> folders;
  // Compile definitions of src/atmo/CMakeLists.txt (none in the WebAssembly build).
#ifdef ATMO_BUILD_TABLES_DIR
  folders.emplace_back(ATMO_BUILD_TABLES_DIR);
#endif
#ifdef ATMO_INSTALL_TABLES_DIR
  folders.emplace_back(ATMO_INSTALL_TABLES_DIR);
#endif
  std::error_code ec;
  std::erase_if(folders, [&](const fs::path& folder) { return !fs::is_directory(folder, ec); });
  return folders;
}

void SetTableCache(std::optional<TableCache> cache) {
  const std::lock_guard<std::mutex> lock(cache_mutex);
  process_cache = std::move(cache);
  cache_set = true;
}

std::optional<TableCache> GetTableCache() {
  const std::lock_guard<std::mutex> lock(cache_mutex);
  if (!cache_set) return TableCache{{}, std::uint64_t{1} << 30, ShippedTableFolders()};
  return process_cache;
}

TableCache DefaultTableCache() {
  TableCache cache{{}, std::uint64_t{1} << 30, ShippedTableFolders()};
  const auto variable = [](const char* name) -> std::optional<std::string> {
    const char* value = std::getenv(name);
    if (value == nullptr) return std::nullopt;
    return std::string(value);
  };
  if (const auto setting = variable("ATMO_TABLE_CACHE")) {
    if (!setting->empty() && *setting != "off") cache.folder = fs::path(*setting);
  } else if (const auto xdg = variable("XDG_CACHE_HOME"); xdg && !xdg->empty() && fs::path(*xdg).is_absolute()) {
    cache.folder = fs::path(*xdg) / "atmo" / "tables";
  } else if (const auto home = variable("HOME"); home && !home->empty()) {
    cache.folder = fs::path(*home) / ".cache" / "atmo" / "tables";
  }
  return cache;
}

std::string_view BuildId() { return ATMO_BUILD_ID; }

namespace io {

std::string TableCacheKey(std::string_view model, const std::map<std::string, std::string>& options,
                          const AtmosphereParameters& parameters) {
  AtmosphereParameters unnamed = parameters;
  unnamed.name = "custom";
  // What scales or frames the images and never enters the tables (per unit solar irradiance):
  // relative and physical units, any exposure and observer share one file
  // (tests/table_cache_test.cc checks that the tables ignore them).
  unnamed.solar_irradiance.assign(unnamed.solar_irradiance.size(), 1.0);
  unnamed.exposure = 10.0;
  unnamed.observer_altitude_m = 0.0;
  std::string key = "atmo table cache 1\nbuild " + std::string(BuildId()) + "\nmodel " + std::string(model) + "\n";
  for (const auto& [option, value] : options) key += "option " + option + "=" + value + "\n";
  return key + "atmosphere " + ToJson(unnamed) + "\n";
}

fs::path CachedTablesPath(const fs::path& folder, const std::string& key) {
  // Two bases, so that a name is 128 bits of the key; the file still holds the whole key.
  return folder / (Hex(Fnv1a(key)) + Hex(Fnv1a(key, 0x84222325cbf29ce4ull)) + kExtension);
}

namespace {

// The file `path` if it holds `key`'s tables (the format of io/table_cache_file.h); `renew` marks
// a hit as recently used.
std::optional<CachedTables> ReadTablesFile(const fs::path& path, const std::string& key, std::uint64_t max_bytes,
                                           bool renew) {
  // Read whole into one buffer that is not zero-filled first (a spectral model's file is tens of
  // MB); the model copies its textures straight out of it.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return std::nullopt;
  struct stat st {};
  const std::size_t header = sizeof kMagic + sizeof kByteOrderMarker + sizeof(std::uint64_t);
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode) || static_cast<std::uint64_t>(st.st_size) > max_bytes ||
      static_cast<std::size_t>(st.st_size) < header) {
    ::close(fd);
    return std::nullopt;
  }
  const std::size_t size = static_cast<std::size_t>(st.st_size);
  CachedTables tables;
  tables.file.reset(new (std::nothrow) unsigned char[size]);
  std::size_t got = 0;
  while (tables.file && got < size) {
    const ssize_t n = ::read(fd, tables.file.get() + got, size - got);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    got += static_cast<std::size_t>(n);
  }
  ::close(fd);
  if (!tables.file || got != size) return std::nullopt;
  const unsigned char* file = tables.file.get();
  if (std::memcmp(file, kMagic, sizeof kMagic) != 0) return std::nullopt;
  std::size_t at = sizeof kMagic;
  const auto read_u64 = [&](std::uint64_t& value) {
    if (size - at < sizeof value) return false;
    std::memcpy(&value, file + at, sizeof value);
    at += sizeof value;
    return true;
  };
  std::uint32_t marker = 0;
  std::memcpy(&marker, file + at, sizeof marker);
  at += sizeof marker;
  std::uint64_t key_size = 0;
  if (marker != kByteOrderMarker || !read_u64(key_size) || key_size != key.size() || size - at < key_size ||
      std::memcmp(file + at, key.data(), key.size()) != 0) {
    return std::nullopt;
  }
  at += key_size;
  std::uint64_t payload_size = 0;
  if (!read_u64(payload_size) || size - at < payload_size) return std::nullopt;
  const std::size_t payload_at = at;
  at += payload_size;
  std::uint64_t checksum = 0;
  if (!read_u64(checksum) || at != size) return std::nullopt;
  if (Checksum(key, std::span<const unsigned char>(file + payload_at, payload_size)) != checksum) return std::nullopt;
  std::error_code ec;
  if (renew) fs::last_write_time(path, fs::file_time_type::clock::now(), ec);  // recently used (best effort)
  tables.payload = std::span<const unsigned char>(file + payload_at, payload_size);
  return tables;
}

}  // namespace

std::optional<CachedTables> ReadCachedTables(const TableCache& cache, const std::string& key) {
  if (!cache.folder.empty()) {
    if (auto tables = ReadTablesFile(CachedTablesPath(cache.folder, key), key, cache.max_bytes, true)) return tables;
  }
  for (const fs::path& folder : cache.shipped) {
    // Shipped files are read whatever the cache's size (they are not the cache's to trim).
    if (auto tables = ReadTablesFile(CachedTablesPath(folder, key), key, std::uint64_t{1} << 40, false)) return tables;
  }
  return std::nullopt;
}

std::string WriteCachedTables(const TableCache& cache, const std::string& key, std::span<const unsigned char> payload) {
  if (cache.folder.empty()) return "";
  const fs::path path = CachedTablesPath(cache.folder, key);
  const std::uint64_t file_bytes = sizeof kMagic + sizeof kByteOrderMarker + 3 * sizeof(std::uint64_t) + key.size() +
                                   payload.size();
  if (file_bytes > cache.max_bytes) return "the tables are larger than the cache (" + FormatBytes(file_bytes) + ")";
  try {
    std::error_code ec;
    fs::create_directories(cache.folder, ec);
    if (ec) throw Error("cannot create the folder: " + ec.message());
    std::string head(kMagic, sizeof kMagic);
    Append(head, kByteOrderMarker);
    Append(head, static_cast<std::uint64_t>(key.size()));
    head += key;
    Append(head, static_cast<std::uint64_t>(payload.size()));
    std::string tail;
    Append(tail, Checksum(key, payload));
    WriteFileAtomically(path, [&](const fs::path& temporary) {
      std::ofstream out(temporary, std::ios::binary);
      out.write(head.data(), static_cast<std::streamsize>(head.size()));
      out.write(reinterpret_cast<const char*>(payload.data()), static_cast<std::streamsize>(payload.size()));
      out.write(tail.data(), static_cast<std::streamsize>(tail.size()));
      out.close();
      if (!out) throw Error("write failed");
    });
  } catch (const std::exception& e) {
    return e.what();
  }
  Trim(cache, path);
  return "";
}

void TableBytesWriter::Raw(const void* data, std::size_t size) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  bytes_.insert(bytes_.end(), bytes, bytes + size);
}

void TableBytesWriter::Int(std::int64_t value) { Raw(&value, sizeof value); }

void TableBytesWriter::Texture(const shared::Texture2D& texture) {
  Int(texture.width);
  Int(texture.height);
  Int(texture.repeat_u ? 1 : 0);
  Raw(texture.texels.data(), texture.texels.size() * sizeof(glm::vec3));
}

void TableBytesWriter::Texture(const shared::Texture3D& texture) {
  Int(texture.width);
  Int(texture.height);
  Int(texture.depth);
  Raw(texture.texels.data(), texture.texels.size() * sizeof(glm::vec3));
}

bool TableBytesReader::Raw(void* data, std::size_t size) {
  if (!ok_ || bytes_.size() - position_ < size) return ok_ = false;
  std::memcpy(data, bytes_.data() + position_, size);
  position_ += size;
  return true;
}

bool TableBytesReader::Int(std::int64_t& value) { return Raw(&value, sizeof value); }

bool TableBytesReader::Texture(shared::Texture2D& texture) {
  std::int64_t w = 0, h = 0, repeat = 0;
  if (!Int(w) || !Int(h) || !Int(repeat)) return false;
  // Sizes bounded by what is left to read (a texel is 12 bytes), so that nothing is allocated for
  // a corrupt size.
  const std::size_t left = (bytes_.size() - position_) / sizeof(glm::vec3);
  if (w < 0 || h < 0 || w > 1 << 24 || h > 1 << 24 || static_cast<std::size_t>(w) * h > left) return ok_ = false;
  texture = shared::Texture2D(static_cast<int>(w), static_cast<int>(h), repeat != 0);
  return Raw(texture.texels.data(), texture.texels.size() * sizeof(glm::vec3));
}

bool TableBytesReader::Texture(shared::Texture3D& texture) {
  std::int64_t w = 0, h = 0, d = 0;
  if (!Int(w) || !Int(h) || !Int(d)) return false;
  const std::size_t left = (bytes_.size() - position_) / sizeof(glm::vec3);
  if (w < 0 || h < 0 || d < 0 || w > 1 << 24 || h > 1 << 24 || d > 1 << 24 ||
      static_cast<double>(w) * h * d > static_cast<double>(left)) {
    return ok_ = false;
  }
  texture = shared::Texture3D(static_cast<int>(w), static_cast<int>(h), static_cast<int>(d));
  return Raw(texture.texels.data(), texture.texels.size() * sizeof(glm::vec3));
}

}  // namespace io
}  // namespace atmo
