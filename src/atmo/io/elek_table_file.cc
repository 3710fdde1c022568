#include "io/elek_table_file.h"

#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>

#include <nlohmann/json.hpp>

#include "atmo/elek.h"
#include "atmo/error.h"
#include "printable.h"
#include "atmo/image.h"
#include "io/table_files.h"
#include "models/elek_model.h"

namespace atmo {
namespace {

using io::Hex64;
using io::Json;
using io::ManifestInteger;

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

}  // namespace

using io::FolderLock;

ElekTableFiles ElekTableFilesFor(const std::filesystem::path& name) {
  const std::string base = name.string();
  return {base + ".exr", base + ".raw", base + ".json", base + "_transmittance.exr", base + "_transmittance.raw"};
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

  // The sun-transmittance table (the 2D table of hillaire's export), one band per batch.
  std::vector<const shared::Texture2D*> transmittance;
  for (const auto& batch : elek->batches()) transmittance.push_back(&batch.transmittance);
  Json transmittance_entry =
      io::StageTable(set, io::TableFromTextures("transmittance", transmittance), files.transmittance_exr,
                     files.transmittance_raw,
                     {{"atmo:version", ATMO_VERSION},
                      {"atmo:model", "elek"},
                      {"atmo:table", "transmittance"},
                      {"atmo:parameterHash", ParameterHashHex(elek->parameters())}});
  transmittance_entry.update(io::TransmittanceTableDescription());
  transmittance_entry["geometry_km"] = {{"bottom_radius", elek->parameters().ground_radius_m / 1000.0},
                                        {"top_radius", elek->parameters().top_radius_m / 1000.0}};

  Json manifest_json = Manifest(*elek, raw);
  manifest_json["transmittance"] = transmittance_entry;
  const std::string manifest = manifest_json.dump(2) + "\n";
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
    io::CheckTableVersions(j, kElekTableFormatVersion, where);
    const std::string hash = j.at("parameter_hash").get<std::string>();
    if (hash != ParameterHashHex(model.parameters())) {
      throw Error(where + "parameter hash " + Printable(hash) + " does not match the parameters' " +
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
                  Printable(j.at("raw_hash_fnv1a64").get<std::string>()) + " (corrupt or modified)");
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
