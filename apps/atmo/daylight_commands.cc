// `atmo irradiance` (the light on planes, include/atmo/irradiance.h) and `atmo calibrate` (the clear
// sky of a measured hour, include/atmo/calibration.h): the daylighting commands (docs/daylighting.md).
#include <chrono>
#include <cstdio>
#include <tuple>
#include <string>
#include <vector>

#include "atmo/annual.h"
#include "atmo/calibration.h"
#include "atmo/colour.h"
#include "atmo/error.h"
#include "atmo/image.h"
#include "atmo/irradiance.h"
#include "atmo/render.h"
#include "atmo/weather.h"
#include "commands.h"

namespace atmo::cli {

namespace {

// "TILT:AZIMUTH" or "sun".
Plane ParsePlane(const std::string& text) {
  if (text == "sun") return Plane::FacingSun();
  const std::size_t colon = text.find(':');
  Plane plane;
  try {
    std::size_t used = 0;
    if (colon == std::string::npos) throw std::invalid_argument("");
    plane.tilt_deg = std::stod(text.substr(0, colon), &used);
    if (used != colon) throw std::invalid_argument("");
    const std::string azimuth = text.substr(colon + 1);
    plane.azimuth_deg = std::stod(azimuth, &used);
    if (used != azimuth.size() || azimuth.empty()) throw std::invalid_argument("");
  } catch (const std::logic_error&) {
    throw Error("--plane must be TILT:AZIMUTH in degrees (e.g. 35:180) or sun, got '" + text + "'");
  }
  if (!(plane.tilt_deg >= 0.0 && plane.tilt_deg <= 180.0) || !std::isfinite(plane.azimuth_deg)) {
    throw Error("--plane " + text + ": the tilt must be in [0, 180] and the azimuth finite");
  }
  return plane;
}

void WriteText(const std::string& path, const std::string& text) {
  if (path.empty()) {
    if (std::fwrite(text.data(), 1, text.size(), stdout) != text.size() || std::fflush(stdout) != 0) {
      throw Error("cannot write to standard output");
    }
    return;
  }
  WriteTextFileAtomically(path, text);
}

// Daylighting works on the accurate model and a real atmosphere unless the user chose.
CommonOptions DaylightDefaults(const CommonOptions& common, bool model_given, bool preset_given) {
  CommonOptions out = common;
  if (!model_given) out.model = "source4d";
  if (!preset_given && out.config.empty()) out.preset = "us-standard";
  return out;
}

}  // namespace

int RunIrradiance(const CommonOptions& given, const IrradianceCommand& command) {
  const CommonOptions common = DaylightDefaults(given, given.model_given, given.preset_given);
  CheckBackend(common);
  CheckOutputsApart(common, {}, {{"--out", command.out_path}});
  if (!command.out_path.empty()) CheckOutputWritable(command.out_path);
  CheckExtension("--out", command.out_path, ".csv");
  std::vector<Plane> planes;
  for (const std::string& text : command.planes) planes.push_back(ParsePlane(text));

  AtmosphereParameters parameters = LoadParameters(common);
  parameters.solar_irradiance.assign(parameters.channel_count(), 1.0);  // the solar spectrum comes in by colour
  struct Row {
    double elevation_deg;
    double azimuth_deg;
    double sun_scale;
  };
  std::vector<Row> rows;
  if (HasDate(command.sun)) {
    const SunAtInstant at = SunAtDate(command.sun);
    rows.push_back({at.position.elevation_deg, at.position.azimuth_deg,
                    1.0 / (at.position.distance_au * at.position.distance_au)});
  } else {
    for (double elevation : command.sun_elevations_deg) rows.push_back({elevation, command.sun_azimuth_deg, 1.0});
  }
  const std::unique_ptr<Model> model = CreateModelFor(common, parameters);
  const double altitude_m = command.altitude_m.value_or(parameters.observer_altitude_m);
  const SpectralConversion convert(parameters.wavelengths_nm);
  IrradianceSettings settings;
  settings.circumsolar_half_angle_deg = command.circumsolar_deg;

  std::string csv = command.spectral
                        ? "sun_elevation_deg,sun_azimuth_deg,plane,wavelength_nm,direct,circumsolar,sky_diffuse,"
                          "ground_reflected,global\n"
                        : "sun_elevation_deg,sun_azimuth_deg,plane,direct_lux,circumsolar_lux,sky_diffuse_lux,"
                          "ground_reflected_lux,global_lux,direct_w_m2,circumsolar_w_m2,sky_diffuse_w_m2,"
                          "ground_reflected_w_m2,global_w_m2\n";
  for (const Row& row : rows) {
    settings.sun_scale = row.sun_scale;
    const std::unique_ptr<SkyView> sky = model->View(altitude_m, SunDirection(row.elevation_deg, row.azimuth_deg));
    const IrradianceResult result = ComputeIrradiance(*sky, parameters, planes, settings);
    for (std::size_t p = 0; p < planes.size(); ++p) {
      const IrradianceComponents& e = result.planes[p];
      const std::vector<double> global = e.Global();
      const std::vector<double>* parts[] = {&e.direct, &e.circumsolar, &e.sky_diffuse, &e.ground_reflected, &global};
      const std::string head = Format("%.10g,%.10g,%s", row.elevation_deg, row.azimuth_deg, command.planes[p].c_str());
      if (command.spectral) {
        for (std::size_t c = 0; c < parameters.channel_count(); ++c) {
          csv += head + Format(",%.10g", parameters.wavelengths_nm[c]);
          for (const std::vector<double>* part : parts) csv += Format(",%.6g", convert.SpectralRadiance(c, (*part)[c]));
          csv += "\n";
        }
      } else {
        csv += head;
        for (const std::vector<double>* part : parts) csv += Format(",%.6g", convert.Luminance(*part));
        for (const std::vector<double>* part : parts) csv += Format(",%.6g", convert.Radiance(*part));
        csv += "\n";
      }
    }
  }
  WriteText(command.out_path, csv);
  return 0;
}

int RunCalibrate(const CommonOptions& given, const CalibrateCommand& command) {
  const CommonOptions common = DaylightDefaults(given, given.model_given, given.preset_given);
  CheckBackend(common);
  if (command.out_path.empty()) throw Error("--out FILE.json is required");
  CheckOutputsApart(common, {}, {{"--out", command.out_path}});
  CheckOutputWritable(command.out_path);
  CheckExtension("--out", command.out_path, ".json");
  const AerosolRequest& aerosol = common.aerosol;
  if (aerosol.aod_550 || aerosol.angstrom_exponent || aerosol.visibility_km || aerosol.linke_turbidity) {
    throw Error("atmo calibrate fits the aerosol's amount itself: give only --aerosol TYPE");
  }
  CommonOptions without_aerosol = common;
  without_aerosol.aerosol = {};
  const AtmosphereParameters parameters = LoadParameters(without_aerosol);

  double elevation_deg = 0.0, azimuth_deg = command.sun_azimuth_deg;
  CalibrationSettings settings;
  if (HasDate(command.sun)) {
    const SunAtInstant at = SunAtDate(command.sun);
    elevation_deg = at.position.elevation_deg;
    azimuth_deg = at.position.azimuth_deg;
    settings.sun_scale = 1.0 / (at.position.distance_au * at.position.distance_au);
  } else if (command.sun_elevation_deg) {
    elevation_deg = *command.sun_elevation_deg;
  } else {
    throw Error("give the sun: --sun-elevation E, or --date with --latitude and --longitude");
  }
  settings.model = common.model;
  settings.options = ParseModelOptions(common.options);
  if (aerosol.type) settings.aerosol_type = *aerosol.type;
  settings.circumsolar_half_angle_deg = command.circumsolar_deg;
  settings.tolerance = command.tolerance_percent / 100.0;
  const double altitude_m = command.altitude_m.value_or(parameters.observer_altitude_m);
  const CalibrationResult result =
      CalibrateClearSky(parameters, altitude_m, SunDirection(elevation_deg, azimuth_deg),
                        DaylightMeasurement{command.direct_normal_lux, command.diffuse_horizontal_lux}, settings);
  if (result.status != CalibrationStatus::kClear) {
    throw Error("no clear sky reproduces these measurements (" + std::string(ToString(result.status)) +
                "): " + result.message + "; nothing written");
  }
  WriteText(command.out_path, ToJson(result.parameters));
  std::printf("%s; %d models of %s; wrote %s\n", result.message.c_str(), result.model_builds, common.model.c_str(),
              command.out_path.c_str());
  return 0;
}

namespace {

// "A:B" with 0 <= A < B (B may be past the file's end).
std::pair<std::size_t, std::size_t> ParseHours(const std::string& text) {
  const std::size_t colon = text.find(':');
  try {
    if (colon == std::string::npos || text.find_first_not_of("0123456789:") != std::string::npos) throw std::invalid_argument("");
    const std::size_t a = std::stoul(text.substr(0, colon));
    const std::size_t b = std::stoul(text.substr(colon + 1));
    if (b <= a) throw std::invalid_argument("");
    return {a, b};
  } catch (const std::logic_error&) {
    throw Error("--hours must be A:B with 0 <= A < B (the file's hours from 0), got '" + text + "'");
  }
}

// "I/N" with 0 <= I < N.
std::pair<int, int> ParseShard(const std::string& text) {
  const std::size_t slash = text.find('/');
  try {
    if (slash == std::string::npos || text.find_first_not_of("0123456789/") != std::string::npos) throw std::invalid_argument("");
    const int i = std::stoi(text.substr(0, slash));
    const int n = std::stoi(text.substr(slash + 1));
    if (n < 1 || i >= n || n > 100000) throw std::invalid_argument("");
    return {i, n};
  } catch (const std::logic_error&) {
    throw Error("--shard must be I/N with 0 <= I < N <= 100000, got '" + text + "'");
  }
}

}  // namespace

int RunAnnual(const CommonOptions& given, const AnnualCommand& command) {
  const CommonOptions common = DaylightDefaults(given, given.model_given, given.preset_given);
  CheckBackend(common);
  const AerosolRequest& aerosol = common.aerosol;
  if (aerosol.aod_550 || aerosol.angstrom_exponent || aerosol.visibility_km || aerosol.linke_turbidity) {
    throw Error("atmo annual fits each hour's aerosol amount itself: give only --aerosol TYPE");
  }
  std::vector<Plane> planes;
  for (const std::string& text : command.planes) planes.push_back(ParsePlane(text));
  AnnualRun run;
  run.out_dir = command.out_dir;
  if (!command.hours.empty()) std::tie(run.first_hour, run.end_hour) = ParseHours(command.hours);
  if (!command.shard.empty()) std::tie(run.shard, run.shards) = ParseShard(command.shard);
  CommonOptions without_aerosol = common;
  without_aerosol.aerosol = {};
  const AtmosphereParameters parameters = LoadParameters(without_aerosol);
  WeatherFile weather = ReadEpw(command.epw_path);
  const WeatherLocation& place = weather.location;
  if (command.latitude_deg && std::abs(*command.latitude_deg - place.latitude_deg) > 0.1) {
    throw Error(command.epw_path + ": its latitude " + Format("%.2f", place.latitude_deg) + " disagrees with --latitude " +
                Format("%.2f", *command.latitude_deg));
  }
  if (command.longitude_deg && std::abs(*command.longitude_deg - place.longitude_deg) > 0.1) {
    throw Error(command.epw_path + ": its longitude " + Format("%.2f", place.longitude_deg) + " disagrees with --longitude " +
                Format("%.2f", *command.longitude_deg));
  }
  AnnualSettings settings;
  settings.model = common.model;
  settings.options = ParseModelOptions(common.options);
  if (aerosol.type) settings.aerosol_type = *aerosol.type;
  settings.planes = planes;
  settings.sky_subdivision = command.subdivision;
  settings.patch_samples = command.patch_samples;
  settings.circumsolar_half_angle_deg = command.circumsolar_deg;
  settings.sun_in_matrix = !command.no_sun_in_matrix;
  settings.sky_map_size = command.sky_maps;
  settings.per_wavelength = command.per_wavelength;
  AnnualSkies skies(parameters, std::move(weather), settings);
  const auto start = std::chrono::steady_clock::now();
  const AnnualRunReport report = atmo::RunAnnual(skies, run, [](const std::string& message) {
    std::fprintf(stderr, "atmo: annual: %s\n", message.c_str());
  });
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("annual: %zu hours computed (%zu of the selection already done) with %d models of %s in %.1f s; ",
              report.computed, report.already_done, report.models_built, common.model.c_str(), seconds);
  if (report.merged) {
    std::printf("wrote %s/sky.mtx, hours.csv and irradiance.csv%s\n", command.out_dir.c_str(),
                command.per_wavelength ? " (and irradiance_spectral.csv)" : "");
  } else {
    std::printf("%zu of the file's %zu hours done: run the other shards (or rerun) to finish\n", report.file_done,
                skies.weather().hours.size());
  }
  return 0;
}

}  // namespace atmo::cli
