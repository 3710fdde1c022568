// Benchmarks of the `reference` path tracer on the "earth" preset: observer on the ground, sun
// 45 degrees high, view zenith 60 degrees at 90 degrees azimuth from the sun.
//   BM_ReferencePaths/N      N paths per channel for one query (items/s = paths/s, all threads)
//   BM_ReferenceToTarget     paths doubled from 4096 until standard error / mean <= 0.5% in every
//                            channel (counter "paths": how many it took)
// Wall-clock time (the paths run on oneTBB threads). To run on 2 cores:
//   taskset -c 0,1 build/bench/atmo_bench --benchmark_filter=Reference --benchmark_min_time=0.5
#include <memory>
#include <vector>

#include <benchmark/benchmark.h>
#include <glm/glm.hpp>

#include "atmo/model.h"
#include "atmo/parameters.h"
#include "models/reference_model.h"

namespace {

const glm::dvec3 kSun = atmo::DirectionFromZenithAzimuth(glm::radians(45.0), 0.0);
const glm::dvec3 kView = atmo::DirectionFromZenithAzimuth(glm::radians(60.0), glm::radians(90.0));

void BM_ReferencePaths(benchmark::State& state) {
  const auto model = atmo::CreateModel("reference", atmo::Preset("earth"));
  const auto sky = model->View(0.0, kSun);
  const auto& reference = static_cast<const atmo::ReferenceSkyView&>(*sky);
  const auto paths = static_cast<std::uint64_t>(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(reference.EstimateByOrder(kView, paths));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(paths));
}
BENCHMARK(BM_ReferencePaths)->Arg(65536)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ReferenceToTarget(benchmark::State& state) {
  const auto model = atmo::CreateModel("reference", atmo::Preset("earth"), {{"target_rel_error", "0.005"}});
  const auto sky = model->View(0.0, kSun);
  const auto& reference = static_cast<const atmo::ReferenceSkyView&>(*sky);
  std::uint64_t paths = 0;
  for (auto _ : state) paths = reference.EstimateByOrder(kView).paths;
  state.counters["paths"] = static_cast<double>(paths);
}
BENCHMARK(BM_ReferenceToTarget)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
