// Irradiance on planes from the sky's radiance (include/atmo/irradiance.h).
#include "atmo/irradiance.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "atmo/error.h"
#include "printable.h"

namespace atmo {

namespace {

std::vector<double> Sum(std::initializer_list<const std::vector<double>*> parts) {
  std::vector<double> out((*parts.begin())->size(), 0.0);
  for (const std::vector<double>* part : parts) {
    for (std::size_t c = 0; c < out.size(); ++c) out[c] += (*part)[c];
  }
  return out;
}

void CheckRange(double value, double low, double high, const std::string& what) {
  if (!(value >= low && value <= high)) {
    throw Error(what + " must be in [" + FormatNumber(low) + ", " + FormatNumber(high) + "], got " +
                FormatNumber(value));
  }
}

// The directions at which the sky is evaluated: the hemisphere's zenith-azimuth cells, those that
// reach within `refine_rad` of the sun split into sub-cells; each with its solid angle and whether
// it lies in the circumsolar cone.
struct SkySamples {
  std::vector<glm::dvec3> views;
  std::vector<double> solid_angles;
  std::vector<char> circumsolar;
};

SkySamples HemisphereSamples(const glm::dvec3& sun, const IrradianceSettings& s) {
  SkySamples out;
  const double d_theta = 0.5 * std::numbers::pi / s.zenith_steps;
  const double d_phi = 2.0 * std::numbers::pi / s.azimuth_steps;
  const double cone = glm::radians(s.circumsolar_half_angle_deg);
  const double cos_cone = std::cos(cone);
  // The aureole is steep within a few degrees of the sun whether or not a cone is asked for.
  const double refine = std::max(cone, glm::radians(5.0));
  const auto add = [&](double theta_0, double theta_1, double phi_0, double phi_1) {
    const glm::dvec3 v = DirectionFromZenithAzimuth(0.5 * (theta_0 + theta_1), 0.5 * (phi_0 + phi_1));
    out.views.push_back(v);
    out.solid_angles.push_back((phi_1 - phi_0) * (std::cos(theta_0) - std::cos(theta_1)));
    out.circumsolar.push_back(cone > 0.0 && glm::dot(v, sun) >= cos_cone ? 1 : 0);
  };
  const int n = s.circumsolar_subdivisions;
  for (int i = 0; i < s.zenith_steps; ++i) {
    const double theta_0 = i * d_theta;
    const double theta_1 = (i + 1) * d_theta;
    const double widest = std::sin(std::min(theta_1, 0.5 * std::numbers::pi));
    const double reach = 0.5 * std::hypot(d_theta, widest * d_phi);  // centre to corner, at most
    for (int j = 0; j < s.azimuth_steps; ++j) {
      const double phi_0 = j * d_phi;
      const double phi_1 = (j + 1) * d_phi;
      const glm::dvec3 centre = DirectionFromZenithAzimuth(0.5 * (theta_0 + theta_1), 0.5 * (phi_0 + phi_1));
      const double from_sun = std::acos(std::clamp(glm::dot(centre, sun), -1.0, 1.0));
      if (n > 1 && from_sun - reach < refine) {
        for (int a = 0; a < n; ++a) {
          for (int b = 0; b < n; ++b) {
            add(theta_0 + a * d_theta / n, theta_0 + (a + 1) * d_theta / n, phi_0 + b * d_phi / n,
                phi_0 + (b + 1) * d_phi / n);
          }
        }
      } else {
        add(theta_0, theta_1, phi_0, phi_1);
      }
    }
  }
  return out;
}

}  // namespace

glm::dvec3 Plane::Normal(const glm::dvec3& sun_direction) const {
  if (tracks_sun) return glm::normalize(sun_direction);
  return DirectionFromZenithAzimuth(glm::radians(tilt_deg), glm::radians(azimuth_deg));
}

std::vector<double> IrradianceComponents::Global() const {
  return Sum({&direct, &circumsolar, &sky_diffuse, &ground_reflected});
}

std::vector<double> IrradianceComponents::Diffuse() const {
  return Sum({&circumsolar, &sky_diffuse, &ground_reflected});
}

IrradianceResult ComputeIrradiance(const SkyView& sky, const AtmosphereParameters& parameters,
                                   std::span<const Plane> planes, const IrradianceSettings& settings) {
  for (int steps : {settings.zenith_steps, settings.azimuth_steps}) {
    if (steps < 2 || steps > 4096) throw Error("irradiance steps must be in [2, 4096], got " + std::to_string(steps));
  }
  CheckRange(settings.circumsolar_half_angle_deg, 0.0, 10.0, "the circumsolar half-angle (degrees)");
  CheckRange(settings.circumsolar_subdivisions, 1, 64, "the circumsolar subdivisions");
  if (!(std::isfinite(settings.sun_scale) && settings.sun_scale > 0.0)) {
    throw Error("the sun scale must be positive and finite, got " + FormatNumber(settings.sun_scale));
  }
  for (const Plane& plane : planes) {
    if (plane.tracks_sun) continue;
    CheckRange(plane.tilt_deg, 0.0, 180.0, "a plane's tilt (degrees)");
    if (!std::isfinite(plane.azimuth_deg)) throw Error("a plane's azimuth must be finite, got " + FormatNumber(plane.azimuth_deg));
  }
  const std::size_t n = sky.channel_count();
  if (n != parameters.channel_count() || parameters.ground_albedo.size() != n) {
    throw Error("the view's channels do not match the parameters");
  }
  const glm::dvec3 sun = glm::normalize(sky.sun_direction());
  const double scale = settings.sun_scale;

  const SkySamples samples = HemisphereSamples(sun, settings);
  std::vector<float> radiance(samples.views.size() * n);
  sky.RadianceBatch(samples.views, RadianceTerms{/*sun_disc=*/false, /*ground=*/false}, radiance);

  IrradianceResult result;
  result.direct_normal.assign(n, 0.0);
  sky.Transmittance(sun, result.direct_normal);
  for (double& t : result.direct_normal) t *= scale;
  const bool sun_up = sun.z > 0.0;

  // The plane's sky components: sum over the samples of L w max(0, n.v), into the cone or the rest.
  const auto sky_part = [&](const glm::dvec3& normal, IrradianceComponents& e) {
    e.circumsolar.assign(n, 0.0);
    e.sky_diffuse.assign(n, 0.0);
    for (std::size_t k = 0; k < samples.views.size(); ++k) {
      const double cosine = glm::dot(normal, samples.views[k]);
      if (cosine <= 0.0) continue;
      const double w = scale * samples.solid_angles[k] * cosine;
      std::vector<double>& into = samples.circumsolar[k] ? e.circumsolar : e.sky_diffuse;
      for (std::size_t c = 0; c < n; ++c) into[c] += w * radiance[k * n + c];
    }
    e.direct.assign(n, 0.0);
    const double incidence = glm::dot(normal, sun);
    if (sun_up && incidence > 0.0) {
      for (std::size_t c = 0; c < n; ++c) e.direct[c] = result.direct_normal[c] * incidence;
    }
  };

  // The ground's radiance comes from the horizontal global irradiance.
  IrradianceComponents horizontal;
  sky_part(glm::dvec3(0.0, 0.0, 1.0), horizontal);
  std::vector<double> ground_radiance(n);
  for (std::size_t c = 0; c < n; ++c) {
    ground_radiance[c] = parameters.ground_albedo[c] *
                         (horizontal.direct[c] + horizontal.circumsolar[c] + horizontal.sky_diffuse[c]) /
                         std::numbers::pi;
  }

  for (const Plane& plane : planes) {
    IrradianceComponents e;
    const glm::dvec3 normal = plane.Normal(sun);
    sky_part(normal, e);
    // The part of the plane's view below the horizon: integral of max(0, n.v) over the lower
    // hemisphere = pi (1 - n_z) / 2.
    const double below = std::numbers::pi * 0.5 * (1.0 - std::clamp(normal.z, -1.0, 1.0));
    e.ground_reflected.resize(n);
    for (std::size_t c = 0; c < n; ++c) e.ground_reflected[c] = ground_radiance[c] * below;
    result.planes.push_back(std::move(e));
  }
  return result;
}

}  // namespace atmo
