// Sun and sky illuminance (include/atmo/illuminance.h).
#include "atmo/illuminance.h"

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "atmo/colour.h"
#include "atmo/error.h"

namespace atmo {

// Midpoint rule over the hemisphere: zenith cell i spans [i, i + 1] dtheta, azimuth cell j
// [j, j + 1] dphi; the exact cell integral of cos(theta) d(omega) = cos sin dtheta dphi is
// dphi (sin^2(theta_1) - sin^2(theta_0)) / 2, used as the weight of the cell's centre so that a
// uniform sky L integrates to exactly pi L.
Illuminance ComputeIlluminance(const SkyView& sky, const AtmosphereParameters& parameters,
                               const IlluminanceSettings& settings) {
  for (int steps : {settings.zenith_steps, settings.azimuth_steps}) {
    if (steps < 2 || steps > 4096) throw Error("illuminance steps must be in [2, 4096], got " + std::to_string(steps));
  }
  const std::size_t n = sky.channel_count();
  if (n != parameters.channel_count()) throw Error("the view's channels do not match the parameters");
  const SpectralConversion convert(parameters.wavelengths_nm);

  const double d_theta = 0.5 * std::numbers::pi / settings.zenith_steps;
  const double d_phi = 2.0 * std::numbers::pi / settings.azimuth_steps;
  std::vector<glm::dvec3> views;
  std::vector<double> weights;
  views.reserve(static_cast<std::size_t>(settings.zenith_steps) * settings.azimuth_steps);
  for (int i = 0; i < settings.zenith_steps; ++i) {
    const double theta_0 = i * d_theta;
    const double theta_1 = (i + 1) * d_theta;
    const double weight = d_phi * 0.5 * (std::sin(theta_1) * std::sin(theta_1) - std::sin(theta_0) * std::sin(theta_0));
    for (int j = 0; j < settings.azimuth_steps; ++j) {
      views.push_back(DirectionFromZenithAzimuth(0.5 * (theta_0 + theta_1), (j + 0.5) * d_phi));
      weights.push_back(weight);
    }
  }
  std::vector<float> radiance(views.size() * n);
  sky.RadianceBatch(views, RadianceTerms{/*sun_disc=*/false, /*ground=*/false}, radiance);
  std::vector<double> hemisphere(n, 0.0);  // per channel: integral of r cos(theta) d(omega)
  for (std::size_t k = 0; k < views.size(); ++k) {
    for (std::size_t c = 0; c < n; ++c) hemisphere[c] += weights[k] * radiance[k * n + c];
  }

  std::vector<double> night(n, 0.0);  // per channel: the night sky's integral of r cos(theta) d(omega)
  if (settings.night_sky != nullptr) {
    if (settings.night_sky->channel_count() != n) throw Error("the night sky's channels do not match the parameters");
    std::vector<double> ones(n, 1.0);
    std::vector<float> glow(views.size() * n, 0.0f);
    settings.night_sky->Scaled(ones).Add(views, glow);
    for (std::size_t k = 0; k < views.size(); ++k) {
      for (std::size_t c = 0; c < n; ++c) night[c] += weights[k] * glow[k * n + c];
    }
    // The stars: point sources, each its attenuated irradiance times the cosine of its zenith angle.
    if (const StarCatalogue* stars = settings.night_sky->stars(); stars != nullptr) {
      std::vector<double> t(n);
      for (std::size_t i = 0; i < stars->stars().size(); ++i) {
        const glm::dvec3 d = settings.night_sky->frame().ToLocal(stars->stars()[i]);
        if (d.z <= 0.0) continue;
        settings.night_sky->Transmittance(d.z, t);
        for (std::size_t c = 0; c < n; ++c) night[c] += settings.night_sky->star_irradiance()[i * n + c] * t[c] * d.z;
      }
    }
  }

  std::vector<double> moon_diffuse(n, 0.0);
  std::vector<double> moon_direct(n, 0.0);
  double moon_up = 0.0;
  if ((settings.moon == nullptr) != (settings.moon_sky == nullptr)) {
    throw Error("the moon's illuminance needs both its Moon and its view");
  }
  if (settings.moon != nullptr) {
    const std::vector<double>& r = settings.moon->relative_irradiance();
    if (r.size() != n || settings.moon_sky->channel_count() != n) throw Error("the moon's channels do not match the parameters");
    std::vector<float> moonlit(views.size() * n);
    settings.moon_sky->RadianceBatch(views, RadianceTerms{/*sun_disc=*/false, /*ground=*/false}, moonlit);
    for (std::size_t k = 0; k < views.size(); ++k) {
      for (std::size_t c = 0; c < n; ++c) moon_diffuse[c] += weights[k] * moonlit[k * n + c] * r[c];
    }
    const glm::dvec3 moon = glm::normalize(settings.moon->direction());
    settings.moon_sky->Transmittance(moon, moon_direct);
    for (std::size_t c = 0; c < n; ++c) moon_direct[c] *= r[c];
    moon_up = std::max(0.0, moon.z);
  }

  std::vector<double> transmittance(n);
  const glm::dvec3 sun = glm::normalize(sky.sun_direction());
  sky.Transmittance(sun, transmittance);

  Illuminance e;
  e.direct_normal_lux = convert.Luminance(transmittance);
  e.direct_normal_w_m2 = convert.Radiance(transmittance);
  e.direct_horizontal_lux = e.direct_normal_lux * std::max(0.0, sun.z);
  e.diffuse_horizontal_lux = convert.Luminance(hemisphere);
  e.diffuse_horizontal_w_m2 = convert.Radiance(hemisphere);
  e.night_sky_horizontal_lux = convert.Luminance(night);
  e.night_sky_horizontal_w_m2 = convert.Radiance(night);
  e.moon_direct_normal_lux = convert.Luminance(moon_direct);
  e.moon_direct_horizontal_lux = e.moon_direct_normal_lux * moon_up;
  e.moon_diffuse_horizontal_lux = convert.Luminance(moon_diffuse);
  e.global_horizontal_lux = e.diffuse_horizontal_lux + e.night_sky_horizontal_lux + e.direct_horizontal_lux +
                            e.moon_direct_horizontal_lux + e.moon_diffuse_horizontal_lux;
  return e;
}

}  // namespace atmo
