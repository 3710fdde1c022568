#!/usr/bin/env bash
# Runs the README's test command RUNS times in a row beside a CPU hog (one busy loop per core),
# stopping at the first failure: the test suite must not depend on an idle machine
# (docs/reliability.md, "Tests on a busy machine").
# Usage: scripts/stress_tests.sh [RUNS] [BUILD_DIR]      (defaults: 10, build)
set -euo pipefail
cd "$(dirname "$0")/.."
runs="${1:-10}"
build="${2:-build}"
[[ "$runs" =~ ^[1-9][0-9]*$ ]] || { echo "stress_tests: RUNS must be a positive integer (got '$runs')" >&2; exit 2; }
[[ -f "$build/CTestTestfile.cmake" ]] || { echo "stress_tests: no test build in '$build' (build it first)" >&2; exit 2; }
cores=$(nproc)
hogs=()
cleanup() { for pid in "${hogs[@]}"; do kill "$pid" 2>/dev/null || true; done; }
trap cleanup EXIT INT TERM
for ((i = 0; i < cores; ++i)); do
  ( while :; do :; done ) &
  hogs+=("$!")
done
echo "stress_tests: $cores busy loops beside 'ctest --test-dir $build -j2', $runs runs"
log=$(mktemp -d)
for ((run = 1; run <= runs; ++run)); do
  start=$(date +%s)
  if ctest --test-dir "$build" -j2 --output-on-failure >"$log/run_$run.log" 2>&1; then
    echo "run $run/$runs: passed in $(( $(date +%s) - start )) s (load $(cut -d' ' -f1-3 /proc/loadavg))"
  else
    echo "run $run/$runs: FAILED after $(( $(date +%s) - start )) s; log: $log/run_$run.log"
    grep -E '\*\*\*Failed|\*\*\*Timeout|Failed  ' "$log/run_$run.log" | head -20 || true
    exit 1
  fi
done
echo "stress_tests: $runs runs passed"
rm -rf "$log"
