// `atmo illuminance`: what a lux meter reads under the model's sky, from the sun and from the sky,
// on a horizontal plane (atmo::ComputeIlluminance), as one CSV row per sun elevation.
#include <cstdio>

#include "atmo/error.h"
#include "atmo/illuminance.h"
#include "atmo/render.h"
#include "commands.h"

namespace atmo::cli {

int RunIlluminance(const CommonOptions& common, const IlluminanceCommand& command) {
  CheckBackend(common);
  AtmosphereParameters parameters = LoadParameters(common);
  parameters.solar_irradiance.assign(parameters.channel_count(), 1.0);  // the solar spectrum comes in by colour
  const std::unique_ptr<Model> model = CreateModelFor(common, parameters);
  const double altitude_m = command.altitude_m.value_or(parameters.observer_altitude_m);
  std::printf("altitude_m,sun_elevation_deg,direct_normal_lux,direct_horizontal_lux,diffuse_horizontal_lux,"
              "global_horizontal_lux,direct_normal_w_m2,diffuse_horizontal_w_m2\n");
  for (double elevation : command.sun_elevations_deg) {
    const std::unique_ptr<SkyView> sky = model->View(altitude_m, SunDirection(elevation, 0.0));
    const Illuminance e = ComputeIlluminance(*sky, model->parameters());
    std::printf("%.10g,%.10g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g\n", altitude_m, elevation, e.direct_normal_lux,
                e.direct_horizontal_lux, e.diffuse_horizontal_lux, e.global_horizontal_lux, e.direct_normal_w_m2,
                e.diffuse_horizontal_w_m2);
  }
  return 0;
}

}  // namespace atmo::cli
