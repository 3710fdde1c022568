// `atmo illuminance`: what a lux meter reads under the model's sky, from the sun and from the sky,
// on a horizontal plane (atmo::ComputeIlluminance), as one CSV row per sun elevation, or one row
// for the sun and moon of a --date. The night sky's own light and the moon have their own columns.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <optional>

#include "atmo/error.h"
#include "atmo/illuminance.h"
#include "atmo/moon.h"
#include "atmo/night_sky.h"
#include "atmo/render.h"
#include "atmo/stars.h"
#include "commands.h"

namespace atmo::cli {

int RunIlluminance(const CommonOptions& common, const IlluminanceCommand& command) {
  CheckBackend(common);
  AtmosphereParameters parameters = LoadParameters(common);
  parameters.solar_irradiance.assign(parameters.channel_count(), 1.0);  // the solar spectrum comes in by colour
  if (command.no_night_glow) parameters.night_sky.enabled = false;
  const std::unique_ptr<Model> model = CreateModelFor(common, parameters);
  const double altitude_m = command.altitude_m.value_or(parameters.observer_altitude_m);
  // --date: one row for that instant's sun (and moon); else one per --sun-elevation, the sun south.
  struct Row {
    double elevation_deg;
    double azimuth_deg;
    std::optional<double> julian_day_utc;
  };
  std::vector<Row> rows;
  if (HasDate(command.sun)) {
    const SunAtInstant at = SunAtDate(command.sun);
    rows.push_back({at.position.elevation_deg, at.position.azimuth_deg, at.julian_day_utc});
  } else {
    for (double elevation : command.sun_elevations_deg) rows.push_back({elevation, 180.0, std::nullopt});
  }
  // The stars when Debian's stellarium-data is installed (docs/night.md), unless --no-stars.
  std::error_code error;
  const StarCatalogue* catalogue =
      !command.no_stars && std::filesystem::is_directory(StarCatalogue::DefaultFolder(), error)
          ? &StarCatalogue::Default()
          : nullptr;
  std::printf("altitude_m,sun_elevation_deg,direct_normal_lux,direct_horizontal_lux,diffuse_horizontal_lux,"
              "global_horizontal_lux,direct_normal_w_m2,diffuse_horizontal_w_m2,night_sky_horizontal_lux,"
              "night_sky_horizontal_w_m2,moon_elevation_deg,moon_phase_deg,moon_direct_horizontal_lux,"
              "moon_diffuse_horizontal_lux\n");
  for (const Row& row : rows) {
    const glm::dvec3 sun = SunDirection(row.elevation_deg, row.azimuth_deg);
    const std::unique_ptr<SkyView> sky = model->View(altitude_m, sun);
    // The night sky's own light and the moon, each in its own columns and in the global (docs/night.md).
    const glm::dvec3 pole = row.julian_day_utc ? EclipticPoleDirection(*row.julian_day_utc, *command.sun.latitude_deg,
                                                                       *command.sun.longitude_deg)
                                               : glm::dvec3(0.0);
    NightSky night(parameters, std::max(altitude_m, 0.0), sun, pole);
    // The sky placed by the date and place (the stars, the Milky Way's starlight), else by the sun.
    const CelestialFrame frame = row.julian_day_utc ? CelestialFrame::FromDate(*row.julian_day_utc,
                                                                               *command.sun.latitude_deg,
                                                                               *command.sun.longitude_deg)
                                                    : CelestialFrame::FromSun(sun);
    if (catalogue != nullptr) {
      night.SetStars(*catalogue, frame);
    } else {
      night.SetFrame(frame);
    }
    IlluminanceSettings settings;
    settings.night_sky = &night;
    const std::optional<MoonPosition> place = ResolveMoon(command.moon, command.sun, row.azimuth_deg, row.julian_day_utc);
    std::optional<Moon> moon;
    std::unique_ptr<SkyView> moon_sky;
    if (place) {
      const glm::dvec3 direction = SunDirection(place->elevation_deg, place->azimuth_deg);
      moon.emplace(direction, place->phase_angle_deg, place->distance_km, parameters.wavelengths_nm, sun);
      moon_sky = model->View(altitude_m, direction);
      settings.moon = &*moon;
      settings.moon_sky = moon_sky.get();
    }
    const Illuminance e = ComputeIlluminance(*sky, model->parameters(), settings);
    std::printf("%.10g,%.10g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,", altitude_m, row.elevation_deg,
                e.direct_normal_lux, e.direct_horizontal_lux, e.diffuse_horizontal_lux, e.global_horizontal_lux,
                e.direct_normal_w_m2, e.diffuse_horizontal_w_m2, e.night_sky_horizontal_lux,
                e.night_sky_horizontal_w_m2);
    if (place) {
      std::printf("%.6g,%.6g,%.6g,%.6g\n", place->elevation_deg, place->phase_angle_deg, e.moon_direct_horizontal_lux,
                  e.moon_diffuse_horizontal_lux);
    } else {
      std::printf("nan,nan,0,0\n");  // no moon
    }
  }
  return 0;
}

}  // namespace atmo::cli
