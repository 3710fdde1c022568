#!/usr/bin/env bash
# Builds atmo for the browser (docs/web.md): libnova's source from Debian's archive (the sun and
# moon from date and place), then web/ with Debian's Emscripten into build-web/:
#   build-web/atmo.mjs, build-web/atmo.wasm   the library and its JavaScript API
#   build-web/site/                           the demo page, ready to serve
#   build-web/package/                        the npm package atmo-sky (`npm pack` there)
# Needs the packages of `scripts/install_deps.sh --web` (emscripten, libglm-dev, nlohmann-json3-dev).
# Usage: scripts/build_web.sh [BUILD_DIR]
set -euo pipefail
if [ "${1:-}" = "-h" ] || [ "${1:-}" = "--help" ]; then  # the comment above
  sed -n '2,/^set -euo/p' "$0" | grep '^#' | sed 's/^# \{0,1\}//'
  exit 0
fi
cd "$(dirname "$0")/.."
build=${1:-build-web}
mkdir -p "$build/_deps"
deps=$(cd "$build/_deps" && pwd)
# libnova 0.16 from Debian's source package, fetched with a private source list and package
# lists (nothing of the system's apt configuration changes), unpacked with Debian's patch applied.
if [ ! -f "$deps/libnova/src/julian_day.c" ]; then
  lists="$deps/apt-lists"
  mkdir -p "$lists/partial"
  printf 'deb-src http://deb.debian.org/debian bookworm main\n' >"$deps/sources.list"
  apt_options=(-o "Dir::Etc::SourceList=$deps/sources.list" -o "Dir::Etc::SourceParts=/nonexistent"
               -o "Dir::State::Lists=$lists" -o "Debug::NoLocking=1" -o "APT::Sandbox::User=$(id -un)")
  apt-get "${apt_options[@]}" update -qq
  (cd "$deps" && apt-get "${apt_options[@]}" source --download-only -qq libnova)
  rm -rf "$deps/libnova" && mkdir -p "$deps/libnova"
  tar -xf "$deps"/libnova_*.orig.tar.* -C "$deps/libnova" --strip-components=1
  tar -xf "$deps"/libnova_*.debian.tar.* -C "$deps/libnova"
  while read -r patch; do
    [ -n "$patch" ] && [ "${patch#\#}" = "$patch" ] && patch -s -d "$deps/libnova" -p1 <"$deps/libnova/debian/patches/$patch"
  done <"$deps/libnova/debian/patches/series"
fi
# Debian's emcc runs on the system's node, which must see Debian's node modules (acorn).
export NODE_PATH=/usr/share/nodejs${NODE_PATH:+:$NODE_PATH}
emcmake cmake -S web -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DATMO_LIBNOVA_SOURCE="$deps/libnova" >/dev/null
cmake --build "$build" -j"$(nproc)"
