#!/usr/bin/env bash
# The property tests at scale: >= 10^6 random queries over random valid atmospheres for every CPU
# model (tests/property_test.cc with ATMO_PROPERTY_SCALE=75: 75 x 13500 queries). Prints the
# count; fails on the first non-finite or unphysical value. About 10 minutes on 2 cores.
# Usage: scripts/property_sweep.sh [BUILD_DIR]   (default: build)
set -euo pipefail
build="${1:-build}"
ATMO_PROPERTY_SCALE="${ATMO_PROPERTY_SCALE:-75}" "$build/tests/atmo_tests" --gtest_filter='Properties.*'
