#!/bin/bash
# The latency of atmo-viewer from a change of source4d's atmosphere to the new sky on screen
# (docs/viewer.md#source4d-tables-on-the-cpu), with source4d's tables built where MODE says
# (--source4d-tables gpu | cpu | auto).
#
#   scripts/viewer_latency.sh MODE [CHANGE_FRAME] [more atmo-viewer flags]
#   scripts/viewer_latency.sh cpu 600
#   scripts/viewer_latency.sh gpu 2000 --build-budget 25
#
# The viewer runs hidden at 1280x720 (under xvfb-run when there is no DISPLAY) with model
# source4d; a script sets mie-density 2 at frame CHANGE_FRAME (default 600; it must come after
# the first sky is shown: about 400 frames with cpu, 1200 with gpu on llvmpipe), and the run ends
# once the new sky is shown. From the frame log (each line's ms is the time since the frame before
# it began) it prints the frame K that first draws the new sky, the time from the start of frame
# CHANGE_FRAME to the start of frame K, and the frame times in between, then the viewer's summary
# and the CPU time of the whole run (/usr/bin/time).
set -euo pipefail
mode=${1:?usage: viewer_latency.sh gpu|cpu|auto [CHANGE_FRAME] [flags]}
change=${2:-600}
shift $(($# >= 2 ? 2 : 1))
root=$(cd "$(dirname "$0")/.." && pwd)
viewer=${ATMO_VIEWER:-$root/build/apps/viewer/atmo-viewer}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
printf 'at %d mie-density 2\n' "$change" >"$work/change.txt"
command=("$viewer" --hidden --width 1280 --height 720 --model source4d --source4d-tables "$mode"
         --frames $((change + 1)) --script "$work/change.txt" --frame-log "$work/frames.txt" "$@")
if [ -z "${DISPLAY:-}" ]; then command=(xvfb-run -a -s "-screen 0 1280x1024x24" "${command[@]}"); fi
/usr/bin/time -f "CPU time of the run: %U s user, %S s system, %e s wall" "${command[@]}" >"$work/out.txt" 2>&1 ||
  { cat "$work/out.txt"; exit 1; }
echo "load average $(cut -d' ' -f1-3 /proc/loadavg)"
awk -v change="$change" '
NR == 1 { next }
{ ms[$1] = $2; pending[$1] = $4; last = $1 }
END {
  if (pending[change - 1] != "-") { print "the first sky was not shown before frame " change ": choose a later one"; exit 1 }
  k = -1
  for (f = change; f <= last; ++f) if (pending[f] == "-") { k = f; break }
  if (k < 0) { print "no new sky by the last frame"; exit 1 }
  n = k > change ? k - change : 1; latency = 0; worst = 0
  for (f = change + 1; f <= k; ++f) { latency += ms[f]; if (ms[f] > worst) worst = ms[f] }
  before = 0
  for (f = change - 20; f < change; ++f) before += ms[f]
  printf "change at frame %d, new sky first drawn in frame %d: %.0f ms later, over %d frames (mean %.1f ms, longest %.1f ms; the 20 frames before the change: mean %.1f ms)\n",
         change, k, latency, k - change, latency / n, worst, before / 20
}' "$work/frames.txt"
tail -n 3 "$work/out.txt"
