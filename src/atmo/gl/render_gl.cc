#include "gl/render_gl.h"

#include <cmath>
#include <string>

#include "atmo/error.h"
#include "cpu/camera.h"
#include "gl/hillaire_gl.h"
#include "physics/shared_parameters.h"

namespace atmo::gl {

Image RenderHillaireGl(const Context& context, const AtmosphereParameters& parameters,
                       const HillaireSettings& settings, const RenderSettings& render, PassTimings* timings) {
  ValidateCamera(render.camera);
  for (const double value : {render.altitude_m, render.sun_elevation_deg, render.sun_azimuth_deg}) {
    if (!std::isfinite(value)) throw Error("altitude and sun angles must be finite");
  }
  Validate(parameters);
  if (parameters.geometry != Geometry::kSpherical) {
    throw Error("model hillaire needs a spherical atmosphere; the half-space of preset '" + parameters.name +
                "' is the geometry of the simple model");
  }
  if (parameters.channel_count() != 3) {
    throw Error("the gl backend renders 3 channels (red, green, blue); these parameters have " +
                std::to_string(parameters.channel_count()));
  }
  if (!settings.use_sky_view_lut) {
    throw Error("the gl backend renders through the sky-view table only (option sky_view=off is CPU-only)");
  }
  if (render.altitude_m < 0.0) throw Error("altitude_m must be >= 0 for model hillaire");
  // Double-precision metres for what the host computes, km for the GPU (program.h).
  const shared::AtmosphereParameters metres = ToSharedParameters(parameters, 0);
  const shared::AtmosphereParameters km = ToSharedParameters(parameters, 0, 1000.0);
  const double r_m = metres.bottom_radius + render.altitude_m;
  if (r_m > metres.top_radius) {
    throw Error("the gl backend renders from inside the atmosphere (altitude <= " +
                std::to_string((metres.top_radius - metres.bottom_radius) / 1000.0) + " km) for now");
  }
  const double r_km = r_m / 1000.0;
  const glm::dvec3 sun = glm::normalize(SunDirection(render.sun_elevation_deg, render.sun_azimuth_deg));
  const double mu_s = shared::ClampCosine(sun.z);

  PassTimings unused;
  PassTimings& t = timings != nullptr ? *timings : unused;
  GlPassTiming pass;
  const shared::Texture2D transmittance =
      ComputeTransmittanceTableGl(context, km, settings.transmittance_lut, settings.transmittance_samples, &pass);
  t.Add("transmittance_lut", pass.gpu_ms);
  // The ground's share of orders >= 2 is a small hemisphere sum, computed on the host as the CPU does.
  const shared::vec3 ground_transfer =
      settings.multiple_scattering_ground
          ? shared::GetGroundTransfer(metres, settings.multiple_scattering_directions / 2,
                                      settings.multiple_scattering_samples)
          : shared::vec3(0.0);
  const shared::Texture2D multiple_scattering = ComputeMultipleScatteringTableGl(
      context, km, transmittance, settings.multiple_scattering_lut, settings.multiple_scattering_directions,
      settings.multiple_scattering_samples, settings.multiple_scattering_media_phase, ground_transfer, &pass);
  t.Add("multiple_scattering_lut", pass.gpu_ms);
  shared::Texture2D sky_view = ComputeSkyViewTableGl(context, km, transmittance, multiple_scattering,
                                                     settings.sky_view_lut, r_km, mu_s, settings.sky_view_samples, &pass);
  t.Add("sky_view_lut", pass.gpu_ms);
  if (render.terms.ground) {
    const shared::Texture2D ground_irradiance =
        ComputeGroundIrradianceTableGl(context, km, transmittance, multiple_scattering, settings.ground_irradiance_lut,
                                       settings.ground_irradiance_directions, settings.ground_irradiance_samples, &pass);
    t.Add("ground_irradiance_lut", pass.gpu_ms);
    sky_view = AddGroundViewGl(context, km, transmittance, ground_irradiance, sky_view, r_km, mu_s, &pass);
    t.Add("ground_view_lut", pass.gpu_ms);
  }
  const shared::vec3 solar_irradiance(parameters.solar_irradiance[0], parameters.solar_irradiance[1],
                                      parameters.solar_irradiance[2]);
  Image image = RenderSkyViewFrameGl(context, km, transmittance, sky_view, ToSharedCamera(render.camera), r_km,
                                     shared::GetHorizonNadirAngle(metres, r_m), sun, render.terms.sun_disc,
                                     solar_irradiance, &pass);
  t.Add("frame_" + std::to_string(render.camera.width) + "x" + std::to_string(render.camera.height), pass.gpu_ms);
  return image;
}

}  // namespace atmo::gl
