#!/usr/bin/env bash
# Installs what fractalbake needs on Debian 12 (when missing) and builds it into build/.
# ./scripts/setup.sh --test also installs the tests' own packages.
# Safe to run again: it installs nothing that is present and rebuilds only what changed.
set -euo pipefail
cd "$(dirname "$0")/.."

PKGS="build-essential cmake pkg-config libvulkan-dev mesa-vulkan-drivers vulkan-tools glslang-tools spirv-tools
vulkan-validationlayers libopenexr-dev openexr libjansson-dev libpng-dev time
libqhull-dev clang python3 libdeflate-dev openimageio-tools libtiff-dev libgeotiff-dev geotiff-bin libtiff-tools
libxml2-dev libflam3-dev"
# --test: also what only the tests use (a real one-node Slurm for tests/cli/slurm.sh, headless
# Chromium for the HTML report of tests/cli/report.sh, flam3-render for tests/cli/flame.sh,
# clang-format for tests/format.sh, Blender for tests/cli/blender-*.sh, numpy and pytest for
# tests/python and tests/install.sh)
[ "${1:-}" = --test ] && PKGS="$PKGS slurm-wlm chromium flam3-utils clang-format blender python3-numpy python3-pytest"
missing=()
for p in $PKGS; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}" >&2
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

BUILD=${FB_BUILD_DIR:-build}
if [ ! -f "$BUILD/CMakeCache.txt" ]; then
  cmake -S . -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo ${FB_CMAKE_ARGS:-} >/dev/null
fi
cmake --build "$BUILD" -j"$(nproc)" >/dev/null
