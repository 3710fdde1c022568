#include "io/table_files.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include <fstream>

#include "atmo/error.h"
#include "printable.h"
#include "io/elek_table_file.h"

namespace atmo {

std::uint64_t Fnv1a64(std::span<const unsigned char> bytes) {
  std::uint64_t hash = 14695981039346656037ull;
  for (unsigned char b : bytes) {
    hash ^= b;
    hash *= 1099511628211ull;
  }
  return hash;
}

}  // namespace atmo

namespace atmo::io {

std::string Hex64(std::uint64_t value) {
  char text[17];
  std::snprintf(text, sizeof(text), "%016llx", static_cast<unsigned long long>(value));
  return text;
}

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

void PrintWarning(const std::string& message) { std::fprintf(stderr, "atmo: warning: %s\n", message.c_str()); }

void CheckTableVersions(const Json& manifest, int format_version, const std::string& where) {
  const std::uint64_t version = ManifestInteger(manifest, "format_version", 0, 1u << 30, where);
  if (version != static_cast<std::uint64_t>(format_version)) {
    throw Error(where + "format version " + std::to_string(version) + "; this atmo reads format version " +
                std::to_string(format_version) + ": precompute it again");
  }
  const std::string atmo_version = manifest.at("atmo_version").get<std::string>();
  if (atmo_version != ATMO_VERSION) {
    PrintWarning(where + "written by atmo " + Printable(atmo_version) + ", this is atmo " + ATMO_VERSION + "; format version " +
                 std::to_string(version) + " matches, loading it");
  }
}

FolderLock::FolderLock(const std::filesystem::path& file, bool exclusive) {
  const std::filesystem::path dir = file.has_parent_path() ? file.parent_path() : std::filesystem::path(".");
  fd_ = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd_ >= 0) {
    while (::flock(fd_, exclusive ? LOCK_EX : LOCK_SH) != 0 && errno == EINTR) {
    }
  }
}

FolderLock::~FolderLock() {
  if (fd_ >= 0) ::close(fd_);  // closing releases the lock
}

std::vector<unsigned char> FloatBytesLittleEndian(std::span<const float> values) {
  std::vector<unsigned char> bytes(4 * values.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    std::uint32_t u;
    std::memcpy(&u, &values[i], 4);
    for (int k = 0; k < 4; ++k) bytes[4 * i + k] = static_cast<unsigned char>(u >> (8 * k));
  }
  return bytes;
}

std::vector<float> FloatsFromLittleEndian(std::span<const unsigned char> bytes) {
  std::vector<float> values(bytes.size() / 4);
  for (std::size_t i = 0; i < values.size(); ++i) {
    const unsigned char* p = bytes.data() + 4 * i;
    const std::uint32_t u = std::uint32_t(p[0]) | std::uint32_t(p[1]) << 8 | std::uint32_t(p[2]) << 16 |
                            std::uint32_t(p[3]) << 24;
    std::memcpy(&values[i], &u, 4);
  }
  return values;
}

Json StageTable(AtomicFileSet& set, const ExportedTable& table, const std::filesystem::path& exr,
                const std::filesystem::path& raw, const ImageMetadata& metadata) {
  const std::size_t texels = table.texel_count();
  if (table.rgb.size() != 3 * texels * table.batches) {
    throw Error("table " + table.name + ": " + std::to_string(table.rgb.size()) + " values, expected " +
                std::to_string(3 * texels * table.batches));
  }
  const std::vector<unsigned char> bytes = FloatBytesLittleEndian(table.rgb);
  set.Stage(raw, [&](const std::filesystem::path& temporary) {
    std::ofstream out(temporary, std::ios::binary);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    if (!out) throw Error("write failed");
  });
  Image image(table.width, table.height * table.depth * static_cast<int>(table.batches), 3);
  image.pixels = table.rgb;  // pixel (x, row) at 3 (x + W row), row = y + H (z + D b): the raw order
  WriteExr(exr, image, metadata, &set);
  Json j;
  j["exr"] = exr.filename().string();
  j["raw"] = raw.filename().string();
  j["width"] = table.width;
  j["height"] = table.height;
  j["depth"] = table.depth;
  j["channels"] = 3;
  j["batches"] = table.batches;
  j["raw_bytes"] = bytes.size();
  j["raw_hash_fnv1a64"] = Hex64(Fnv1a64(bytes));
  return j;
}

ExportedTable TableFromTextures(const std::string& name, std::span<const shared::Texture2D* const> batches) {
  ExportedTable table;
  table.name = name;
  table.width = batches.front()->width;
  table.height = batches.front()->height;
  table.batches = batches.size();
  table.rgb.reserve(3 * table.texel_count() * table.batches);
  for (const shared::Texture2D* texture : batches) {
    if (texture->width != table.width || texture->height != table.height) {
      throw Error("table " + name + ": the batches differ in size");
    }
    for (const glm::vec3& texel : texture->texels) {
      for (int k = 0; k < 3; ++k) table.rgb.push_back(texel[k]);
    }
  }
  return table;
}

Json TransmittanceTableDescription() {
  Json j;
  j["meaning"] = "T(r, mu): transmittance from radius r along the direction of zenith cosine mu to the top of the "
                 "atmosphere, for the rays that do not meet the ground (Bruneton 2017, section 2.3)";
  j["units"] = "unitless, per channel";
  j["parameters"] = "r: distance from the planet centre (km), in [R_b, R_t]; mu: cosine of the view zenith angle";
  j["mapping"] =
      "u = (0.5 + x_mu (W - 1)) / W, v = (0.5 + x_r (H - 1)) / H, with H_t = sqrt(R_t^2 - R_b^2), "
      "rho = sqrt(r^2 - R_b^2), d = -r mu + sqrt(r^2 (mu^2 - 1) + R_t^2) (the distance to the top), "
      "d_min = R_t - r, d_max = rho + H_t, x_mu = (d - d_min) / (d_max - d_min), x_r = rho / H_t";
  j["inverse"] =
      "x_mu = (u W - 0.5) / (W - 1), x_r = (v H - 0.5) / (H - 1), rho = H_t x_r, r = sqrt(rho^2 + R_b^2), "
      "d_min = R_t - r, d_max = rho + H_t, d = d_min + x_mu (d_max - d_min), "
      "mu = (H_t^2 - rho^2 - d^2) / (2 r d) (mu = 1 where d = 0), clamped to [-1, 1]";
  j["ground_rays"] = "a ray that meets the ground (mu < 0 and r^2 (mu^2 - 1) + R_b^2 >= 0) has no entry; its "
                     "transmittance to the top is 0, and between two points of it the ratio of the mirrored "
                     "rays (mu -> -mu) is used (atmoTransmittanceAlong)";
  j["glsl"] = {{"lookup", "atmoTransmittance(atmosphere, table, r, mu)"},
               {"uv", "atmo_GetTransmittanceTextureUvFromRMu(atmosphere, textureSize(table, 0), r, mu)"},
               {"inverse", "atmo_GetRMuFromTransmittanceTextureUv(atmosphere, textureSize(table, 0), uv, r, mu)"}};
  j["sampler"] = "GL_LINEAR, GL_CLAMP_TO_EDGE on both axes";
  return j;
}

ExportedTable ReadTable(const Json& entry, const std::string& name, const std::filesystem::path& folder,
                        const std::string& where, std::uintmax_t max_bytes) {
  const std::string at = where + name + ": ";
  ExportedTable table;
  table.name = name;
  table.width = static_cast<int>(ManifestInteger(entry, "width", 1, 16384, at));
  table.height = static_cast<int>(ManifestInteger(entry, "height", 1, 16384, at));
  table.depth = static_cast<int>(ManifestInteger(entry, "depth", 1, 16384, at));
  table.batches = ManifestInteger(entry, "batches", 1, 1u << 20, at);
  if (ManifestInteger(entry, "channels", 3, 3, at) != 3) throw Error(at + "channels must be 3");
  const std::uint64_t expected = 12ull * table.texel_count() * table.batches;
  if (expected > max_bytes) throw Error(at + "a table of " + std::to_string(expected) + " bytes is too large");
  if (ManifestInteger(entry, "raw_bytes", 0, std::uint64_t{1} << 50, at) != expected) {
    throw Error(at + "raw_bytes does not match its sizes (" + std::to_string(expected) + " bytes)");
  }
  const std::string file = entry.at("raw").get<std::string>();
  if (file.empty() || std::filesystem::path(file).filename().string() != file) {
    throw Error(at + "raw must be a file name beside the manifest (got '" + Printable(file) + "')");
  }
  const std::filesystem::path path = folder / file;
  const std::string data = ReadFileBounded(path, "table data ", expected);
  if (data.size() != expected) {
    throw Error("table '" + Printable(path.string()) + "': " + std::to_string(data.size()) + " bytes, expected " +
                std::to_string(expected));
  }
  const std::span<const unsigned char> bytes(reinterpret_cast<const unsigned char*>(data.data()), data.size());
  const std::string hash = Hex64(Fnv1a64(bytes));
  if (hash != entry.at("raw_hash_fnv1a64").get<std::string>()) {
    throw Error("table '" + Printable(path.string()) + "': data hash " + hash + " does not match the manifest's " +
                Printable(entry.at("raw_hash_fnv1a64").get<std::string>()) + " (corrupt or modified)");
  }
  table.rgb = FloatsFromLittleEndian(bytes);
  return table;
}

}  // namespace atmo::io
