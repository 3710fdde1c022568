#!/usr/bin/env bash
# The nightly fuzzing run: every libFuzzer target (fuzz/) for a share of TOTAL executions (default
# 10^7 over all targets), then the inputs that reached new coverage merged into the tree's corpus
# (fuzz/corpus/<target>/, libFuzzer's -merge=1: only inputs that add coverage), so that the next
# run and tests/fuzz_replay_test.cc start from them. Fails on any crash, leak, timeout or
# out-of-memory input (left in BUILD_DIR/fuzz-artifacts/<target>/; keep it as a regression, see
# scripts/fuzz.sh). Prints executions per target and their sum.
# Usage: scripts/fuzz_nightly.sh [TOTAL] [BUILD_DIR]     (defaults: 10000000, build-fuzz)
set -euo pipefail
cd "$(dirname "$0")/.."
total="${1:-10000000}"
build="${2:-build-fuzz}"
[[ "$total" =~ ^[1-9][0-9]*$ ]] || { echo "fuzz_nightly: TOTAL must be a positive integer (got '$total')" >&2; exit 2; }

if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=clang++ \
    -DATMO_FUZZ=ON -DATMO_GL=OFF -DATMO_BUILD_TESTS=OFF -DATMO_BUILD_BENCHMARKS=OFF >/dev/null
fi
cmake --build "$build" -j"$(nproc)" --target fuzzers

targets=$(sed -n 's/^set(ATMO_FUZZ_TARGETS \(.*\))$/\1/p' fuzz/CMakeLists.txt)
count=$(wc -w <<<"$targets")
per_target=$(( (total + count - 1) / count ))
if [ -z "${TMPDIR:-}" ] && [ -w /dev/shm ]; then export TMPDIR=/dev/shm; fi

failed=0
sum=0
start=$(date +%s)
for target in $targets; do
  corpus="$build/fuzz-corpus/$target"
  artifacts="$build/fuzz-artifacts/$target/"
  log="$build/fuzz-nightly-$target.log"
  mkdir -p "$corpus" "$artifacts" "fuzz/corpus/$target"
  dict=()
  if [ -f "fuzz/$target.dict" ]; then dict=(-dict="fuzz/$target.dict"); fi
  status=0
  # Parallel jobs share the executions; -runs bounds each job's share.
  jobs=$(nproc)
  "$build/fuzz/fuzz_$target" "$corpus" "fuzz/corpus/$target" "${dict[@]}" \
    -runs=$(( (per_target + jobs - 1) / jobs )) -jobs="$jobs" -workers="$jobs" -timeout=10 -rss_limit_mb=2048 \
    -max_len=65536 -print_final_stats=1 -artifact_prefix="$artifacts" >"$log" 2>&1 || status=$?
  # With -jobs the workers log to fuzz-N.log in the working directory: their stats are summed.
  executions=0
  for worker_log in fuzz-[0-9]*.log; do
    [ -f "$worker_log" ] || continue
    n=$(sed -n 's/^stat::number_of_executed_units: *//p' "$worker_log" | tail -n 1)
    executions=$(( executions + ${n:-0} ))
    cat "$worker_log" >>"$log"
    rm -f "$worker_log"
  done
  found=$(find "$artifacts" -type f | wc -l)
  before=$(find "fuzz/corpus/$target" -type f | wc -l)
  "$build/fuzz/fuzz_$target" -merge=1 "fuzz/corpus/$target" "$corpus" >>"$log" 2>&1 || status=$?
  after=$(find "fuzz/corpus/$target" -type f | wc -l)
  sum=$(( sum + executions ))
  printf '%-16s %12d executions  %3d findings  corpus %d -> %d  exit %s\n' "$target" "$executions" "$found" \
    "$before" "$after" "$status"
  if [ "$status" -ne 0 ] || [ "$found" -ne 0 ]; then
    failed=1
    tail -n 40 "$log"
  fi
done
echo "fuzz_nightly: $sum executions over $count targets in $(( $(date +%s) - start )) s"
exit "$failed"
