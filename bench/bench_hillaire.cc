// Benchmarks of the `hillaire` model on the "earth" preset, through the public API only.
//
// The table passes are timed inside the model (PassTimings, "every parallel pass has a name and a
// timer"): the LUT benchmarks rerun Model::Precompute and report the named pass's own time as
// manual time, so the other passes of Precompute do not count. The per-view sky-view table and
// the frame are timed from outside in wall-clock time (the work runs on oneTBB threads, so the
// main thread's CPU time would mean nothing).
//
// To run: atmo_bench --benchmark_min_time=0.05 [--benchmark_filter=Lut]
#include <memory>
#include <string>

#include <benchmark/benchmark.h>

#include "atmo/error.h"
#include "atmo/model.h"
#include "atmo/parameters.h"
#include "atmo/render.h"

namespace {

// Sun at 30 degrees elevation in the south, the view every benchmark uses.
constexpr double kSunElevationDeg = 30.0;
constexpr double kSunAzimuthDeg = 180.0;

// The model, created (and precomputed) once for all benchmarks; null if creation failed, with
// the reason in *error.
atmo::Model* EarthModel(std::string* error) {
  static std::string creation_error;
  static const std::unique_ptr<atmo::Model> model = []() -> std::unique_ptr<atmo::Model> {
    try {
      return atmo::CreateModel("hillaire", atmo::Preset("earth"));
    } catch (const std::exception& e) {
      creation_error = e.what();
      return nullptr;
    }
  }();
  *error = creation_error;
  return model.get();
}

// Reruns Precompute and reports the last duration of the pass `pass_name` as the iteration time.
void BenchmarkPrecomputePass(benchmark::State& state, const char* pass_name) {
  std::string error;
  atmo::Model* model = EarthModel(&error);
  if (model == nullptr) {
    state.SkipWithError(error.c_str());
    return;
  }
  for (auto _ : state) {
    model->Precompute();
    const double ms = model->timings().LastMs(pass_name);
    if (ms < 0.0) {
      state.SkipWithError((std::string("the model has no pass named ") + pass_name).c_str());
      break;
    }
    state.SetIterationTime(ms / 1000.0);
  }
}

void BM_TransmittanceLut(benchmark::State& state) { BenchmarkPrecomputePass(state, "transmittance_lut"); }
BENCHMARK(BM_TransmittanceLut)->UseManualTime()->Unit(benchmark::kMillisecond);

void BM_MultiScatteringLut(benchmark::State& state) { BenchmarkPrecomputePass(state, "multiple_scattering_lut"); }
BENCHMARK(BM_MultiScatteringLut)->UseManualTime()->Unit(benchmark::kMillisecond);

// Model::View builds the per-view sky-view table (and little else).
void BM_SkyViewLut(benchmark::State& state) {
  std::string error;
  const atmo::Model* model = EarthModel(&error);
  if (model == nullptr) {
    state.SkipWithError(error.c_str());
    return;
  }
  const glm::dvec3 sun = atmo::SunDirection(kSunElevationDeg, kSunAzimuthDeg);
  for (auto _ : state) {
    std::unique_ptr<atmo::SkyView> view = model->View(0.0, sun);
    benchmark::DoNotOptimize(view.get());
  }
}
BENCHMARK(BM_SkyViewLut)->UseRealTime()->Unit(benchmark::kMillisecond);

// Everything a new frame with new parameters needs before shading: all tables.
void BM_AllLuts(benchmark::State& state) {
  std::string error;
  atmo::Model* model = EarthModel(&error);
  if (model == nullptr) {
    state.SkipWithError(error.c_str());
    return;
  }
  const glm::dvec3 sun = atmo::SunDirection(kSunElevationDeg, kSunAzimuthDeg);
  for (auto _ : state) {
    model->Precompute();
    std::unique_ptr<atmo::SkyView> view = model->View(0.0, sun);
    benchmark::DoNotOptimize(view.get());
  }
}
BENCHMARK(BM_AllLuts)->UseRealTime()->Unit(benchmark::kMillisecond);

// A full-HD perspective frame from the ground, from a prepared view: the frame pass alone (the
// sky-view table it reads is BM_SkyViewLut).
void BM_Frame1920x1080(benchmark::State& state) {
  std::string error;
  const atmo::Model* model = EarthModel(&error);
  if (model == nullptr) {
    state.SkipWithError(error.c_str());
    return;
  }
  atmo::RenderSettings settings;
  settings.camera.kind = atmo::CameraKind::kPerspective;
  settings.camera.width = 1920;
  settings.camera.height = 1080;
  settings.camera.fov_deg = 90.0;
  settings.camera.yaw_deg = kSunAzimuthDeg;
  settings.camera.pitch_deg = 10.0;
  settings.sun_elevation_deg = kSunElevationDeg;
  settings.sun_azimuth_deg = kSunAzimuthDeg;
  const std::unique_ptr<atmo::SkyView> view =
      model->View(0.0, atmo::SunDirection(settings.sun_elevation_deg, settings.sun_azimuth_deg));
  for (auto _ : state) {
    atmo::Image image =
        atmo::RenderView(*view, settings.camera, settings.terms, model->parameters().solar_irradiance);
    benchmark::DoNotOptimize(image.pixels.data());
  }
}
BENCHMARK(BM_Frame1920x1080)->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace
