// Irradiance on planes from the sky's radiance (include/atmo/irradiance.h).
#include "atmo/irradiance.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "atmo/error.h"
#include "atmo/sky_patches.h"
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

// The directions at which the sky is evaluated: cells in zenith and azimuth (the hemisphere's grid,
// or each sky patch split into patch_samples x patch_samples), those that reach within
// `refine_rad` of the sun split further; each with its solid angle, whether it lies in the
// circumsolar cone, and its patch (-1 without patches).
struct Cell {
  double theta_0, theta_1, phi_0, phi_1;
  int patch;
};

struct SkySamples {
  std::vector<glm::dvec3> views;
  std::vector<double> solid_angles;
  std::vector<double> circumsolar;  // the fraction of the cell's solid angle in the cone
  std::vector<int> patch;
  std::vector<Cell> cells;
};

// The integral of n.v over a cell, exact (the cosine may be negative in part of it).
double CosineIntegral(const glm::dvec3& n, const Cell& c) {
  const double s0 = std::sin(c.theta_0), s1 = std::sin(c.theta_1);
  const double sin2 = 0.5 * (c.theta_1 - c.theta_0) - 0.25 * (std::sin(2.0 * c.theta_1) - std::sin(2.0 * c.theta_0));
  return n.z * (c.phi_1 - c.phi_0) * 0.5 * (s1 * s1 - s0 * s0) +
         sin2 * (n.x * (std::cos(c.phi_0) - std::cos(c.phi_1)) + n.y * (std::sin(c.phi_1) - std::sin(c.phi_0)));
}

// The integral of max(0, n.v) over a cell: exact where the cosine keeps one sign on the cell's
// corners and edge midpoints, else a 12 x 12 midpoint rule of the clamped cosine.
double ClampedCosineIntegral(const glm::dvec3& n, const Cell& c) {
  int positive = 0, negative = 0;
  for (double a : {0.0, 0.5, 1.0}) {
    for (double b : {0.0, 0.5, 1.0}) {
      const double d = glm::dot(n, DirectionFromZenithAzimuth(c.theta_0 + a * (c.theta_1 - c.theta_0),
                                                              c.phi_0 + b * (c.phi_1 - c.phi_0)));
      (d > 0.0 ? positive : negative) += 1;
    }
  }
  if (negative == 0) return CosineIntegral(n, c);
  if (positive == 0) return 0.0;
  constexpr int k = 12;
  double sum = 0.0;
  const double dt = (c.theta_1 - c.theta_0) / k, dp = (c.phi_1 - c.phi_0) / k;
  for (int a = 0; a < k; ++a) {
    const double t0 = c.theta_0 + a * dt;
    const double w = dp * (std::cos(t0) - std::cos(t0 + dt));
    for (int b = 0; b < k; ++b) {
      sum += w * std::max(0.0, glm::dot(n, DirectionFromZenithAzimuth(t0 + 0.5 * dt, c.phi_0 + (b + 0.5) * dp)));
    }
  }
  return sum;
}

std::vector<Cell> BaseCells(const IrradianceSettings& s) {
  std::vector<Cell> cells;
  if (s.patches == nullptr) {
    const double d_theta = 0.5 * std::numbers::pi / s.zenith_steps;
    const double d_phi = 2.0 * std::numbers::pi / s.azimuth_steps;
    for (int i = 0; i < s.zenith_steps; ++i) {
      for (int j = 0; j < s.azimuth_steps; ++j) cells.push_back({i * d_theta, (i + 1) * d_theta, j * d_phi, (j + 1) * d_phi, -1});
    }
    return cells;
  }
  const int k = s.patch_samples;
  const std::vector<SkyPatches::Patch>& patches = s.patches->patches();
  for (std::size_t p = 0; p < patches.size(); ++p) {
    const SkyPatches::Patch& patch = patches[p];
    const double theta_top = glm::radians(90.0 - patch.altitude_1_deg);
    const double theta_bottom = glm::radians(90.0 - patch.altitude_0_deg);
    const double phi_0 = glm::radians(patch.azimuth_0_deg);
    const double phi_1 = glm::radians(patch.azimuth_1_deg);
    const int sectors = patch.azimuth_1_deg - patch.azimuth_0_deg >= 360.0 ? 6 * k : k;  // the polar cap
    // The sky brightens steeply towards the horizon: the patches below 12 degrees get three times
    // the rows (four times).
    const int rows = patch.altitude_0_deg < 12.0 - 1e-9 ? 4 * k : k;
    for (int a = 0; a < rows; ++a) {
      for (int b = 0; b < sectors; ++b) {
        cells.push_back({theta_top + a * (theta_bottom - theta_top) / rows, theta_top + (a + 1) * (theta_bottom - theta_top) / rows,
                         phi_0 + b * (phi_1 - phi_0) / sectors, phi_0 + (b + 1) * (phi_1 - phi_0) / sectors,
                         static_cast<int>(p)});
      }
    }
  }
  return cells;
}

SkySamples HemisphereSamples(const glm::dvec3& sun, const IrradianceSettings& s) {
  SkySamples out;
  const double cone = glm::radians(s.circumsolar_half_angle_deg);
  const double cos_cone = cone > 0.0 ? std::cos(cone) : 2.0;
  // The aureole is steep within a few degrees of the sun whether or not a cone is asked for.
  const double refine = std::max(cone, glm::radians(5.0));
  const auto add = [&](double theta_0, double theta_1, double phi_0, double phi_1, int patch) {
    const glm::dvec3 v = DirectionFromZenithAzimuth(0.5 * (theta_0 + theta_1), 0.5 * (phi_0 + phi_1));
    const double solid_angle = (phi_1 - phi_0) * (std::cos(theta_0) - std::cos(theta_1));
    out.views.push_back(v);
    out.solid_angles.push_back(solid_angle);
    out.patch.push_back(patch);
    out.cells.push_back({theta_0, theta_1, phi_0, phi_1, patch});
    // The share of the cell inside the cone: 0 or 1 away from its edge, else by 8 x 8 sub-cells.
    double inside = 0.0;
    if (cone > 0.0) {
      const double reach = 0.5 * std::hypot(theta_1 - theta_0, std::sin(std::min(theta_1, 0.5 * std::numbers::pi)) * (phi_1 - phi_0));
      const double from_sun = std::acos(std::clamp(glm::dot(v, sun), -1.0, 1.0));
      if (from_sun + reach <= cone) {
        inside = 1.0;
      } else if (from_sun - reach < cone) {
        constexpr int k = 8;
        const double dt = (theta_1 - theta_0) / k, dp = (phi_1 - phi_0) / k;
        for (int a = 0; a < k; ++a) {
          const double t0 = theta_0 + a * dt;
          for (int b = 0; b < k; ++b) {
            if (glm::dot(DirectionFromZenithAzimuth(t0 + 0.5 * dt, phi_0 + (b + 0.5) * dp), sun) >= cos_cone) {
              inside += dp * (std::cos(t0) - std::cos(t0 + dt));
            }
          }
        }
        inside /= solid_angle;
      }
    }
    out.circumsolar.push_back(inside);
  };
  const int n = s.circumsolar_subdivisions;
  for (const Cell& c : BaseCells(s)) {
    const double widest = std::sin(std::min(c.theta_1, 0.5 * std::numbers::pi));
    const double reach = 0.5 * std::hypot(c.theta_1 - c.theta_0, widest * (c.phi_1 - c.phi_0));  // centre to corner, at most
    const glm::dvec3 centre = DirectionFromZenithAzimuth(0.5 * (c.theta_0 + c.theta_1), 0.5 * (c.phi_0 + c.phi_1));
    const double from_sun = std::acos(std::clamp(glm::dot(centre, sun), -1.0, 1.0));
    if (n > 1 && from_sun - reach < refine) {
      const double d_theta = (c.theta_1 - c.theta_0) / n;
      const double d_phi = (c.phi_1 - c.phi_0) / n;
      for (int a = 0; a < n; ++a) {
        for (int b = 0; b < n; ++b) {
          add(c.theta_0 + a * d_theta, c.theta_0 + (a + 1) * d_theta, c.phi_0 + b * d_phi, c.phi_0 + (b + 1) * d_phi,
              c.patch);
        }
      }
    } else {
      add(c.theta_0, c.theta_1, c.phi_0, c.phi_1, c.patch);
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
  CheckRange(settings.patch_samples, 1, 16, "the samples per patch side");
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
      const double w = scale * ClampedCosineIntegral(normal, samples.cells[k]);
      if (w <= 0.0) continue;
      const double in_cone = samples.circumsolar[k];
      for (std::size_t c = 0; c < n; ++c) {
        e.circumsolar[c] += in_cone * w * radiance[k * n + c];
        e.sky_diffuse[c] += (1.0 - in_cone) * w * radiance[k * n + c];
      }
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

  if (settings.patches != nullptr) {
    // Each patch's mean radiance: its samples' integral over its solid angle.
    const std::size_t count = settings.patches->count();
    result.patch_radiance.assign(count * n, 0.0);
    for (std::size_t k = 0; k < samples.views.size(); ++k) {
      const std::size_t p = static_cast<std::size_t>(samples.patch[k]);
      for (std::size_t c = 0; c < n; ++c) result.patch_radiance[p * n + c] += scale * samples.solid_angles[k] * radiance[k * n + c];
    }
    for (std::size_t p = 0; p < count; ++p) {
      for (std::size_t c = 0; c < n; ++c) result.patch_radiance[p * n + c] /= settings.patches->patches()[p].solid_angle_sr;
    }
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
