// Tregenza and Reinhart sky patches (include/atmo/sky_patches.h).
#include "atmo/sky_patches.h"

#include <cmath>
#include <numbers>
#include <string>

#include "atmo/error.h"
#include "atmo/model.h"

namespace atmo {

SkyPatches SkyPatches::Reinhart(int subdivision) {
  if (subdivision < 1 || subdivision > 16) {
    throw Error("the sky subdivision (Reinhart's MF) must be in [1, 16], got " + std::to_string(subdivision));
  }
  static constexpr int kTregenzaRow[] = {30, 30, 24, 24, 18, 12, 6};
  SkyPatches out;
  out.subdivision_ = subdivision;
  const int rows = 7 * subdivision;
  out.row_deg_ = 90.0 / (rows + 0.5);
  for (int r = 0; r <= rows; ++r) {
    out.row_start_.push_back(static_cast<int>(out.patches_.size()));
    const bool cap = r == rows;
    const int n = cap ? 1 : subdivision * kTregenzaRow[r / subdivision];
    const double alt_0 = r * out.row_deg_;
    const double alt_1 = cap ? 90.0 : (r + 1) * out.row_deg_;
    const double width = 360.0 / n;
    for (int j = 0; j < n; ++j) {
      Patch p;
      p.altitude_0_deg = alt_0;
      p.altitude_1_deg = alt_1;
      p.azimuth_0_deg = cap ? 0.0 : (j - 0.5) * width;
      p.azimuth_1_deg = cap ? 360.0 : (j + 0.5) * width;
      p.solid_angle_sr = glm::radians(p.azimuth_1_deg - p.azimuth_0_deg) *
                         (std::sin(glm::radians(alt_1)) - std::sin(glm::radians(alt_0)));
      p.centre = cap ? glm::dvec3(0.0, 0.0, 1.0)
                     : DirectionFromZenithAzimuth(glm::radians(90.0 - 0.5 * (alt_0 + alt_1)), glm::radians(j * width));
      out.patches_.push_back(p);
    }
  }
  out.row_start_.push_back(static_cast<int>(out.patches_.size()));
  return out;
}

int SkyPatches::Index(const glm::dvec3& direction) const {
  const double length = glm::length(direction);
  if (!(length > 0.0) || direction.z < 0.0) return -1;
  const double altitude = glm::degrees(std::asin(std::min(1.0, direction.z / length)));
  const int rows = 7 * subdivision_;
  const int r = std::min(static_cast<int>(altitude / row_deg_), rows);
  const int first = row_start_[r];
  const int n = row_start_[r + 1] - first;
  if (n == 1) return first;
  double azimuth = glm::degrees(std::atan2(direction.x, direction.y));
  if (azimuth < 0.0) azimuth += 360.0;
  const int j = static_cast<int>(std::floor(azimuth / (360.0 / n) + 0.5)) % n;
  return first + j;
}

}  // namespace atmo
