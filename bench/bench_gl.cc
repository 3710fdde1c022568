// Benchmarks of the GL backend (gl_f32_rgb): model hillaire's passes and frame on the "earth"
// preset, and the elek table on "atmosphere-plus", each pass timed on the GPU (gl::GpuPassTimer:
// GL_TIME_ELAPSED, or dispatch to glFinish on llvmpipe) and reported as manual time. One context
// and one HillaireGl serve all iterations; programs are compiled before the first timed one.
// Without a GL context the benchmarks report an error and the others run on.
//
// To run: atmo_bench --benchmark_filter=Gl --benchmark_min_time=0.05
#include <memory>
#include <string>

#include <benchmark/benchmark.h>

#include "atmo/error.h"
#include "atmo/parameters.h"
#include "atmo/render.h"
#include "cpu/camera.h"
#include "gl/context.h"
#include "gl/elek_gl.h"
#include "gl/hillaire_gl.h"
#include "physics/shared_parameters.h"

namespace {

// The context and hillaire's GPU tables, made once; null with the reason in `error` when no
// context can be made.
struct GlState {
  std::unique_ptr<atmo::gl::Context> context;
  std::unique_ptr<atmo::gl::HillaireGl> sky;
  std::string error;
};

GlState& GetGlState() {
  static GlState state = [] {
    GlState s;
    try {
      s.context = std::make_unique<atmo::gl::Context>();
      s.sky = std::make_unique<atmo::gl::HillaireGl>(*s.context, atmo::Preset("earth"), atmo::HillaireSettings{});
    } catch (const std::exception& e) {
      s.error = e.what();
    }
    return s;
  }();
  return state;
}

// The frame of `atmo bench`: perspective, 90 degrees, towards the sun at 30 degrees elevation.
atmo::Camera BenchCamera() { return {atmo::CameraKind::kPerspective, 1920, 1080, 90.0, 180.0, 10.0}; }

// Runs every hillaire pass (tables, view, frame) and reports the pass `pass_name`'s GPU time.
void BenchmarkHillaireGlPass(benchmark::State& state, const std::string& pass_name) {
  GlState& gl = GetGlState();
  if (gl.sky == nullptr) {
    state.SkipWithError(gl.error.c_str());
    return;
  }
  const glm::dvec3 sun = atmo::SunDirection(30.0, 180.0);
  const atmo::shared::CameraParameters camera = atmo::ToSharedCamera(BenchCamera());
  const atmo::RadianceTerms terms{true, true};
  const auto run = [&](atmo::PassTimings* timings) {
    gl.sky->Precompute(timings);
    gl.sky->SetView(0.0, sun, terms.ground, timings);
    gl.sky->RenderFrame(camera, terms, timings);
  };
  run(nullptr);  // compiles the programs
  for (auto _ : state) {
    atmo::PassTimings timings;
    run(&timings);
    double ms = 0.0;
    if (pass_name == "all_luts") {
      for (const atmo::PassTiming& pass : timings.entries()) {
        if (pass.name.size() > 4 && pass.name.compare(pass.name.size() - 4, 4, "_lut") == 0) ms += pass.last_ms;
      }
    } else {
      ms = timings.LastMs(pass_name);
    }
    state.SetIterationTime(ms / 1000.0);
  }
  state.SetLabel(gl.context->renderer());
}

void BM_GlTransmittanceLut(benchmark::State& state) { BenchmarkHillaireGlPass(state, "transmittance_lut"); }
BENCHMARK(BM_GlTransmittanceLut)->UseManualTime()->Unit(benchmark::kMillisecond);

void BM_GlMultiScatteringLut(benchmark::State& state) { BenchmarkHillaireGlPass(state, "multiple_scattering_lut"); }
BENCHMARK(BM_GlMultiScatteringLut)->UseManualTime()->Unit(benchmark::kMillisecond);

void BM_GlSkyViewLut(benchmark::State& state) { BenchmarkHillaireGlPass(state, "sky_view_lut"); }
BENCHMARK(BM_GlSkyViewLut)->UseManualTime()->Unit(benchmark::kMillisecond);

// transmittance, multiple scattering, ground irradiance, sky view and ground view.
void BM_GlAllLuts(benchmark::State& state) { BenchmarkHillaireGlPass(state, "all_luts"); }
BENCHMARK(BM_GlAllLuts)->UseManualTime()->Unit(benchmark::kMillisecond);

void BM_GlFrame1920x1080(benchmark::State& state) { BenchmarkHillaireGlPass(state, "frame_1920x1080"); }
BENCHMARK(BM_GlFrame1920x1080)->UseManualTime()->Unit(benchmark::kMillisecond);

// The elek table of the seed's size with K = 4 on the GPU (every pass; no read-back).
void BM_GlElekTable(benchmark::State& state) {
  GlState& gl = GetGlState();
  if (gl.context == nullptr) {
    state.SkipWithError(gl.error.c_str());
    return;
  }
  const atmo::AtmosphereParameters parameters = atmo::Preset("atmosphere-plus");
  const atmo::ElekSettings settings;  // 32 x 256 x 32, K = 4
  const atmo::shared::AtmosphereParameters km = atmo::ToSharedParameters(parameters, 0, 1000.0);
  atmo::gl::ComputeElekTablesGl(*gl.context, km, settings);  // compiles the programs
  for (auto _ : state) {
    atmo::PassTimings timings;
    atmo::gl::ComputeElekTablesGl(*gl.context, km, settings, &timings);
    double ms = 0.0;
    for (const atmo::PassTiming& pass : timings.entries()) {
      if (pass.name.size() > 4 && pass.name.compare(pass.name.size() - 4, 4, "_lut") == 0) ms += pass.last_ms;
    }
    state.SetIterationTime(ms / 1000.0);
  }
  state.SetLabel(gl.context->renderer());
}
BENCHMARK(BM_GlElekTable)->UseManualTime()->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace
