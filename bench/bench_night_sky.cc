// The night sky's cost (include/atmo/night_sky.h): its per-view tables, and a 1280 x 720 frame of
// the default render (hillaire, earth, folded into linear sRGB as `atmo render` does) with and
// without it; the target is at most 1.3 times the frame without it.
#include <memory>
#include <vector>

#include <benchmark/benchmark.h>

#include "atmo/colour.h"
#include "atmo/model.h"
#include "atmo/night_sky.h"
#include "atmo/render.h"

namespace {

constexpr double kSunElevationDeg = -30.0;

const atmo::Model& Earth() {
  static const std::unique_ptr<atmo::Model> model = atmo::CreateModel("hillaire", atmo::Preset("earth"));
  return *model;
}

void BM_NightSkyTables(benchmark::State& state) {
  const atmo::AtmosphereParameters p = atmo::Preset(state.range(0) == 0 ? "earth" : "earth-spectral");
  for (auto _ : state) {
    const atmo::NightSky night(p, 0.0, atmo::SunDirection(kSunElevationDeg, 180.0));
    benchmark::DoNotOptimize(night.airglow_zenith().data());
  }
}
BENCHMARK(BM_NightSkyTables)->Arg(0)->Arg(1)->UseRealTime()->Unit(benchmark::kMillisecond);

// Arg 1: with the night sky; 0: without; 2: with its airglow only.
void BM_NightFrame1280x720(benchmark::State& state) {
  const atmo::Model& model = Earth();
  const glm::dvec3 sun = atmo::SunDirection(kSunElevationDeg, 180.0);
  const std::unique_ptr<atmo::SkyView> view = model.View(0.0, sun);
  atmo::AtmosphereParameters p = model.parameters();
  if (state.range(0) == 2) p.night_sky.zodiacal_scale = p.night_sky.starlight_scale = 0.0;
  const atmo::NightSky night(p, 0.0, sun);
  atmo::Camera camera;
  camera.width = 1280;
  camera.height = 720;
  camera.yaw_deg = 180.0;
  camera.pitch_deg = 10.0;
  atmo::RadianceTerms terms;
  if (state.range(0) >= 1) terms.night_sky = &night;
  const atmo::SpectralConversion convert(model.parameters().wavelengths_nm);
  const std::vector<glm::vec3> weights = atmo::ColourWeights(convert, atmo::ImageColour::kLinearSrgb);
  atmo::Image image;
  for (auto _ : state) {
    atmo::RenderViewFolded(*view, camera, terms, weights, image);
    benchmark::DoNotOptimize(image.pixels.data());
  }
}
BENCHMARK(BM_NightFrame1280x720)->Arg(0)->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace
