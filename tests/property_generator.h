// The random atmospheres and queries of the property tests (tests/property_test.cc on the CPU
// models, tests/gl_property_test.cc on the GL backend): one generator, so that both backends are
// checked over the same parameter box.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <random>
#include <vector>

#include "atmo/model.h"
#include "atmo/parameters.h"

namespace atmo::testing {

// ATMO_PROPERTY_SCALE multiplies the atmosphere counts (1 in CI).
inline int Scale() {
  const char* text = std::getenv("ATMO_PROPERTY_SCALE");
  const int scale = text == nullptr ? 1 : std::atoi(text);
  return scale < 1 ? 1 : scale;
}

inline double LogUniform(std::mt19937_64& rng, double lo, double hi) {
  return std::exp(std::uniform_real_distribution<double>(std::log(lo), std::log(hi))(rng));
}

// A random spherical atmosphere inside the documented bounds (docs/reliability.md): radii from a
// 1 km rock to 1e9 m, thickness 1e-4..1 radii, coefficients over 10 decades, scale heights
// relative to the thickness, any albedo and g in (-0.999, 0.999).
inline AtmosphereParameters RandomAtmosphere(std::mt19937_64& rng) {
  AtmosphereParameters p = Preset("earth");
  p.name = "random";
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  p.ground_radius_m = LogUniform(rng, 1e3, 1e9);
  const double thickness = p.ground_radius_m * LogUniform(rng, 1e-4, 1.0);
  p.top_radius_m = p.ground_radius_m + thickness;
  for (Medium* m : {&p.rayleigh, &p.mie}) {
    for (int c = 0; c < 3; ++c) {
      m->scattering_per_m[c] = unit(rng) < 0.1 ? 0.0 : LogUniform(rng, 1e-12, 1e-2);
      m->absorption_per_m[c] = unit(rng) < 0.3 ? 0.0 : LogUniform(rng, 1e-12, 1e-2);
    }
    m->density = DensityProfile::Exponential(thickness * LogUniform(rng, 1e-3, 1.0));
  }
  for (int c = 0; c < 3; ++c) p.ozone.absorption_per_m[c] = unit(rng) < 0.5 ? 0.0 : LogUniform(rng, 1e-12, 1e-4);
  p.ozone.density = DensityProfile::Tent(0.1 * thickness, 0.25 * thickness, 0.4 * thickness);
  p.mie.phase_g = std::uniform_real_distribution<double>(-0.999, 0.999)(rng);
  p.mie.phase = unit(rng) < 0.5 ? PhaseFunction::kCornetteShanks : PhaseFunction::kHenyeyGreenstein;
  for (int c = 0; c < 3; ++c) p.ground_albedo[c] = unit(rng);
  Validate(p);
  return p;
}

// Random queries of one atmosphere: altitudes from the ground to 1000 km (and exactly at the
// top), views exactly horizontal, grazing (within 1e-6 of the horizon and of the ground's
// tangent), straight up and down, and uniform; suns above and below the horizon.
struct Query {
  double altitude_m;
  glm::dvec3 sun;
  glm::dvec3 view;
};

// A random view direction of an observer at `altitude_m` (the view part of RandomQueries).
inline glm::dvec3 RandomView(std::mt19937_64& rng, const AtmosphereParameters& p, double altitude_m) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double r = p.ground_radius_m + altitude_m;
  const double horizon = std::acos(-std::sqrt(std::max(0.0, 1.0 - (p.ground_radius_m / r) * (p.ground_radius_m / r))));
  const double kind = unit(rng);
  double zenith;
  if (kind < 0.15) zenith = 0.5 * M_PI;                                // exactly horizontal
  else if (kind < 0.3) zenith = horizon + (unit(rng) - 0.5) * 2e-6;   // grazing the ground
  else if (kind < 0.35) zenith = 0.0;
  else if (kind < 0.4) zenith = M_PI;
  else zenith = std::acos(std::uniform_real_distribution<double>(-1.0, 1.0)(rng));
  return DirectionFromZenithAzimuth(std::clamp(zenith, 0.0, M_PI), 2.0 * M_PI * unit(rng));
}

// A random observer altitude and sun of one atmosphere (the observer part of RandomQueries).
inline void RandomObserver(std::mt19937_64& rng, const AtmosphereParameters& p, double& altitude_m, glm::dvec3& sun) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double pick = unit(rng);
  altitude_m = pick < 0.2 ? 0.0 : pick < 0.3 ? p.top_radius_m - p.ground_radius_m : LogUniform(rng, 1.0, 1e6);
  const double sun_zenith = std::acos(std::uniform_real_distribution<double>(-1.0, 1.0)(rng));
  sun = DirectionFromZenithAzimuth(sun_zenith, 0.0);
}

inline std::vector<Query> RandomQueries(std::mt19937_64& rng, const AtmosphereParameters& p, int count) {
  std::vector<Query> queries;
  for (int i = 0; i < count; ++i) {
    Query q;
    RandomObserver(rng, p, q.altitude_m, q.sun);
    q.view = RandomView(rng, p, q.altitude_m);
    queries.push_back(q);
  }
  return queries;
}

}  // namespace atmo::testing
