// The reference the image tests of the sun disc compare against (sun_disc_test.cc,
// cubemap_test.cc): the transmitted direct irradiance over the disc, integrated independently of
// any camera.
#pragma once

#include <cmath>
#include <numbers>
#include <vector>

#include <glm/glm.hpp>

#include "atmo/model.h"

namespace atmo::testing {

// int L T dOmega over the disc of `sky`, per channel, by the midpoint rule on a polar grid uniform
// in solid angle (t = cos(theta) and the azimuth about the sun).
inline std::vector<double> DiscIrradiance(const SkyView& sky, int rings = 300, int sectors = 300) {
  constexpr double kPi = std::numbers::pi;
  const glm::dvec3 s = sky.sun_direction();
  const glm::dvec3 e1 = glm::normalize(glm::cross(s, glm::dvec3(0.3, 0.4, 0.866)));
  const glm::dvec3 e2 = glm::cross(s, e1);
  const double cos_alpha = std::cos(sky.sun_angular_radius_rad());
  const double cell = 2.0 * kPi * (1.0 - cos_alpha) / (rings * sectors);
  const std::size_t n = sky.channel_count();
  std::vector<double> sum(n, 0.0), l(n);
  for (int i = 0; i < rings; ++i) {
    const double t = cos_alpha + (1.0 - cos_alpha) * (i + 0.5) / rings;
    for (int j = 0; j < sectors; ++j) {
      const double phi = 2.0 * kPi * (j + 0.5) / sectors;
      sky.SunDiscRadiance(t * s + std::sqrt(1.0 - t * t) * (std::cos(phi) * e1 + std::sin(phi) * e2), l);
      for (std::size_t c = 0; c < n; ++c) sum[c] += l[c] * cell;
    }
  }
  return sum;
}

}  // namespace atmo::testing
