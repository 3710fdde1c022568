#!/usr/bin/env bash
# The WebAssembly build's table times against the native library's, single-threaded, in one run
# (docs/web.md): per model the passes of `atmo bench --threads 1` (min of its repeats) and of
# atmo.wasm under node (min of as many model builds, after one to warm the JIT), and their ratio.
# Usage: scripts/web_bench.sh [BUILD_DIR] [BUILD_WEB_DIR]   (defaults build and build-web)
set -euo pipefail
if [ "${1:-}" = "-h" ] || [ "${1:-}" = "--help" ]; then  # the comment above
  sed -n '2,/^set -euo/p' "$0" | grep '^#' | sed 's/^# \{0,1\}//'
  exit 0
fi
cd "$(dirname "$0")/.."
build=${1:-build}
web=${2:-build-web}
for model in hillaire source4d; do
  repeats=10
  [ "$model" = source4d ] && repeats=3
  "$build/apps/atmo/atmo" bench --model "$model" --threads 1 --repeat "$repeats" --width 16 --height 16 >"/tmp/atmo_web_bench_native_$$.txt"
  node web/bench.mjs "$web" "$model" "$repeats" "/tmp/atmo_web_bench_native_$$.txt"
done
rm -f "/tmp/atmo_web_bench_native_$$.txt"
