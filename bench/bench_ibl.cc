// Benchmarks of the image-based lighting passes (atmo/ibl.h) from a 256-texel sky cube map:
// the L2 spherical harmonics, the 32-texel irradiance cube map, the 6-level specular chain, and
// all three together (the target: <= 50 ms on 2 cores). Wall-clock time: the work runs on oneTBB
// threads. Pin the core count with taskset (oneTBB follows the process's affinity mask):
//   taskset -c 0,1 build/bench/atmo_bench --benchmark_filter=Ibl --benchmark_min_time=0.5s
#include <memory>

#include <benchmark/benchmark.h>

#include "atmo/colour.h"
#include "atmo/cubemap.h"
#include "atmo/ibl.h"
#include "atmo/model.h"
#include "atmo/parameters.h"

namespace {

// The clear-sky cube (hillaire, earth, sun at 30 degrees), linear sRGB in cd/m^2 with the disc.
const atmo::Cubemap& SkyCube() {
  static const atmo::Cubemap cube = [] {
    const auto model = atmo::CreateModel("hillaire", atmo::Preset("earth"));
    const auto sky = model->View(0.0, atmo::SunDirection(30.0, 180.0));
    const atmo::SpectralConversion convert(model->parameters().wavelengths_nm);
    return atmo::RenderCubemapFolded(*sky, 256, {}, atmo::ColourWeights(convert, atmo::ImageColour::kLinearSrgb));
  }();
  return cube;
}

void BM_IblSphericalHarmonics(benchmark::State& state) {
  const atmo::Cubemap& cube = SkyCube();
  for (auto _ : state) benchmark::DoNotOptimize(atmo::ProjectSphericalHarmonics(cube));
}
BENCHMARK(BM_IblSphericalHarmonics)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_IblIrradianceCube(benchmark::State& state) {
  const atmo::Cubemap& cube = SkyCube();
  for (auto _ : state) benchmark::DoNotOptimize(atmo::IrradianceCubemap(cube));
}
BENCHMARK(BM_IblIrradianceCube)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_IblSpecularChain(benchmark::State& state) {
  const atmo::Cubemap& cube = SkyCube();
  for (auto _ : state) benchmark::DoNotOptimize(atmo::PrefilterSpecular(cube));
}
BENCHMARK(BM_IblSpecularChain)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_IblAll(benchmark::State& state) {
  const atmo::Cubemap& cube = SkyCube();
  for (auto _ : state) {
    benchmark::DoNotOptimize(atmo::ProjectSphericalHarmonics(cube));
    benchmark::DoNotOptimize(atmo::IrradianceCubemap(cube));
    benchmark::DoNotOptimize(atmo::PrefilterSpecular(cube));
  }
}
BENCHMARK(BM_IblAll)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
