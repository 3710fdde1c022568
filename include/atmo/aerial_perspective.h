// Aerial perspective: a froxel volume over a camera's frustum that holds, per channel, the
// in-scattered radiance and the transmittance between the camera and each froxel (Hillaire 2020,
// section 5.4), so that a renderer composites distant geometry with one lookup.
//
// To use it:
//   auto sky = model->View(altitude_m, sun);
//   atmo::AerialPerspectiveVolume ap = atmo::ComputeAerialPerspectiveVolume(*sky, camera);
//   ap.Lookup(pixel_x, pixel_y, distance_m, radiance, transmittance);
//   // shaded = surface * transmittance + radiance
#pragma once

#include <span>
#include <vector>

#include "atmo/model.h"
#include "atmo/render.h"

namespace atmo {

struct AerialPerspectiveSettings {
  int width = 32;                   // froxels across the image
  int height = 32;                  // froxels down the image
  int depth = 32;                   // distance slices
  double max_distance_m = 32000.0;  // slice z ends at (z + 1) / depth * max_distance_m
};

// Throws atmo::Error for sizes outside [1, 512] or a distance that is not finite and > 0.
void ValidateAerialPerspectiveSettings(const AerialPerspectiveSettings& settings);

class AerialPerspectiveVolume {
 public:
  AerialPerspectiveVolume() = default;
  // A volume computed elsewhere (the GL backend): `radiance` and `transmittance` hold
  // channel_count values per froxel, froxel (x, y, z) at x + width (y + height z). Throws
  // atmo::Error when the sizes disagree.
  AerialPerspectiveVolume(const AerialPerspectiveSettings& settings, const Camera& camera, std::size_t channel_count,
                          std::vector<float> radiance, std::vector<float> transmittance);

  // (x, y) in image pixels of the camera (pixel centres at +0.5), distance in metres; trilinear
  // between froxels; between the camera and the first slice, linear from (0 radiance, 1
  // transmittance); beyond max_distance_m clamped to the last slice.
  void Lookup(double x, double y, double distance_m, std::span<double> radiance,
              std::span<double> transmittance) const;

  const AerialPerspectiveSettings& settings() const { return settings_; }
  std::size_t channel_count() const { return channel_count_; }
  // Froxel values: channel c of froxel (x, y, z).
  double RadianceAt(int x, int y, int z, std::size_t c) const { return radiance_[Index(x, y, z) * channel_count_ + c]; }
  double TransmittanceAt(int x, int y, int z, std::size_t c) const {
    return transmittance_[Index(x, y, z) * channel_count_ + c];
  }

 private:
  friend AerialPerspectiveVolume ComputeAerialPerspectiveVolume(const SkyView&, const Camera&,
                                                                const AerialPerspectiveSettings&);
  std::size_t Index(int x, int y, int z) const {
    return static_cast<std::size_t>(x) + static_cast<std::size_t>(settings_.width) * (y + static_cast<std::size_t>(settings_.height) * z);
  }
  AerialPerspectiveSettings settings_;
  Camera camera_;
  std::size_t channel_count_ = 0;
  std::vector<float> radiance_;
  std::vector<float> transmittance_;
};

// Fills the volume through SkyView::ScatteringAlongSegment, in parallel. Throws atmo::Error for
// invalid settings (sizes outside [1, 512], a non-positive distance) or a model without aerial
// perspective.
AerialPerspectiveVolume ComputeAerialPerspectiveVolume(const SkyView& sky, const Camera& camera,
                                                       const AerialPerspectiveSettings& settings = {});

}  // namespace atmo
