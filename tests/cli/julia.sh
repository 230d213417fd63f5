#!/usr/bin/env bash
# The Julia layer: channels, palettes, previews, types.
# Needs a Vulkan device (lavapipe at least): it compares backends. Usage: julia.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
require_vulkan
S="--size 96x64 --quiet"

# ---- bad input: julia ----
FB_VK_NO_FLOAT64=1 expect_fail 2 "needs a Vulkan device with shaderFloat64" o.exr -- julia $S --precision double --backend vulkan -o o.exr
printf '{"size": [64, 32], "layers": [{"type": "julia", "channels": []}]}' > chan.json
# a subset of channels: exactly those in the file, equal to the full layer's; iter alone previews
if "$FB" julia $S --channels iter,de -o sub.exr --preview sub.png && "$FB" julia $S -o full.exr &&
  [ "$("$FB" info sub.exr | sed -n 's/^channels: *//p')" = 2 ] && "$FB" compare sub.exr full.exr --ignore-missing > /dev/null &&
  "$FB" julia $S --channels iter -o it.exr --preview it.png && [ -s it.png ] && [ -s sub.png ]; then ok; else bad "julia --channels"; fi
"$FB" julia $S --stops "0,0,0,0;0.5,1,0,0;1,1,1,1" --density 0 --brightness 2 -o js.exr && ok || bad "julia with stops failed"
if "$FB" julia $S --alpha 0.5,0.25 -o j.exr --preview j.png 2> err.txt; then ok; else bad "julia bake failed: $(cat err.txt)"; fi
[ "$(od -An -tu1 -j25 -N1 j.png | tr -d ' ')" = "2" ] && ok || bad "the julia preview is not an RGB PNG"
"$FB" info j.exr | grep -q "R (half)" && ok || bad "julia colour is not half by default"
"$FB" julia $S --float -o jf.exr && "$FB" info jf.exr | grep -q "R (float)" && ok || bad "--float does not store float colour"
valid_exr j.exr
"$FB" info j.exr | grep -q "layer sky .*iter (uint)" && ok || bad "julia layer lacks sky.iter as uint"

cli_finish
