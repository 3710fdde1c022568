// What the exported table files of every model share (private): the manifest's integers, the
// version rule, the folder lock that publishes a set as one, and little-endian float data.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "atmo/hillaire_tables.h"
#include "atmo/image.h"
#include "shared/glsl_cpp.h"

namespace atmo::io {

using Json = nlohmann::ordered_json;

// The 16 lower-case hex digits of a 64-bit value.
std::string Hex64(std::uint64_t value);

// An integer of the manifest in [lo, hi]. JSON numbers with a fraction or exponent are refused
// rather than converted: get<int>() loaded format_version 1.5 as 1, and converting 1e30 to an
// integer is undefined behaviour (it printed -2147483648, and raw_bytes 1e30 read as 32768).
std::uint64_t ManifestInteger(const Json& j, const char* key, std::uint64_t lo, std::uint64_t hi,
                              const std::string& where);

// The version rule of every table manifest: `format_version` other than this program's
// `format_version` is refused (atmo::Error, one line: "<where>format version N; this atmo reads
// format version M: precompute it again"); the same format version written by another atmo
// version loads, with one warning line on stderr ("atmo: warning: <where>written by atmo X, this
// is atmo Y; format version N matches, loading it"). `where` ends with ": ".
void CheckTableVersions(const Json& manifest, int format_version, const std::string& where);

// Prints "atmo: warning: <message>" as one line on stderr.
void PrintWarning(const std::string& message);

// An advisory lock (flock) on the folder of a table's files, for as long as it lives: exclusive
// while an export publishes its set, shared while a load reads it, so that a reader never sees
// the files of two exports mixed and two exports publish one after the other. A folder that
// cannot be opened is not locked (the operation then fails on its own files).
class FolderLock {
 public:
  FolderLock(const std::filesystem::path& file, bool exclusive);
  ~FolderLock();
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  int fd_ = -1;
};

// Little-endian float32 bytes of `values`, and back (bytes.size() a multiple of 4).
std::vector<unsigned char> FloatBytesLittleEndian(std::span<const float> values);
std::vector<float> FloatsFromLittleEndian(std::span<const unsigned char> bytes);

// Stages `table` into `set` as an EXR, a W x (H D batches) float RGB image with texel (x, y, z) of
// batch b at pixel (x, y + H (z + D b)) (the raw order, so rows are raw rows), and as the raw
// file: little-endian float32 RGB, texel (x, y, z) of batch b at float index
// 3 (x + W (y + H (z + D b))). Returns the manifest's fields for the table: "exr" and "raw" (the
// file names, without folder), width, height, depth, channels (3), batches, raw_bytes and
// raw_hash_fnv1a64.
Json StageTable(AtomicFileSet& set, const ExportedTable& table, const std::filesystem::path& exr,
                const std::filesystem::path& raw, const ImageMetadata& metadata);

// One batch per texture (all of one size), into a table of depth 1 (texel (x, y) of batch b at
// 3 (x + W (y + H b))).
ExportedTable TableFromTextures(const std::string& name, std::span<const shared::Texture2D* const> batches);

// The manifest's description of the 2D transmittance table of Bruneton 2017 (hillaire's and
// elek's): meaning, units, the mapping (r, mu) -> (u, v) and its inverse, the sampler.
Json TransmittanceTableDescription();

// Reads the raw file of a manifest entry written by StageTable (its name relative to `folder`),
// checking the sizes (each side in [1, 16384], at most `max_bytes` of data), its length and its
// hash. Throws atmo::Error starting with `where`.
ExportedTable ReadTable(const Json& entry, const std::string& name, const std::filesystem::path& folder,
                        const std::string& where, std::uintmax_t max_bytes);

}  // namespace atmo::io
