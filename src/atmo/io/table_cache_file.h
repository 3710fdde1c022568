// The table cache's files (include/atmo/table_cache.h), private to the library: one file per key,
// and the little byte format models write their tables in.
//
// A file: the 8 bytes "ATMOTBL1", the 32-bit marker 0x01020304 in the writer's byte order (a
// file of another byte order is ignored), the key's length (64 bits) and bytes, the payload's
// length and bytes, and a 64-bit checksum of the key and payload together (FNV-1a's step over
// 64-bit words, the last word zero-padded). Its name is two FNV-1a
// hashes of the key (two bases) in hex, ".atmotables".
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "atmo/parameters.h"
#include "atmo/table_cache.h"
#include "shared/glsl_cpp.h"

namespace atmo::io {

// The key of a model's tables: what they depend on. The model's name and options (sorted, as in
// the map), the atmosphere's canonical JSON without its name (a preset and its dump are one
// atmosphere) and without what only scales or frames images (the solar irradiance, the exposure,
// the observer's altitude), and BuildId() (the code that computes the tables).
std::string TableCacheKey(std::string_view model, const std::map<std::string, std::string>& options,
                          const AtmosphereParameters& parameters);

// A file read whole, and its payload within it.
struct CachedTables {
  std::unique_ptr<unsigned char[]> file;
  std::span<const unsigned char> payload;
};

// The payload kept under `key` in cache.folder, else in a shipped folder, or std::nullopt (no
// file, another key, a corrupt or unreadable file). A hit in cache.folder marks the file as
// recently used.
std::optional<CachedTables> ReadCachedTables(const TableCache& cache, const std::string& key);

// Keeps `payload` under `key` in cache.folder (written whole, then renamed; nothing when the
// folder is empty), then removes the least recently used files while the folder holds more than
// cache.max_bytes. Never throws: returns "" or the reason the file could not be written.
std::string WriteCachedTables(const TableCache& cache, const std::string& key,
                              std::span<const unsigned char> payload);

// The file of `folder` that holds `key`.
std::filesystem::path CachedTablesPath(const std::filesystem::path& folder, const std::string& key);

// Appends integers and textures to a payload, in this machine's byte order (the file's marker
// rejects another).
class TableBytesWriter {
 public:
  void Int(std::int64_t value);
  void Texture(const shared::Texture2D& texture);
  void Texture(const shared::Texture3D& texture);
  std::vector<unsigned char>& bytes() { return bytes_; }

 private:
  void Raw(const void* data, std::size_t size);
  std::vector<unsigned char> bytes_;
};

// Reads what TableBytesWriter wrote; every read returns false, and reads nothing more, once the
// payload is shorter than asked or a size is out of range.
class TableBytesReader {
 public:
  explicit TableBytesReader(std::span<const unsigned char> bytes) : bytes_(bytes) {}
  bool Int(std::int64_t& value);
  bool Texture(shared::Texture2D& texture);
  bool Texture(shared::Texture3D& texture);
  // True when every byte was read and no read failed.
  bool Finished() const { return ok_ && position_ == bytes_.size(); }

 private:
  bool Raw(void* data, std::size_t size);
  std::span<const unsigned char> bytes_;
  std::size_t position_ = 0;
  bool ok_ = true;
};

}  // namespace atmo::io
