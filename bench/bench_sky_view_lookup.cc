// The per-pixel sky-view lookup of a full-HD frame on one thread: the shared double-precision
// path (GetAzimuthFromSun, GetSkyViewTextureUvFromBeta, texture) pixel by pixel, against the
// float row kernel cpu::LookupSkyViewRow. Both read a 192 x 108 table of made-up values (the
// cost does not depend on them) for the view of BM_Frame1920x1080: perspective camera, 90 degrees
// field of view, looking south 10 degrees up, sun 30 degrees up in the south, observer on the ground.
// The counter pixel_time is the time per pixel.
//
// To run: atmo_bench --benchmark_filter=SkyViewLookup
#include <cmath>
#include <vector>

#include <benchmark/benchmark.h>

#include "cpu/sky_view_lookup.h"
#include "shared/shared.h"

namespace {

constexpr int kWidth = 1920;
constexpr int kHeight = 1080;
constexpr double kPi = 3.14159265358979323846;

struct Frame {
  atmo::shared::Texture2D table{192, 108, /*repeat=*/true};
  double beta = 0.0;
  glm::dvec3 sun{0.0};
  std::vector<glm::dvec3> views;  // row-major, as RenderView passes them
  std::vector<float> x, y, z;     // the same, as float rows
};

const Frame& TheFrame() {
  static const Frame frame = [] {
    Frame f;
    for (int j = 0; j < f.table.height; ++j) {
      for (int i = 0; i < f.table.width; ++i) f.table.at(i, j) = glm::vec3(1.0f + 0.01f * i, 1.0f + 0.02f * j, 2.0f);
    }
    atmo::shared::AtmosphereParameters atmosphere{};
    atmosphere.bottom_radius = 6360e3;
    atmosphere.top_radius = 6460e3;
    f.beta = atmo::shared::GetHorizonNadirAngle(atmosphere, atmosphere.bottom_radius);
    const double sun_elevation = 30.0 * kPi / 180.0;
    f.sun = atmo::shared::GetDirectionFromAzimuthElevation(kPi, sun_elevation);
    const atmo::shared::CameraParameters camera = atmo::shared::MakeCameraParameters(
        atmo::shared::kCameraPerspective, kWidth, kHeight, 0.5 * kPi, kPi, 10.0 * kPi / 180.0);
    for (int j = 0; j < kHeight; ++j) {
      for (int i = 0; i < kWidth; ++i) {
        atmo::shared::vec3 v;
        atmo::shared::GetCameraRayDirection(camera, atmo::shared::vec2(i + 0.5, j + 0.5), v);
        f.views.push_back(v);
        f.x.push_back(static_cast<float>(v.x));
        f.y.push_back(static_cast<float>(v.y));
        f.z.push_back(static_cast<float>(v.z));
      }
    }
    return f;
  }();
  return frame;
}

void SetPixelCounter(benchmark::State& state) {
  state.counters["pixel_time"] = benchmark::Counter(
      double(kWidth) * kHeight, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void BM_SkyViewLookupShared(benchmark::State& state) {
  const Frame& f = TheFrame();
  const atmo::shared::ivec2 size = atmo::shared::textureSize(f.table, 0);
  std::vector<float> row(3 * kWidth);
  for (auto _ : state) {
    for (int j = 0; j < kHeight; ++j) {
      for (int i = 0; i < kWidth; ++i) {
        const glm::dvec3& view = f.views[static_cast<std::size_t>(j) * kWidth + i];
        const double azimuth = atmo::shared::GetAzimuthFromSun(view, f.sun);
        const atmo::shared::vec2 uv = atmo::shared::GetSkyViewTextureUvFromBeta(size, f.beta, view.z, azimuth);
        const atmo::shared::vec4 l = atmo::shared::texture(f.table, uv);
        for (int c = 0; c < 3; ++c) row[3 * i + c] = static_cast<float>(l[c]);
      }
      benchmark::DoNotOptimize(row.data());
      benchmark::ClobberMemory();
    }
  }
  SetPixelCounter(state);
}
BENCHMARK(BM_SkyViewLookupShared)->Unit(benchmark::kMillisecond);

void BM_SkyViewLookupRow(benchmark::State& state) {
  const Frame& f = TheFrame();
  const atmo::cpu::SkyViewLookup lookup = atmo::cpu::MakeSkyViewLookup(f.table, f.beta, f.sun);
  std::vector<float> row(3 * kWidth);
  for (auto _ : state) {
    for (int j = 0; j < kHeight; ++j) {
      const std::size_t begin = static_cast<std::size_t>(j) * kWidth;
      atmo::cpu::LookupSkyViewRow(lookup, &f.x[begin], &f.y[begin], &f.z[begin], kWidth, row.data());
      benchmark::DoNotOptimize(row.data());
      benchmark::ClobberMemory();
    }
  }
  SetPixelCounter(state);
}
BENCHMARK(BM_SkyViewLookupRow)->Unit(benchmark::kMillisecond);

}  // namespace
