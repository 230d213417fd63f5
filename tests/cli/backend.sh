#!/usr/bin/env bash
# --backend auto (the default): on a CPU implementation of Vulkan (lavapipe) each layer runs where it
# is faster, the same bits as that backend alone; the file, the bake's line and `devices` say where.
# On a GPU every layer runs on it. Usage: backend.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
require_vulkan
check "devices explains auto" grep -q -- "--backend auto (the default)" <("$FB" devices)
cpu=0
"$FB" devices | grep -q '^0 *\* .* cpu ' && cpu=1
# a scene of every kind of choice: a double-precision Julia set of 8.4 million samples (no AVX2
# path: lavapipe's), simplex fBm (no AVX2 loop: lavapipe's), gradient fBm (the AVX2 loop: native)
# and a chaos game (native)
cat > mix.json << 'JSON'
{"size": [2048, 1024], "compression": "none",
 "layers": [{"type": "julia", "name": "sky", "samples": 4, "channels": ["iter"], "precision": "double"},
            {"type": "fbm", "name": "rock", "noise": "simplex"},
            {"type": "fbm", "name": "ground"},
            {"type": "ifs", "name": "fern", "points": 2000000}]}
JSON
"$FB" render mix.json -o auto.exr 2> auto.txt
check "auto bakes" test -s auto.exr
if [ $cpu -eq 1 ]; then
  check "the line says where each layer ran" grep -q "with sky and rock on llvmpipe.*, ground and fern on native C" auto.txt
  check "the file: backend auto" grep -q 'fractalbake/backend (type string): "auto"' <(exrheader auto.exr)
  check "the file: each layer's backend" grep -q '"sky=vulkan;rock=vulkan;ground=native;fern=native"' <(exrheader auto.exr)
  # the same bits as each backend alone, layer by layer
  "$FB" render mix.json --backend vulkan --quiet -o vk.exr
  "$FB" render mix.json --backend native --quiet -o nat.exr
  check "sky is lavapipe's, bit for bit" "$FB" compare vk.exr auto.exr --layer sky > /dev/null
  check "rock is lavapipe's, bit for bit" "$FB" compare vk.exr auto.exr --layer rock > /dev/null
  check "ground is native's, bit for bit" "$FB" compare nat.exr auto.exr --layer ground > /dev/null
  check "fern is native's, bit for bit" "$FB" compare nat.exr auto.exr --layer fern > /dev/null
  check "--backend vulkan: every layer on the device" grep -q 'fractalbake/backend (type string): "vulkan"' <(exrheader vk.exr)
  check "--from an auto file reproduces it byte for byte" "$FB" render --from auto.exr --quiet -o again.exr
  check "(the same bytes)" cmp -s auto.exr again.exr
  # all native: the native backend's pixels, bit for bit; the file says auto was asked, and where
  # each layer ran; --json agrees; --from bakes each layer where it ran again
  "$FB" render --set size=256x128 --set layers.plants.points=300000 --json -o d-auto.exr > d-auto.json
  "$FB" render --set size=256x128 --set layers.plants.points=300000 --backend native --quiet -o d-native.exr
  check "the default scene on lavapipe: the native pixels, bit for bit" "$FB" compare d-auto.exr d-native.exr --quiet
  check "... the file records auto, as asked" grep -q 'fractalbake/backend (type string): "auto"' <(exrheader d-auto.exr)
  check "... and each layer on native" grep -q '"detail=native;sky=native;terrain=native;ground=native;snow=native;gentle=native;plants=native"' <(exrheader d-auto.exr)
  check "... the native file records native and no list" test "$(exrheader d-native.exr | grep -c 'fractalbake/backend (type string): "native"\|layer-backends')" = 1
  check "... --json: backend auto, every layer native" test "$(python3 -c "import json; r = json.load(open('d-auto.json')); print(r['backend'], sorted({l['backend'] for l in r['layers']}))")" = "auto ['native']"
  "$FB" render --from d-auto.exr --quiet -o d-from.exr
  check "... --from it: the same bytes (each layer where it ran)" cmp -s d-auto.exr d-from.exr
else
  check "a GPU runs every layer" grep -q '"sky=vulkan;rock=vulkan;ground=vulkan;fern=vulkan"' <(exrheader auto.exr)
  check "the file: backend auto, as asked" grep -q 'fractalbake/backend (type string): "auto"' <(exrheader auto.exr)
fi
expect_fail 2 "--backend: expected auto, vulkan or native" o.exr -- fbm --size 8x8 --backend gpu -o o.exr
cli_finish
