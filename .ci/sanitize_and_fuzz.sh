#!/usr/bin/env bash
# The second half of .ci/run: builds build-asan with clang (-DATMO_FUZZ=ON, which sanitizes with
# address,undefined + float-cast-overflow and adds libFuzzer's coverage), runs every test of it
# under ASan/UBSan (LeakSanitizer on, Mesa's driver leaks suppressed by .ci/lsan.supp), then
# scripts/fuzz.sh for SECONDS per target in the same build.
# Usage: .ci/sanitize_and_fuzz.sh [SECONDS]     (default 60)
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"
start=$(date +%s)
# Left out of this build, each tested by the first half of .ci/run: the Python module (an
# instrumented extension cannot load into an uninstrumented interpreter without preloading the
# ASan runtime), the install and consumer-project tests (they build outside projects against the
# prefix), the viewer and the benchmarks.
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=clang++ -DATMO_FUZZ=ON \
  -DATMO_BUILD_BENCHMARKS=OFF -DATMO_PYTHON=OFF -DATMO_INSTALL=OFF -DATMO_BUILD_VIEWER=OFF >/dev/null
cmake --build build-asan -j2
echo "ci: sanitizer build in $(( $(date +%s) - start )) s"

export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
export LSAN_OPTIONS="suppressions=$PWD/.ci/lsan.supp:print_suppressions=0"
start=$(date +%s)
# Mesa leaves allocations behind in modules it unloads before exit (the GLFW/GLX window: 112
# bytes; the headless EGL context: 128 bytes from a realloc), whose stacks end in "<unknown
# module>", which no suppression can name. So the tests labelled gl (every test that makes a GL
# context) run with ASan and UBSan but without leak detection, and every other test with it. The
# tests labelled web build and run WebAssembly, which the sanitizers do not see: they run in the
# plain build only.
#
# Nine tests repeat one numeric loop for minutes under the sanitizers (each 75-450 s of a 2-core
# machine here, against 3-30 s in the plain build, which runs them): shorter tests and the fuzzers
# run the same code under ASan, so they are left out of this stage to keep CI inside its limit.
# (The last two: the moonlit sky at Krisciunas and Schaefer's site, 188 s, and every model on a
# tabulated phase function, 77 s; PhaseTable's other tests and Source4dTables cover that code.)
heavy='^(Folder\.ShardsAndRerunsGiveTheSerialRunsBytes|Folder\.CalibratedHoursReproduceTheirMeasurements'
heavy+='|Source4dModel\.SunZenithInterpolationIsSmoothAcrossTheKnots|Source4dModel\.GroundSkyIrradianceMatchesTheReferenceFlux'
heavy+='|WaterVapor\.EveryModelAbsorbsItsOpticalDepth|StandardPresets\.ReferenceAndSource4dAgreeOnUsStandardAndAHazySky'
heavy+='|Moon\.MoonlitSkyAtKrisciunasAndSchaefersSite|PhaseTable\.EveryModelAgreesWithTheAnalyticPhaseItTabulates'
# The README's examples (DocsTest.EveryReadmeExampleRuns): since source4d on us-standard became the
# default, a dozen of them compute spectral tables (90 s in the plain build).
heavy+='|DocsTest\.EveryReadmeExampleRuns)$'
ctest --test-dir build-asan --output-on-failure -j2 -LE '^(gl|web)$' -E "$heavy"
ASAN_OPTIONS="$ASAN_OPTIONS:detect_leaks=0" ctest --test-dir build-asan --output-on-failure -j2 -L '^gl$'
# The threaded WebAssembly build's loops (web/shim) under ThreadSanitizer, natively on four threads,
# repeated: a race in the pool's hand-over between loops shows within a few repeats. Without
# address-space randomisation (setarch -R): clang 14's ThreadSanitizer refuses the layouts of
# kernels with a large mmap randomisation ("unexpected memory mapping").
clang++ -std=c++20 -O1 -g -fsanitize=thread -Iweb/shim -DATMO_WEB_SHIM_THREADS=4 \
  tests/web_shim/thread_pool_test.cc -o build-asan/web_shim_tsan -lgtest -lgtest_main -pthread
no_aslr=(setarch "$(uname -m)" -R)
"${no_aslr[@]}" true 2>/dev/null || no_aslr=()  # where a sandbox forbids it, as the kernel lays out
TSAN_OPTIONS="halt_on_error=1" "${no_aslr[@]}" ./build-asan/web_shim_tsan --gtest_repeat=20 --gtest_brief=1
echo "ci: sanitizer tests in $(( $(date +%s) - start )) s"

start=$(date +%s)
./scripts/fuzz.sh "$seconds" build-asan
echo "ci: fuzzing in $(( $(date +%s) - start )) s"
