#!/usr/bin/env bash
# The reference samples the demo page shows the models' errors against (web/site/reference_earth.csv,
# docs/web.md): atmo's path tracer (model reference) on preset earth, observer on the ground, the
# sun at 2, 5, 10, 20, 40 and 70 degrees, the sky above the horizon at view zenith angles 0-88
# degrees and azimuths 0-180 degrees from the sun (the sky is symmetric about the sun's vertical),
# 262144 paths per point with next-event estimation at every vertex, seed 7: a standard error of
# ~0.3-0.5 %, which the CSV carries. 3 min 19 s on 2 cores.
# Usage: scripts/make_web_reference.sh [ATMO_CLI]
set -euo pipefail
if [ "${1:-}" = "-h" ] || [ "${1:-}" = "--help" ]; then  # the comment above
  sed -n '2,/^set -euo/p' "$0" | grep '^#' | sed 's/^# \{0,1\}//'
  exit 0
fi
cd "$(dirname "$0")/.."
cli=${1:-build/apps/atmo/atmo}
grid=$(mktemp)
trap 'rm -f "$grid"' EXIT
echo "altitude_m,sun_zenith_deg,view_zenith_deg,azimuth_deg" >"$grid"
for elevation in 2 5 10 20 40 70; do
  for zenith in 0 10 20 30 40 50 60 70 80 85 88; do
    for azimuth in 0 15 30 60 90 120 150 180; do
      echo "0,$((90 - elevation)),$zenith,$azimuth" >>"$grid"
    done
  done
done
"$cli" sample --model reference --preset earth --grid "$grid" --option samples=262144 --option nee=vertex --seed 7 \
  --unit luminance --out web/site/reference_earth.csv
echo "wrote web/site/reference_earth.csv ($(($(wc -l <web/site/reference_earth.csv) - 1)) points)"
