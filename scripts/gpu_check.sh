#!/usr/bin/env bash
# Every GPU figure of docs/performance.md in one run, for a lent NVIDIA machine (headless EGL; see
# the section "On an NVIDIA GPU" there) and, with --quick, on Mesa's llvmpipe in CI (ctest
# gpu_check, label gl): the device the context got, then per figure the measured medians beside
# the issue's targets.
#
#   scripts/gpu_check.sh [BUILD] [--quick]      BUILD: the build folder (default build)
#
# Figures: hillaire's tables (all_tables; also with a texel per invocation, for comparison) and a
# 3840x2160 frame; elek's 32x256x32 table (K = 4);
# source4d's GPU tables and a 1280x720 frame; the viewer's frame rate at 1280x720 (atmo-viewer
# --offscreen: no display needed); then every pass of the three benches. A full run takes under 5 minutes on an H200 and
# about a minute on 2 llvmpipe cores with --quick. Exits non-zero only when a command fails; the
# targets are printed, not asserted (a machine's load is not a test's business).
set -euo pipefail
build=build
quick=0
for arg in "$@"; do
  case "$arg" in
    --quick) quick=1 ;;
    -*) echo "gpu_check: unknown flag $arg" >&2; exit 2 ;;
    *) build=$arg ;;
  esac
done
atmo="$build/apps/atmo/atmo"
viewer="$build/apps/viewer/atmo-viewer"
[ -x "$atmo" ] || { echo "gpu_check: no $atmo (build the project first)" >&2; exit 2; }
if [ "$quick" = 1 ]; then repeat=1; frames=20; else repeat=20; frames=6000; fi
start=$(date +%s)

# The median column of `atmo bench` for a pass: bench_median OUTPUT PASS.
bench_median() { awk -v pass="$2" '$1 == pass { print $2 }' <<<"$1"; }
row() { printf '%-40s %12s %-4s target %s\n' "$1" "${2:-n/a}" "${4:-ms}" "$3"; }

hillaire=$("$atmo" bench --backend gl --repeat "$repeat" --width 3840 --height 2160)
grep '^gl device' <<<"$hillaire"
echo "figure                                         median      target"
row "hillaire: all tables" "$(bench_median "$hillaire" all_tables)" "<= 0.05 ms (H100/H200)"
row "hillaire: 3840x2160 frame" "$(bench_median "$hillaire" frame_3840x2160)" "<= 0.1 ms (H100/H200)"
# The same tables with a texel per invocation (llvmpipe's form): what the work-group forms gain here.
per_texel=$("$atmo" bench --backend gl --work-group-forms off --repeat "$repeat" --width 64 --height 64)
row "hillaire: all tables, a texel per invocation" "$(bench_median "$per_texel" all_tables)" "- (comparison)"

elek=$("$atmo" bench --backend gl --model elek --preset atmosphere-plus --repeat "$([ "$quick" = 1 ] && echo 1 || echo 5)" \
  --width 1280 --height 720)
row "elek: all tables (atmosphere-plus)" "$(bench_median "$elek" all_tables)" "<= 20 ms (H100/H200)"

source4d=$("$atmo" bench --backend gl --model source4d --repeat "$([ "$quick" = 1 ] && echo 1 || echo 5)" \
  --width 1280 --height 720)
row "source4d: all tables" "$(bench_median "$source4d" all_tables)" "<= 10 ms (H100/H200)"
row "source4d: 1280x720 frame" "$(bench_median "$source4d" frame_1280x720)" "-"

if [ -x "$viewer" ]; then
  # No window needed: --offscreen draws into a framebuffer, at most two frames ahead of the GPU.
  out=$("$viewer" --offscreen --frames "$frames" --width 1280 --height 720 2>&1) || { echo "$out" >&2; exit 1; }
  fps=$(grep -o '[0-9.]* fps' <<<"$out" | tail -1 | cut -d' ' -f1)
  row "viewer: 1280x720 frame rate (hillaire)" "${fps:-n/a}" ">= 1000 fps (H100/H200)" fps
else
  echo "viewer: skipped (no $viewer: built without GLFW)"
fi
echo
echo "every pass (atmo bench medians, ms):"
for bench in "$hillaire" "$per_texel" "$elek" "$source4d"; do grep -v "^gl device" <<<"$bench"; done
echo "gpu_check: $(( $(date +%s) - start )) s"
