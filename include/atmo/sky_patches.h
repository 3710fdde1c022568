// The sky patches of annual daylight simulation: Tregenza's 145 and Reinhart's subdivisions of
// them (577, 2305, ...), in the order and orientation of Radiance's reinhart.cal and gendaymtx.
//
// To use it:
//   atmo::SkyPatches p = atmo::SkyPatches::Reinhart(1);   // Tregenza: 145 patches
//   int i = p.Index(direction);                           // 0..144, -1 below the horizon
//
// Geometry (docs/daylighting.md): with MF the subdivision, rows of altitude alpha = 90 / (7 MF +
// 0.5) degrees from the horizon up, row r holding MF times Tregenza's count of row floor(r / MF)
// (30, 30, 24, 24, 18, 12, 6) patches, and a polar cap of half a row's height above them. In each
// row the first patch is centred on north and the numbers grow towards the east. Radiance's sky
// matrices put the ground first (row 0) and these patches after it (rows 1..count()).
#pragma once

#include <vector>

#include <glm/glm.hpp>

namespace atmo {

class SkyPatches {
 public:
  struct Patch {
    double altitude_0_deg;
    double altitude_1_deg;
    double azimuth_0_deg;  // compass; the first patch of a row starts west of north (negative)
    double azimuth_1_deg;
    double solid_angle_sr;
    glm::dvec3 centre;  // unit, x east, y north, z up
  };

  // MF in [1, 16]. Throws atmo::Error outside.
  static SkyPatches Reinhart(int subdivision);

  int subdivision() const { return subdivision_; }
  std::size_t count() const { return patches_.size(); }
  const std::vector<Patch>& patches() const { return patches_; }
  // The patch that holds `direction` (need not be unit); -1 below the horizon (z < 0).
  int Index(const glm::dvec3& direction) const;

 private:
  int subdivision_ = 1;
  double row_deg_ = 12.0;
  std::vector<Patch> patches_;
  std::vector<int> row_start_;  // first patch of each row, and count() at the end
};

}  // namespace atmo
