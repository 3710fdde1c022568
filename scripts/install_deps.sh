#!/usr/bin/env bash
# Installs every Debian package atmo needs to build, test and benchmark.
# Idempotent: safe to run again; uses sudo only when not already root. node and npm are for the
# KTX2 read-back test: configuring the build then installs the npm package ktx-parse into
# <build>/node/node_modules (tests/CMakeLists.txt). They are tools, not libraries: a machine that
# has them already (another distribution of Node.js, whose nodejs package bundles npm and
# conflicts with Debian's npm) keeps them; only a machine without them gets Debian's. clang and
# its runtime libraries are for the sanitizer and libFuzzer build of .ci/run (scripts/fuzz.sh).
# With --tests it also installs what only the tests run: blender, which renders
# `atmo render --target blender` maps in tests/engine_target_test.cc (a large package, so the
# README's first command, which builds and runs only the CLI, leaves it out), python3-distributed
# (Dask), on which tests/python run annual skies on a local cluster, and openimageio-tools, whose
# oiiotool reads back the Radiance HDR sky maps in tests/annual_test.cc. stellarium-data is the
# star catalogue that atmo reads at run time for its night skies (docs/night.md; GPL-2+, not
# shipped); with --no-install-recommends it does not pull Stellarium itself. --tests and --web
# also install Emscripten, which builds atmo for the browser (scripts/build_web.sh, docs/web.md),
# and Chromium, in which the tests load the demo page headless.
set -euo pipefail

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi

PACKAGES=(
  build-essential cmake ninja-build pkg-config
  libopenexr-dev libpng-dev
  libcli11-dev nlohmann-json3-dev
  libtbb-dev libglm-dev
  libnova-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libegl-dev libgl-dev libegl-mesa0 libgl1-mesa-dri libepoxy-dev
  libglfw3-dev xvfb xauth
  pybind11-dev python3-dev python3-numpy python3-pytest python3-venv python3-setuptools python3-wheel
  libimgui-dev libstb-dev
  clang libclang-rt-14-dev
  stellarium-data
)
if [ "${1:-}" = "--tests" ]; then
  PACKAGES+=(blender python3-distributed openimageio-tools)
fi
if [ "${1:-}" = "--tests" ] || [ "${1:-}" = "--web" ]; then
  PACKAGES+=(emscripten chromium)
fi
if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then
  PACKAGES+=(nodejs npm)
fi

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install_deps: all ${#PACKAGES[@]} packages already installed"
  exit 0
fi

echo "install_deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
