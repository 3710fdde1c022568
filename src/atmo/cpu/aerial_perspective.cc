#include "atmo/aerial_perspective.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

#include "atmo/error.h"
#include "atmo/memory.h"
#include "cpu/camera.h"

namespace atmo {

void ValidateAerialPerspectiveSettings(const AerialPerspectiveSettings& settings) {
  for (int side : {settings.width, settings.height, settings.depth}) {
    if (side < 1 || side > 512) throw Error("aerial perspective volume sizes must be in [1, 512]");
  }
  if (!(settings.max_distance_m > 0.0) || !std::isfinite(settings.max_distance_m)) {
    throw Error("aerial perspective max_distance_m must be finite and > 0");
  }
}

AerialPerspectiveVolume ComputeAerialPerspectiveVolume(const SkyView& sky, const Camera& camera,
                                                       const AerialPerspectiveSettings& settings) {
  ValidateCamera(camera);
  ValidateAerialPerspectiveSettings(settings);
  AerialPerspectiveVolume volume;
  volume.settings_ = settings;
  volume.camera_ = camera;
  volume.channel_count_ = sky.channel_count();
  const std::size_t n = volume.channel_count_;
  const std::size_t froxels = static_cast<std::size_t>(settings.width) * settings.height * settings.depth;
  // Radiance and transmittance, one float each per froxel and channel.
  CheckMemory("an aerial-perspective volume of " + std::to_string(settings.width) + "x" +
                  std::to_string(settings.height) + "x" + std::to_string(settings.depth) + " at " + std::to_string(n) +
                  " channels",
              8.0 * static_cast<double>(froxels) * static_cast<double>(n));
  volume.radiance_.assign(froxels * n, 0.0f);
  volume.transmittance_.assign(froxels * n, 1.0f);
  const shared::CameraParameters shared_camera = ToSharedCamera(camera);

  oneapi::tbb::parallel_for(oneapi::tbb::blocked_range<int>(0, settings.height * settings.depth),
                            [&](const oneapi::tbb::blocked_range<int>& range) {
    std::vector<double> radiance(n);
    std::vector<double> transmittance(n);
    for (int yz = range.begin(); yz < range.end(); ++yz) {
      const int y = yz % settings.height;
      const int z = yz / settings.height;
      const double distance = (z + 1.0) / settings.depth * settings.max_distance_m;
      for (int x = 0; x < settings.width; ++x) {
        // Froxel centre in image pixels.
        const shared::vec2 frag((x + 0.5) / settings.width * camera.width, (y + 0.5) / settings.height * camera.height);
        shared::vec3 view;
        if (!shared::GetCameraRayDirection(shared_camera, frag, view)) continue;
        sky.ScatteringAlongSegment(view, distance, radiance, transmittance);
        const std::size_t base = volume.Index(x, y, z) * n;
        for (std::size_t c = 0; c < n; ++c) {
          volume.radiance_[base + c] = static_cast<float>(radiance[c]);
          volume.transmittance_[base + c] = static_cast<float>(transmittance[c]);
        }
      }
    }
  });
  return volume;
}

AerialPerspectiveVolume::AerialPerspectiveVolume(const AerialPerspectiveSettings& settings, const Camera& camera,
                                                 std::size_t channel_count, std::vector<float> radiance,
                                                 std::vector<float> transmittance)
    : settings_(settings),
      camera_(camera),
      channel_count_(channel_count),
      radiance_(std::move(radiance)),
      transmittance_(std::move(transmittance)) {
  const std::size_t values =
      static_cast<std::size_t>(settings.width) * settings.height * settings.depth * channel_count;
  if (radiance_.size() != values || transmittance_.size() != values) {
    throw Error("aerial perspective volume: expected " + std::to_string(values) + " values per quantity");
  }
}

void AerialPerspectiveVolume::Lookup(double px, double py, double distance_m, std::span<double> radiance,
                                     std::span<double> transmittance) const {
  const AerialPerspectiveSettings& s = settings_;
  // Continuous froxel coordinates: froxel centres at integers in x and y; slice z at distance
  // (z + 1) / depth * max, with a virtual slice -1 at the camera (radiance 0, transmittance 1).
  auto taps = [](double f, int size, int& i0, int& i1, double& w) {
    f = shared::ClampToRange(f, 0.0, static_cast<double>(size - 1));  // NaN -> 0, never an index outside
    i0 = static_cast<int>(std::floor(f));
    i1 = std::min(i0 + 1, size - 1);
    w = f - i0;
  };
  int x0, x1, y0, y1;
  double wx, wy;
  taps(px / camera_.width * s.width - 0.5, s.width, x0, x1, wx);
  taps(py / camera_.height * s.height - 0.5, s.height, y0, y1, wy);
  const double fz = shared::ClampToRange(distance_m / s.max_distance_m * s.depth - 1.0, -1.0, s.depth - 1.0);
  const int z0 = static_cast<int>(std::floor(fz));
  const int z1 = std::min(z0 + 1, s.depth - 1);
  const double wz = fz - z0;
  for (std::size_t c = 0; c < channel_count_; ++c) {
    auto sample = [&](const std::vector<float>& data, int z, double camera_value) {
      if (z < 0) return camera_value;
      auto at = [&](int x, int y) { return static_cast<double>(data[Index(x, y, z) * channel_count_ + c]); };
      const double a = at(x0, y0) + (at(x1, y0) - at(x0, y0)) * wx;
      const double b = at(x0, y1) + (at(x1, y1) - at(x0, y1)) * wx;
      return a + (b - a) * wy;
    };
    radiance[c] = sample(radiance_, z0, 0.0) + (sample(radiance_, z1, 0.0) - sample(radiance_, z0, 0.0)) * wz;
    transmittance[c] =
        sample(transmittance_, z0, 1.0) + (sample(transmittance_, z1, 1.0) - sample(transmittance_, z0, 1.0)) * wz;
  }
}

}  // namespace atmo
