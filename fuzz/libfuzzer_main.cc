// The libFuzzer entry of one fuzz target (fuzz_targets.h), chosen by ATMO_FUZZ_TARGET at compile
// time (fuzz/CMakeLists.txt builds one binary per target).
#include <cstddef>
#include <cstdint>

#include "fuzz_targets.h"

namespace {

constexpr int (*FindTarget(std::string_view name))(const std::uint8_t*, std::size_t) {
  for (const atmo::fuzz::FuzzTarget& target : atmo::fuzz::kFuzzTargets) {
    if (target.name == name) return target.run;
  }
  return nullptr;
}

constexpr auto kRun = FindTarget(ATMO_FUZZ_TARGET);
static_assert(kRun != nullptr, "ATMO_FUZZ_TARGET names no entry of atmo::fuzz::kFuzzTargets");

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) { return kRun(data, size); }
