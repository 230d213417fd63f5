#!/usr/bin/env bash
# Sets up (packages, build) and runs the whole test suite. GPU tests run on whatever Vulkan device
# exists (lavapipe in CI) with VK_LAYER_KHRONOS_validation enabled: any validation message fails.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh --test
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
export FB_VK_VALIDATION=1
ctest --test-dir "${FB_BUILD_DIR:-build}" --output-on-failure -j2 "$@"
