// The exported hillaire tables (include/atmo/hillaire_tables.h, docs/tables.md): their CPU
// computation, the manifest, the files and reading them back.
#include "io/hillaire_table_file.h"

#include <cmath>
#include <cstdio>
#include <fstream>

#include "atmo/error.h"
#include "atmo/image.h"
#include "cpu/camera.h"
#include "io/table_files.h"
#include "physics/shared_parameters.h"
#include "printable.h"
#include "shared/shared.h"

namespace atmo {
namespace {

using io::Json;

constexpr const char* kFormat = "atmo-hillaire-tables";

std::size_t TableIndex(std::string_view name) {
  for (std::size_t i = 0; i < std::size(kHillaireTableNames); ++i) {
    if (kHillaireTableNames[i] == name) return i;
  }
  throw Error("no hillaire table named '" + std::string(name) + "'");
}

std::string Size(glm::ivec2 s) { return std::to_string(s.x) + "x" + std::to_string(s.y); }

// The observer radius (m) and the unit sun direction of a view.
double ObserverRadius(const AtmosphereParameters& p, const HillaireExportView& view) {
  return p.ground_radius_m + view.altitude_m;
}

Json Vec3(const glm::dvec3& v) { return Json::array({v.x, v.y, v.z}); }

// What each table holds, its mapping both ways and its sampler (docs/tables.md).
Json Description(std::string_view name) {
  Json j;
  if (name == "transmittance") return io::TransmittanceTableDescription();
  if (name == "multiple_scattering") {
    j["meaning"] = "Psi_ms(r, mu_s): the radiance that scattering orders >= 2 send in any direction, per unit "
                   "scattering coefficient (Hillaire 2020, section 5.5.2); the source term of those orders at a "
                   "point is Psi_ms times the scattering coefficient there";
    j["units"] = "sr^-1 per unit solar irradiance at the top of the atmosphere (times a scattering coefficient per "
                 "km: sr^-1 km^-1)";
    j["encoding"] = "each texel holds ln(max(Psi_ms, 1e-30)) per channel: filter bilinearly, then Psi_ms = exp(value), "
                    "0 below 2e-30 (atmoMultipleScattering does both)";
    j["parameters"] = "r: distance from the planet centre (km); mu_s: cosine of the sun zenith angle at r";
    j["mapping"] = "u = (0.5 + x (W - 1)) / W, v = (0.5 + y (H - 1)) / H, with "
                   "x = clamp((1 + sign(mu_s) sqrt(|mu_s|)) / 2, 0, 1), y = clamp((r - R_b) / (R_t - R_b), 0, 1)";
    j["inverse"] = "a = 2 clamp((u W - 0.5) / (W - 1), 0, 1) - 1, mu_s = sign(a) a^2, "
                   "r = R_b + clamp((v H - 0.5) / (H - 1), 0, 1) (R_t - R_b)";
    j["glsl"] = {{"lookup", "atmoMultipleScattering(atmosphere, table, r, mu_s)"},
                 {"uv", "atmo_GetMultiScatteringTextureUvFromRMuS(atmosphere, textureSize(table, 0), r, mu_s)"},
                 {"inverse", "atmo_GetRMuSFromMultiScatteringTextureUv(atmosphere, textureSize(table, 0), uv, r, "
                             "mu_s)"}};
    j["sampler"] = "GL_LINEAR, GL_CLAMP_TO_EDGE on both axes";
    return j;
  }
  if (name == "sky_view" || name == "sky_view_ground") {
    j["meaning"] = name == "sky_view"
                       ? "the sky radiance seen by the observer of \"view\" in every direction (Hillaire 2020, "
                         "section 5.3): single scattering ray marched plus Psi_ms, without the sun disc and "
                         "without light reflected by the ground (atmo sample's radiance)"
                       : "sky_view plus the light of the lit Lambertian ground below the horizon, attenuated on its "
                         "way: what the images of atmo render show (without the sun disc)";
    j["units"] = "sr^-1 per unit solar irradiance at the top of the atmosphere; times solar_irradiance: the values "
                 "of `atmo render --unit relative`";
    j["parameters"] = "view direction in the observer's local frame (x east, y north, z up): mu = its z (cosine "
                      "of the zenith angle theta), azimuth = atan2(v_x s_y - v_y s_x, v_x s_x + v_y s_y) in "
                      "[0, 2 pi), its azimuth from the sun's (s: the sun direction); r = view.r_km";
    j["mapping"] = "u = azimuth / (2 pi) + 0.5 / W (repeats); with beta = max(acos(sqrt(r^2 - R_b^2) / r), 1e-9) "
                   "(the horizon's dip below the horizontal, seen from r), theta_h = pi - beta, h = H / 2: "
                   "theta <= theta_h (sky): v = 0.5 (0.5 + y (h - 1)) / h, y = 1 - sqrt(1 - theta / theta_h); "
                   "theta > theta_h (ground): v = 0.5 + 0.5 (0.5 + y (h - 1)) / h, "
                   "y = sqrt(min((theta - theta_h) / beta, 1))";
    j["inverse"] = "azimuth = (u - 0.5 / W) 2 pi; v < 0.5: y = clamp((2 v h - 0.5) / (h - 1), 0, 1), "
                   "theta = theta_h (1 - (1 - y)^2); v >= 0.5: y = clamp(((2 v - 1) h - 0.5) / (h - 1), 0, 1), "
                   "theta = theta_h + beta y^2; mu = cos(theta)";
    j["rows"] = "rows [0, H/2) hold the sky half, rows [H/2, H) the rays that meet the ground; the horizon lies "
                "between rows H/2 - 1 and H/2, so bilinear filtering never mixes the two";
    j["glsl"] = {{"lookup", "atmoSkyView(atmosphere, table, r, view_direction, sun_direction)"},
                 {"uv", "atmo_GetSkyViewTextureUvFromViewAngles(atmosphere, textureSize(table, 0), r, mu, azimuth)"},
                 {"inverse", "atmo_GetViewAnglesFromSkyViewTextureUv(atmosphere, textureSize(table, 0), r, uv, mu, "
                             "azimuth)"}};
    j["sampler"] = "GL_LINEAR, GL_REPEAT in u (s), GL_CLAMP_TO_EDGE in v (t)";
    return j;
  }
  const bool radiance = name == "aerial_radiance";
  j["meaning"] = radiance ? "aerial perspective (Hillaire 2020, section 5.4): the radiance scattered into the "
                            "camera ray between the camera and each froxel's distance, ray marched"
                          : "aerial perspective: the transmittance between the camera and each froxel's distance";
  j["units"] = radiance ? "sr^-1 per unit solar irradiance at the top of the atmosphere (times solar_irradiance: "
                          "relative units)"
                        : "unitless, per channel";
  j["parameters"] = "screen point (s_x, s_y) in [0, 1]^2 of the camera of \"aerial_camera\" (s_y = 0 at the "
                    "image's top row: pixel (x, y) of a W_i x H_i image is at ((x + 0.5) / W_i, (y + 0.5) / H_i)); "
                    "distance from the camera (km)";
  j["mapping"] = "u = s_x, v = s_y (froxel (x, y) centred on ((x + 0.5) / W, (y + 0.5) / H)); with "
                 "s = clamp(distance / max_distance D - 1, -1, D - 1): w = (max(s, 0) + 0.5) / D; froxel z holds "
                 "the distance (z + 1) / D max_distance; for s < 0 (before the first slice) the value is "
                 "mixed with the camera's own (radiance 0, transmittance 1) by weight clamp(s + 1, 0, 1)";
  j["inverse"] = "s_x = u, s_y = v, distance = (w D + 0.5) / D max_distance";
  j["glsl"] = {{"lookup", "atmoAerialPerspective(aerial_radiance, aerial_transmittance, screen_uv, distance, "
                          "max_distance, radiance, transmittance)"},
               {"uvw", "atmo_GetAerialPerspectiveTextureUvwFromScreenDistance(textureSize(table, 0), screen_uv, "
                       "distance, max_distance)"},
               {"inverse", "atmo_GetScreenDistanceFromAerialPerspectiveTextureUvw(textureSize(table, 0), uvw, "
                           "max_distance, screen_uv, distance)"}};
  j["compositing"] = "a surface of radiance L at that distance is seen as L transmittance + radiance";
  j["sampler"] = "GL_LINEAR, GL_CLAMP_TO_EDGE on all three axes";
  return j;
}

Json Manifest(const HillaireTables& tables, const std::vector<Json>& entries) {
  const AtmosphereParameters& p = tables.parameters;
  const HillaireExportView& view = tables.view;
  const double r_m = ObserverRadius(p, view);
  const glm::dvec3 sun = glm::normalize(SunDirection(view.sun_elevation_deg, view.sun_azimuth_deg));
  const shared::AtmosphereParameters metres = ToSharedParameters(p, 0);
  Json options = Json::object();
  for (const auto& [key, value] : tables.options) options[key] = value;
  Json j;
  j["format"] = kFormat;
  j["format_version"] = kHillaireTablesFormatVersion;
  j["atmo_version"] = ATMO_VERSION;
  j["model"] = "hillaire";
  j["backend"] = tables.backend;
  j["parameter_hash"] = ParameterHashHex(p);
  j["preset"] = p.name;
  j["options"] = options;
  j["channels"] = {
      {"count", p.channel_count()},
      {"wavelengths_nm", p.wavelengths_nm},
      {"batches", ChannelBatchCount(p.channel_count())},
      {"rule", "batch b holds channels 3b, 3b + 1, 3b + 2 in R, G, B; a last batch with fewer than three "
               "channels repeats its last one; the batches follow one another in every file"}};
  j["solar_irradiance"] = p.solar_irradiance;
  j["geometry_km"] = {{"bottom_radius", p.ground_radius_m / 1000.0}, {"top_radius", p.top_radius_m / 1000.0}};
  j["geometry_note"] = "R_b = bottom_radius, R_t = top_radius; every length of the mappings in km (the values "
                       "do not depend on the unit as long as r, the radii and the distances share it)";
  j["view"] = {{"altitude_m", view.altitude_m},
               {"r_km", r_m / 1000.0},
               {"sun_elevation_deg", view.sun_elevation_deg},
               {"sun_azimuth_deg", view.sun_azimuth_deg},
               {"sun_zenith_cosine", shared::ClampCosine(sun.z)},
               {"sun_direction", Vec3(sun)},
               {"horizon_nadir_angle_rad", shared::GetHorizonNadirAngle(metres, r_m)},
               {"frame", "local: x east, y north, z up; azimuths are compass azimuths (0 north, 90 east)"},
               {"tables", "sky_view, sky_view_ground, aerial_radiance and aerial_transmittance hold this observer "
                          "and sun; the sky views are stored relative to the sun's azimuth"}};
  const shared::CameraParameters camera = ToSharedCamera(view.camera);
  j["aerial_camera"] = {
      {"kind", view.camera.kind == CameraKind::kPerspective ? "perspective"
               : view.camera.kind == CameraKind::kFisheye   ? "fisheye"
                                                            : "equirect"},
      {"width", view.camera.width},
      {"height", view.camera.height},
      {"fov_deg", view.camera.fov_deg},
      {"yaw_deg", view.camera.yaw_deg},
      {"pitch_deg", view.camera.pitch_deg},
      {"forward", Vec3(camera.forward)},
      {"right", Vec3(camera.right)},
      {"up", Vec3(camera.up)},
      {"rays", "perspective: pixel (x, y) looks along normalize(forward + X right + Y up), "
               "X = (2 (x + 0.5) / W_i - 1) tan(fov / 2), Y = (1 - 2 (y + 0.5) / H_i) tan(fov / 2) H_i / W_i"},
      {"max_distance_km", view.aerial.max_distance_m / 1000.0}};
  j["raw_layout"] = "little-endian IEEE float32, 3 per texel (R, G, B interleaved), texel (x, y, z) of batch b at "
                    "float index 3 (x + W (y + H (z + D b))): row-major, x fastest, texel (0, 0, 0) first, no "
                    "header or padding";
  j["exr_layout"] = "one float32 RGB image of W x (H D batches) pixels, ZIP; pixel (x, y + H (z + D b)) holds texel "
                    "(x, y, z) of batch b (the raw order: image row 0 = table row 0)";
  j["texel_centres"] = "texel i of a side of n texels has its centre at (i + 0.5) / n in the sampler's coordinate "
                       "(OpenGL's convention); the mappings give that coordinate directly. The unit ranges of the "
                       "transmittance, multiple-scattering and sky-view mappings put their ends on the centres of "
                       "the first and last texels";
  Json table_entries = Json::object();
  for (std::size_t i = 0; i < entries.size(); ++i) {
    Json entry = entries[i];
    entry.update(Description(kHillaireTableNames[i]));
    table_entries[std::string(kHillaireTableNames[i])] = entry;
  }
  j["tables"] = table_entries;
  j["sun_disc"] = "not in the tables: `atmo render` adds a limb-darkened disc of angular radius "
                  "sun_angular_radius_rad and unit irradiance, attenuated by atmoTransmittance";
  j["sun_angular_radius_rad"] = p.sun_angular_radius_rad;
  j["parameters"] = Json::parse(ToJson(p));
  return j;
}

}  // namespace

const ExportedTable& HillaireTables::table(std::string_view name) const {
  const std::size_t i = TableIndex(name);
  if (i >= tables.size()) throw Error("hillaire tables: table '" + std::string(name) + "' is missing");
  return tables[i];
}

std::vector<std::pair<std::string, std::string>> HillaireTableOptions(const HillaireSettings& s) {
  const auto i = [](int v) { return std::to_string(v); };
  return {{"transmittance_lut", Size(s.transmittance_lut)},
          {"transmittance_samples", i(s.transmittance_samples)},
          {"multiple_scattering_lut", Size(s.multiple_scattering_lut)},
          {"multiple_scattering_directions", i(s.multiple_scattering_directions)},
          {"multiple_scattering_samples", i(s.multiple_scattering_samples)},
          {"multiple_scattering_phase", s.multiple_scattering_media_phase ? "media" : "isotropic"},
          {"multiple_scattering_ground", s.multiple_scattering_ground ? "on" : "off"},
          {"multiple_scattering_orders", i(s.multiple_scattering_orders)},
          {"multiple_scattering_gather_directions", i(s.multiple_scattering_gather_directions)},
          {"sky_view_lut", Size(s.sky_view_lut)},
          {"sky_view_samples", i(s.sky_view_samples)},
          {"ray_march_samples", i(s.ray_march_samples)},
          {"ground_irradiance_lut", i(s.ground_irradiance_lut)},
          {"ground_irradiance_directions", i(s.ground_irradiance_directions)},
          {"ground_irradiance_samples", i(s.ground_irradiance_samples)}};
}

void ValidateHillaireExportView(const AtmosphereParameters& p, const HillaireExportView& view) {
  const double top_m = p.top_radius_m - p.ground_radius_m;
  if (!std::isfinite(view.altitude_m) || view.altitude_m < 0.0 || view.altitude_m > top_m) {
    char text[160];
    std::snprintf(text, sizeof(text), "--altitude in [0, %.10g] m (got %.10g)", top_m, view.altitude_m);
    throw Error("the exported sky view needs an observer inside the atmosphere: " + std::string(text));
  }
  if (!std::isfinite(view.sun_elevation_deg) || !std::isfinite(view.sun_azimuth_deg)) {
    throw Error("the sun's elevation and azimuth must be finite");
  }
  if (view.camera.kind != CameraKind::kPerspective) {
    throw Error("the exported aerial-perspective volume needs a perspective camera");
  }
  ValidateCamera(view.camera);
  ValidateAerialPerspectiveSettings(view.aerial);
}

ExportedTable AerialPerspectiveTable(const AerialPerspectiveVolume& volume, bool radiance) {
  const AerialPerspectiveSettings& s = volume.settings();
  const std::size_t nc = volume.channel_count();
  ExportedTable table;
  table.name = radiance ? "aerial_radiance" : "aerial_transmittance";
  table.width = s.width;
  table.height = s.height;
  table.depth = s.depth;
  table.batches = ChannelBatchCount(nc);
  table.rgb.reserve(3 * table.texel_count() * table.batches);
  for (std::size_t b = 0; b < table.batches; ++b) {
    for (int z = 0; z < s.depth; ++z) {
      for (int y = 0; y < s.height; ++y) {
        for (int x = 0; x < s.width; ++x) {
          for (std::size_t k = 0; k < 3; ++k) {
            const std::size_t c = std::min(3 * b + k, nc - 1);
            table.rgb.push_back(static_cast<float>(radiance ? volume.RadianceAt(x, y, z, c)
                                                            : volume.TransmittanceAt(x, y, z, c)));
          }
        }
      }
    }
  }
  return table;
}

HillaireTables ComputeHillaireTables(const Model& model, const HillaireExportView& view) {
  const auto* hillaire = dynamic_cast<const HillaireModel*>(&model);
  if (hillaire == nullptr) {
    throw Error("the hillaire tables need model hillaire, not model " + std::string(model.name()));
  }
  const AtmosphereParameters& p = hillaire->parameters();
  ValidateHillaireExportView(p, view);
  HillaireTables tables;
  tables.parameters = p;
  tables.options = HillaireTableOptions(hillaire->settings());
  tables.view = view;
  tables.backend = "cpu";
  const glm::dvec3 sun = glm::normalize(SunDirection(view.sun_elevation_deg, view.sun_azimuth_deg));
  const double r_m = ObserverRadius(p, view);
  const double mu_s = shared::ClampCosine(sun.z);
  std::vector<shared::Texture2D> sky_view;
  std::vector<shared::Texture2D> sky_view_ground;
  std::vector<const shared::Texture2D*> transmittance;
  std::vector<const shared::Texture2D*> multiple_scattering;
  for (const HillaireModel::Batch& batch : hillaire->batches()) {
    transmittance.push_back(&batch.transmittance);
    multiple_scattering.push_back(&batch.multiple_scattering);
    sky_view.push_back(hillaire->ComputeSkyViewLut(batch, r_m, mu_s));
    sky_view_ground.push_back(sky_view.back());
    hillaire->AddGroundView(batch, r_m, mu_s, sky_view_ground.back());
  }
  const auto pointers = [](const std::vector<shared::Texture2D>& textures) {
    std::vector<const shared::Texture2D*> out;
    for (const auto& t : textures) out.push_back(&t);
    return out;
  };
  tables.tables.push_back(io::TableFromTextures("transmittance", transmittance));
  tables.tables.push_back(io::TableFromTextures("multiple_scattering", multiple_scattering));
  tables.tables.push_back(io::TableFromTextures("sky_view", pointers(sky_view)));
  tables.tables.push_back(io::TableFromTextures("sky_view_ground", pointers(sky_view_ground)));
  const std::unique_ptr<SkyView> observer = hillaire->View(view.altitude_m, sun);
  const AerialPerspectiveVolume volume = ComputeAerialPerspectiveVolume(*observer, view.camera, view.aerial);
  tables.tables.push_back(AerialPerspectiveTable(volume, /*radiance=*/true));
  tables.tables.push_back(AerialPerspectiveTable(volume, /*radiance=*/false));
  return tables;
}

std::vector<std::filesystem::path> HillaireTableFiles::all() const {
  std::vector<std::filesystem::path> files;
  for (std::size_t i = 0; i < exr.size(); ++i) {
    files.push_back(exr[i]);
    files.push_back(raw[i]);
  }
  files.push_back(json);
  return files;
}

HillaireTableFiles HillaireTableFilesFor(const std::filesystem::path& name) {
  const std::string base = name.string();
  HillaireTableFiles files;
  files.json = base + ".json";
  for (std::string_view table : kHillaireTableNames) {
    files.exr.push_back(base + "_" + std::string(table) + ".exr");
    files.raw.push_back(base + "_" + std::string(table) + ".raw");
  }
  return files;
}

HillaireTableFiles ExportHillaireTables(const HillaireTables& tables, const std::filesystem::path& name) {
  if (tables.tables.size() != std::size(kHillaireTableNames)) {
    throw Error("hillaire tables: expected " + std::to_string(std::size(kHillaireTableNames)) + " tables, got " +
                std::to_string(tables.tables.size()));
  }
  const HillaireTableFiles files = HillaireTableFilesFor(name);
  // One set: every file written completely first, then published in one locked commit with the
  // manifest last; a failure before that changes no file.
  AtomicFileSet set;
  std::vector<Json> entries;
  for (std::size_t i = 0; i < tables.tables.size(); ++i) {
    const ExportedTable& table = tables.tables[i];
    if (table.name != kHillaireTableNames[i]) {
      throw Error("hillaire tables: table " + std::to_string(i) + " is '" + table.name + "', expected '" +
                  std::string(kHillaireTableNames[i]) + "'");
    }
    entries.push_back(io::StageTable(set, table, files.exr[i], files.raw[i],
                                     {{"atmo:version", ATMO_VERSION},
                                      {"atmo:model", "hillaire"},
                                      {"atmo:table", table.name},
                                      {"atmo:parameterHash", ParameterHashHex(tables.parameters)},
                                      {"atmo:manifest", files.json.filename().string()}}));
  }
  const std::string manifest = Manifest(tables, entries).dump(2) + "\n";
  set.Stage(files.json, [&](const std::filesystem::path& temporary) {
    std::ofstream out(temporary, std::ios::binary);
    out << manifest;
    if (!out) throw Error("write failed");
  });
  const io::FolderLock lock(files.json, /*exclusive=*/true);
  set.Commit();
  return files;
}

HillaireTables ReadHillaireTables(const std::filesystem::path& name) {
  const HillaireTableFiles files = HillaireTableFilesFor(name);
  const io::FolderLock lock(files.json, /*exclusive=*/false);  // no export publishes while we read
  const std::string where = "hillaire tables '" + files.json.string() + "': ";
  Json j;
  try {
    j = Json::parse(ReadFileBounded(files.json, "hillaire tables manifest "));
  } catch (const Json::exception& e) {
    throw Error(where + "malformed JSON (" + std::string(e.what()) + ")");
  }
  try {
    if (!j.is_object() || j.value("format", std::string()) != kFormat) {
      throw Error(where + "not a hillaire tables manifest (format is not \"" + std::string(kFormat) + "\")");
    }
    io::CheckTableVersions(j, kHillaireTablesFormatVersion, where);
    HillaireTables tables;
    tables.parameters = FromJson(j.at("parameters").dump());
    const std::string hash = j.at("parameter_hash").get<std::string>();
    if (hash != ParameterHashHex(tables.parameters)) {
      throw Error(where + "parameter hash " + Printable(hash) + " does not match its parameters' " +
                  ParameterHashHex(tables.parameters));
    }
    tables.parameters.name = j.at("preset").get<std::string>();
    tables.backend = j.at("backend").get<std::string>();
    for (const auto& [key, value] : j.at("options").items()) tables.options.emplace_back(key, value.get<std::string>());
    const Json& view = j.at("view");
    tables.view.altitude_m = view.at("altitude_m").get<double>();
    tables.view.sun_elevation_deg = view.at("sun_elevation_deg").get<double>();
    tables.view.sun_azimuth_deg = view.at("sun_azimuth_deg").get<double>();
    const Json& camera = j.at("aerial_camera");
    // The export's camera is perspective (ValidateHillaireExportView); another kind was read as perspective.
    const std::string kind = camera.at("kind").get<std::string>();
    if (kind != "perspective") throw Error(where + "aerial_camera.kind must be \"perspective\" (got \"" + Printable(kind) + "\")");
    tables.view.camera.kind = CameraKind::kPerspective;
    tables.view.camera.width = static_cast<int>(io::ManifestInteger(camera, "width", 1, kMaxImageSide, where));
    tables.view.camera.height = static_cast<int>(io::ManifestInteger(camera, "height", 1, kMaxImageSide, where));
    tables.view.camera.fov_deg = camera.at("fov_deg").get<double>();
    tables.view.camera.yaw_deg = camera.at("yaw_deg").get<double>();
    tables.view.camera.pitch_deg = camera.at("pitch_deg").get<double>();
    tables.view.aerial.max_distance_m = camera.at("max_distance_km").get<double>() * 1000.0;
    const std::size_t batches = ChannelBatchCount(tables.parameters.channel_count());
    const std::filesystem::path folder = files.json.has_parent_path() ? files.json.parent_path() : ".";
    for (std::string_view table_name : kHillaireTableNames) {
      const std::string key(table_name);
      ExportedTable table =
          io::ReadTable(j.at("tables").at(key), key, folder, where, std::uintmax_t{1} << 32);
      if (table.batches != batches) throw Error(where + key + ": " + std::to_string(table.batches) +
                                                " batches, its parameters have " + std::to_string(batches));
      tables.tables.push_back(std::move(table));
    }
    // One set: the 2D tables flat and at least 2 texels a side (their mappings divide by W - 1 and
    // H - 1, as the model's options require), the sky views' heights even and >= 4 (a sky and a
    // ground half), the two sky views of one size, the two aerial tables of one size.
    for (std::size_t i = 0; i < 4; ++i) {
      const ExportedTable& t = tables.tables[i];
      if (t.depth != 1 || t.width < 2 || t.height < 2) {
        throw Error(where + t.name + ": " + std::to_string(t.width) + "x" + std::to_string(t.height) + "x" +
                    std::to_string(t.depth) + ", a 2D table has depth 1 and at least 2 texels a side");
      }
      if (i >= 2 && (t.height % 2 != 0 || t.height < 4)) {
        throw Error(where + t.name + ": height " + std::to_string(t.height) +
                    ", a sky view's height is even and >= 4 (sky and ground halves)");
      }
    }
    const auto check_same_size = [&](std::size_t a, std::size_t b) {
      const ExportedTable& x = tables.tables[a];
      const ExportedTable& y = tables.tables[b];
      if (x.width != y.width || x.height != y.height || x.depth != y.depth) {
        throw Error(where + y.name + " is " + std::to_string(y.width) + "x" + std::to_string(y.height) + "x" +
                    std::to_string(y.depth) + ", " + x.name + " " + std::to_string(x.width) + "x" +
                    std::to_string(x.height) + "x" + std::to_string(x.depth) + ": they must be of one size");
      }
    };
    check_same_size(2, 3);
    check_same_size(4, 5);
    const ExportedTable& aerial = tables.tables.back();
    tables.view.aerial.width = aerial.width;
    tables.view.aerial.height = aerial.height;
    tables.view.aerial.depth = aerial.depth;
    // The view as the export checks it: an observer inside the atmosphere, a finite sun, a valid camera
    // and volume.
    try {
      ValidateHillaireExportView(tables.parameters, tables.view);
    } catch (const Error& e) {
      throw Error(where + "view: " + e.what());
    }
    return tables;
  } catch (const Json::exception& e) {
    throw Error(where + "missing or malformed key (" + std::string(e.what()) + ")");
  }
}

}  // namespace atmo
