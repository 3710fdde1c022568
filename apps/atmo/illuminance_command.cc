// `atmo illuminance`: what a lux meter reads under the model's sky, from the sun and from the sky,
// on a horizontal plane (atmo::ComputeIlluminance), as one CSV row per sun elevation.
#include <algorithm>
#include <cstdio>

#include "atmo/error.h"
#include "atmo/illuminance.h"
#include "atmo/night_sky.h"
#include "atmo/render.h"
#include "commands.h"

namespace atmo::cli {

int RunIlluminance(const CommonOptions& common, const IlluminanceCommand& command) {
  CheckBackend(common);
  AtmosphereParameters parameters = LoadParameters(common);
  parameters.solar_irradiance.assign(parameters.channel_count(), 1.0);  // the solar spectrum comes in by colour
  const std::unique_ptr<Model> model = CreateModelFor(common, parameters);
  const double altitude_m = command.altitude_m.value_or(parameters.observer_altitude_m);
  if (command.no_night_glow) parameters.night_sky.enabled = false;
  std::printf("altitude_m,sun_elevation_deg,direct_normal_lux,direct_horizontal_lux,diffuse_horizontal_lux,"
              "global_horizontal_lux,direct_normal_w_m2,diffuse_horizontal_w_m2,night_sky_horizontal_lux,"
              "night_sky_horizontal_w_m2\n");
  for (double elevation : command.sun_elevations_deg) {
    const glm::dvec3 sun = SunDirection(elevation, 0.0);
    const std::unique_ptr<SkyView> sky = model->View(altitude_m, sun);
    // The night sky's own light, in its own column and in the global (docs/night.md).
    const NightSky night(parameters, std::max(altitude_m, 0.0), sun);
    IlluminanceSettings settings;
    settings.night_sky = &night;
    const Illuminance e = ComputeIlluminance(*sky, model->parameters(), settings);
    std::printf("%.10g,%.10g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g\n", altitude_m, elevation, e.direct_normal_lux,
                e.direct_horizontal_lux, e.diffuse_horizontal_lux, e.global_horizontal_lux, e.direct_normal_w_m2,
                e.diffuse_horizontal_w_m2, e.night_sky_horizontal_lux, e.night_sky_horizontal_w_m2);
  }
  return 0;
}

}  // namespace atmo::cli
