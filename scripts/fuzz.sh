#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz/, clang with ASan + UBSan) and runs each for SECONDS (default
# 1800, the long run; CI runs 60). Each run starts from the seeds in fuzz/corpus/<target>/ plus
# what earlier runs added to BUILD_DIR/fuzz-corpus/<target>/, uses fuzz/<target>.dict, and
# leaves any crash, leak, timeout or out-of-memory input in BUILD_DIR/fuzz-artifacts/<target>/.
# Prints the executions per target and fails if any target found something: keep such an input
# as fuzz/regressions/<target>/<what-it-broke> (tests/fuzz_replay_test.cc replays it) and fix it.
# Usage: scripts/fuzz.sh [SECONDS] [BUILD_DIR]     (default BUILD_DIR: build-fuzz)
#        ATMO_FUZZ_TARGETS="grid_csv exr_reader" scripts/fuzz.sh 60   (only those targets)
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-1800}"
build="${2:-build-fuzz}"

if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=clang++ \
    -DATMO_FUZZ=ON -DATMO_GL=OFF -DATMO_BUILD_TESTS=OFF -DATMO_BUILD_BENCHMARKS=OFF >/dev/null
fi
cmake --build "$build" -j"$(nproc)" --target fuzzers

targets="${ATMO_FUZZ_TARGETS:-$(sed -n 's/^set(ATMO_FUZZ_TARGETS \(.*\))$/\1/p' fuzz/CMakeLists.txt)}"
# The targets that read files write them into a private folder under TMPDIR: memory if we can.
if [ -z "${TMPDIR:-}" ] && [ -w /dev/shm ]; then export TMPDIR=/dev/shm; fi

failed=0
summary=""
for target in $targets; do
  corpus="$build/fuzz-corpus/$target"
  artifacts="$build/fuzz-artifacts/$target/"
  log="$build/fuzz-$target.log"
  mkdir -p "$corpus" "$artifacts"
  dict=()
  if [ -f "fuzz/$target.dict" ]; then dict=(-dict="fuzz/$target.dict"); fi
  echo "fuzz: $target for ${seconds} s (log $log)"
  status=0
  "$build/fuzz/fuzz_$target" "$corpus" "fuzz/corpus/$target" "${dict[@]}" \
    -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=65536 \
    -print_final_stats=1 -artifact_prefix="$artifacts" >"$log" 2>&1 || status=$?
  executions=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
  coverage=$(grep -o 'cov: [0-9]*' "$log" | tail -n 1 | cut -d' ' -f2 || true)
  found=$(find "$artifacts" -type f | wc -l)
  summary+=$(printf '%-16s %12s executions  %6s edges  %3s findings  exit %s' "$target" "${executions:-?}" \
    "${coverage:-?}" "$found" "$status")$'\n'
  if [ "$status" -ne 0 ] || [ "$found" -ne 0 ]; then
    failed=1
    tail -n 40 "$log"
  fi
done
printf '%s' "$summary"
exit "$failed"
