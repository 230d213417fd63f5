#!/usr/bin/env bash
# Sets up (packages, build) and bakes the default scene to out/default.exr with a PNG preview.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
mkdir -p out
./build/fractalbake render -o out/default.exr --preview out/default.png "$@"
echo "baked out/default.exr and out/default.png with $PWD/build/fractalbake"
echo "(for the README's commands: export PATH=\"$PWD/build:\$PATH\")"
