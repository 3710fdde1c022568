#include "io/elek_table_file.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>

#include <nlohmann/json.hpp>

#include "atmo/elek.h"
#include "atmo/error.h"
#include "atmo/image.h"
#include "models/elek_model.h"

namespace atmo {
namespace {

using Json = nlohmann::ordered_json;

std::string Hex64(std::uint64_t value) {
  char text[17];
  std::snprintf(text, sizeof(text), "%016llx", static_cast<unsigned long long>(value));
  return text;
}

// Little-endian float32 bytes of the RGBA tables of every batch, one after another.
std::vector<unsigned char> RawBytes(const ElekModel& model) {
  std::vector<unsigned char> bytes;
  for (std::size_t b = 0; b < model.batches().size(); ++b) {
    for (float f : model.Rgba(b)) {
      std::uint32_t u;
      std::memcpy(&u, &f, 4);
      for (int k = 0; k < 4; ++k) bytes.push_back(static_cast<unsigned char>(u >> (8 * k)));
    }
  }
  return bytes;
}

std::string MappingName(const ElekModel& model) {
  return model.settings().mapping == shared::kElekMappingLinear ? "linear" : "nonlinear";
}

Json Manifest(const ElekModel& model, const std::vector<unsigned char>& raw) {
  const AtmosphereParameters& p = model.parameters();
  const glm::ivec3 s = model.settings().size;
  Json options = Json::object();
  for (const auto& [key, value] : model.settings().TableOptions()) options[key] = value;
  Json mie_wavelengths = Json::array();
  for (std::size_t c = 0; c < p.channel_count(); c += 3) mie_wavelengths.push_back(p.wavelengths_nm[c]);
  const bool linear = model.settings().mapping == shared::kElekMappingLinear;
  Json j;
  j["format"] = "atmo-elek-table";
  j["format_version"] = kElekTableFormatVersion;
  j["atmo_version"] = ATMO_VERSION;
  j["model"] = "elek";
  j["parameterisation"] = MappingName(model);
  j["mapping"] = linear ? Json{{"u", "h / H_a"}, {"v", "(cos(phi) + 1) / 2"}, {"w", "(cos(delta) + 1) / 2"}}
                        : Json{{"u", "sqrt(h / H_a)"},
                               {"v", "0.5 (1 + sign(cos(phi)) |cos(phi)|^(1/3))"},
                               {"w", "0.5 (1 + sign(cos(delta)) |cos(delta)|^(1/3))"}};
  j["texel_coordinates"] = "(u, v, w) = (x / (W - 1), y / (H - 1), z / (D - 1))";
  j["size"] = {{"width", s.x}, {"height", s.y}, {"depth", s.z}};
  j["batches"] = model.batches().size();
  j["raw_layout"] = "little-endian float32 RGBA, texel (x, y, z) of batch b at float index "
                    "4 (x + y W + z W H + b W H D)";
  j["exr_layout"] = "W x (H D batches) float image R, G, B, A; texel (x, y, z) of batch b at pixel (x, y + H (z + D b))";
  j["channels"] = {{"R", "factored Rayleigh scattering, channel 3b"},
                   {"G", "factored Rayleigh scattering, channel 3b + 1"},
                   {"B", "factored Rayleigh scattering, channel 3b + 2"},
                   {"A", "factored Mie scattering of channel 3b"}};
  j["wavelengths_nm"] = p.wavelengths_nm;
  j["mie_wavelengths_nm"] = mie_wavelengths;
  j["units"] = "factored radiance per unit solar irradiance (unitless): radiance (sr^-1) = p(nu) * value, "
               "phase functions normalised to 1; the Mie of other channels by Bruneton 2008's ratio";
  j["altitude_range_m"] = {0.0, p.top_radius_m - p.ground_radius_m};
  j["options"] = options;
  j["parameter_hash"] = ParameterHashHex(p);
  j["parameters"] = Json::parse(ToJson(p));
  j["raw_bytes"] = raw.size();
  j["raw_hash_fnv1a64"] = Hex64(Fnv1a64(raw));
  return j;
}

// A regular file of at most max_bytes (a device or FIFO is refused, /dev/zero does not exhaust memory).
std::string ReadFile(const std::filesystem::path& path, const char* what,
                     std::uintmax_t max_bytes = kMaxInputFileBytes) {
  return ReadFileBounded(path, "elek table " + std::string(what) + " ", max_bytes);
}

// An integer of the manifest in [lo, hi]. JSON numbers with a fraction or exponent are refused
// rather than converted: get<int>() loaded format_version 1.5 as 1, and converting 1e30 to an
// integer is undefined behaviour (it printed -2147483648, and raw_bytes 1e30 read as 32768).
std::uint64_t ManifestInteger(const Json& j, const char* key, std::uint64_t lo, std::uint64_t hi,
                              const std::string& where) {
  const Json& value = j.at(key);
  const std::string range = " in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  if (!value.is_number_integer()) throw Error(where + key + " must be an integer" + range + " (got " + value.dump() + ")");
  if (value.is_number_unsigned()) {
    const std::uint64_t u = value.get<std::uint64_t>();
    if (u >= lo && u <= hi) return u;
  }
  throw Error(where + key + " must be an integer" + range + " (got " + value.dump() + ")");
}

}  // namespace

std::uint64_t Fnv1a64(std::span<const unsigned char> bytes) {
  std::uint64_t hash = 14695981039346656037ull;
  for (unsigned char b : bytes) {
    hash ^= b;
    hash *= 1099511628211ull;
  }
  return hash;
}

// An advisory lock (flock) on the folder of a table's files, for as long as it lives: exclusive
// while an export publishes its set, shared while a load reads it, so that a reader never sees
// the files of two exports mixed and two exports publish one after the other. A folder that
// cannot be opened is not locked (the operation then fails on its own files).
namespace {

class FolderLock {
 public:
  FolderLock(const std::filesystem::path& file, bool exclusive) {
    const std::filesystem::path dir = file.has_parent_path() ? file.parent_path() : std::filesystem::path(".");
    fd_ = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd_ >= 0) {
      while (::flock(fd_, exclusive ? LOCK_EX : LOCK_SH) != 0 && errno == EINTR) {
      }
    }
  }
  ~FolderLock() {
    if (fd_ >= 0) ::close(fd_);  // closing releases the lock
  }
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  int fd_ = -1;
};

}  // namespace

ElekTableFiles ElekTableFilesFor(const std::filesystem::path& name) {
  const std::string base = name.string();
  return {base + ".exr", base + ".raw", base + ".json"};
}

ElekTableFiles ExportElekTable(const Model& model, const std::filesystem::path& name) {
  const auto* elek = dynamic_cast<const ElekModel*>(&model);
  if (elek == nullptr) {
    throw Error("precompute exports the table of model elek, not of model " + std::string(model.name()));
  }
  if (!elek->settings().table.empty()) throw Error("this elek model was loaded from a table; export the original");
  const ElekTableFiles files = ElekTableFilesFor(name);
  const std::vector<unsigned char> raw = RawBytes(*elek);
  const glm::ivec3 s = elek->settings().size;
  const std::size_t batches = elek->batches().size();

  // One set: every file written completely first, then published in one locked commit with the
  // manifest last; a failure before that changes no file.
  AtomicFileSet set;
  set.Stage(files.raw, [&](const std::filesystem::path& temporary) {
    std::ofstream out(temporary, std::ios::binary);
    out.write(reinterpret_cast<const char*>(raw.data()), static_cast<std::streamsize>(raw.size()));
    if (!out) throw Error("write failed");
  });

  Image image(s.x, s.y * s.z * static_cast<int>(batches), 3);
  image.alpha.resize(static_cast<std::size_t>(image.width) * image.height);
  for (std::size_t b = 0; b < batches; ++b) {
    const std::vector<float> rgba = elek->Rgba(b);
    const std::size_t offset = b * static_cast<std::size_t>(s.x) * s.y * s.z;
    for (std::size_t i = 0; i < rgba.size() / 4; ++i) {
      // Pixel index x + row W with row = y + H z + H D b: the texel index plus the batch offset.
      const std::size_t pixel = offset + i;
      for (int c = 0; c < 3; ++c) image.pixels[3 * pixel + c] = rgba[4 * i + c];
      image.alpha[pixel] = rgba[4 * i + 3];
    }
  }
  WriteExr(files.exr, image,
           {{"atmo:version", ATMO_VERSION},
            {"atmo:model", "elek"},
            {"atmo:parameterHash", ParameterHashHex(elek->parameters())},
            {"atmo:elekSize", std::to_string(s.x) + "x" + std::to_string(s.y) + "x" + std::to_string(s.z)},
            {"atmo:elekParameterisation", MappingName(*elek)},
            {"atmo:elekLayout", "slice z of batch b = rows [H (z + D b), H (z + D b + 1)); A = Mie of channel 3b"}},
           &set);

  const std::string manifest = Manifest(*elek, raw).dump(2) + "\n";
  set.Stage(files.json, [&](const std::filesystem::path& temporary) {
    std::ofstream out(temporary, std::ios::binary);
    out << manifest;
    if (!out) throw Error("write failed");
  });
  const FolderLock lock(files.json, /*exclusive=*/true);
  set.Commit();
  return files;
}

void LoadElekTable(const std::string& name, ElekModel& model) {
  const ElekTableFiles files = ElekTableFilesFor(name);
  const FolderLock lock(files.json, /*exclusive=*/false);  // no export publishes while we read
  const std::string where = "elek table '" + files.json.string() + "': ";
  Json j;
  try {
    j = Json::parse(ReadFile(files.json, "manifest"));
  } catch (const Json::exception& e) {
    throw Error(where + "malformed JSON (" + std::string(e.what()) + ")");
  }
  try {
    if (j.value("format", std::string()) != "atmo-elek-table") throw Error(where + "not an elek table manifest");
    const std::uint64_t version = ManifestInteger(j, "format_version", 0, 1u << 30, where);
    if (version != static_cast<std::uint64_t>(kElekTableFormatVersion)) {
      throw Error(where + "format version " + std::to_string(version) + " does not match this program's " +
                  std::to_string(kElekTableFormatVersion));
    }
    const std::string atmo_version = j.at("atmo_version").get<std::string>();
    if (atmo_version != ATMO_VERSION) {
      throw Error(where + "written by atmo " + atmo_version + ", this is atmo " + ATMO_VERSION + "; precompute it again");
    }
    const std::string hash = j.at("parameter_hash").get<std::string>();
    if (hash != ParameterHashHex(model.parameters())) {
      throw Error(where + "parameter hash " + hash + " does not match the parameters' " +
                  ParameterHashHex(model.parameters()) + " (preset '" + model.parameters().name + "')");
    }
    const Json& options = j.at("options");
    for (const auto& [key, value] : model.settings().TableOptions()) {
      const std::string stored = options.value(key, std::string("(missing)"));
      if (stored != value) {
        throw Error(where + key + " " + stored + " does not match the model's " + value + " (pass --option " + key +
                    "=" + stored + ")");
      }
    }
    if (ManifestInteger(j, "batches", 1, 1u << 20, where) != model.batches().size()) {
      throw Error(where + "channel batches differ");
    }
    const glm::ivec3 s = model.settings().size;
    const std::size_t texels = static_cast<std::size_t>(s.x) * s.y * s.z;
    const std::size_t expected = 16 * texels * model.batches().size();
    const std::uint64_t manifest_bytes = ManifestInteger(j, "raw_bytes", 0, std::uint64_t{1} << 50, where);
    if (manifest_bytes != expected) {
      throw Error(where + "raw_bytes " + std::to_string(manifest_bytes) + " does not match the " +
                  std::to_string(expected) + " bytes of this model's table");
    }
    const std::string raw = ReadFile(files.raw, "data", expected);
    if (raw.size() != expected) {
      throw Error("elek table '" + files.raw.string() + "': " + std::to_string(raw.size()) + " bytes, expected " +
                  std::to_string(expected));
    }
    const auto* bytes = reinterpret_cast<const unsigned char*>(raw.data());
    const std::string data_hash = Hex64(Fnv1a64({bytes, raw.size()}));
    if (data_hash != j.at("raw_hash_fnv1a64").get<std::string>()) {
      throw Error("elek table '" + files.raw.string() + "': data hash " + data_hash + " does not match the manifest's " +
                  j.at("raw_hash_fnv1a64").get<std::string>() + " (corrupt or modified)");
    }
    for (std::size_t b = 0; b < model.batches().size(); ++b) {
      std::vector<float> rgba(4 * texels);
      for (std::size_t i = 0; i < rgba.size(); ++i) {
        const unsigned char* p = bytes + 4 * (b * 4 * texels + i);
        const std::uint32_t u = std::uint32_t(p[0]) | std::uint32_t(p[1]) << 8 | std::uint32_t(p[2]) << 16 |
                                std::uint32_t(p[3]) << 24;
        std::memcpy(&rgba[i], &u, 4);
      }
      model.SetRgba(b, rgba);
    }
  } catch (const Json::exception& e) {
    throw Error(where + "missing or malformed key (" + std::string(e.what()) + ")");
  }
}

}  // namespace atmo
