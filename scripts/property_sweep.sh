#!/usr/bin/env bash
# The property tests at scale: >= 10^6 random queries over random valid atmospheres for every CPU
# model (tests/property_test.cc with ATMO_PROPERTY_SCALE=75: 75 x 13500 queries), then the GL
# backend's hillaire and elek through the same generator (tests/gl_property_test.cc, scale
# ATMO_GL_PROPERTY_SCALE=50: 50 x 2600 queries) where the build has it. Prints the counts; fails
# on the first non-finite or unphysical value.
# Usage: scripts/property_sweep.sh [BUILD_DIR]   (default: build)
set -euo pipefail
build="${1:-build}"
ATMO_PROPERTY_SCALE="${ATMO_PROPERTY_SCALE:-75}" "$build/tests/atmo_tests" --gtest_filter='Properties.*'
if [ -x "$build/tests/atmo_gl_tests" ]; then
  ATMO_PROPERTY_SCALE="${ATMO_GL_PROPERTY_SCALE:-50}" "$build/tests/atmo_gl_tests" --gtest_filter='GlProperties.*'
fi
