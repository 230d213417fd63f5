#!/usr/bin/env bash
# The erode layer end to end: its channels; the same bits for any thread count and strip height,
# and on lavapipe as natively (where a Vulkan device exists); every model key reaches the model; a
# terrain input lends its world (the cell size) and its hillshade. Usage: erode.sh PATH/TO/fractalbake
SRC=$(cd "$(dirname "$0")/../.." && pwd)
. "$(dirname "$0")/lib.sh"
cli_init "$@"
scene() { # scene FILE [extra erode keys]
  printf '{"size": [96, 80], "seed": 2, "layers": [{"type": "fbm", "name": "h", "octaves": 5, "hurst": 0.9, "frequency": 3}, {"type": "erode", "name": "e", "input": "h", "extent": 8, "iterations": 60, "duration": 30%s}]}' "${2:-}" > "$1"
}
scene e.json
"$FB" render e.json --backend native --quiet -o base.exr && ok || bad "erode render failed"
"$FB" info base.exr | grep -q "layer e .*Y (float), deposition (float), flow (float), sediment (float), water (float), wear (float)" && ok ||
  bad "erode channels: $("$FB" info base.exr | grep 'layer e')"
"$FB" compare base.exr base.exr --layer h > /dev/null && "$FB" compare base.exr base.exr --layer e > /dev/null && ok || bad "compare"
# the bits do not depend on threads or strips
for f in "--threads 1" "--threads 2 --strip-rows 7" "--threads 3 --strip-rows 1"; do
  "$FB" render e.json --backend native --quiet $f -o t.exr && "$FB" compare base.exr t.exr --max-abs 0 > /dev/null && ok || bad "erode differs with $f"
done
if have_vulkan; then
  "$FB" render e.json --backend vulkan --quiet -o v.exr && "$FB" compare base.exr v.exr --max-abs 0 > /dev/null && ok ||
    bad "erode differs between lavapipe and native: $("$FB" compare base.exr v.exr --max-abs 0 | grep -v ' ok')"
fi
# every key of the model changes the result
for kv in extent=6 iterations=40 duration=20 rain=0.01 gravity=5 capacity=0.1 dissolve=0.3 deposit=0.5 \
  evaporation=0.5 depth=0.02 talus=20 thermal=0.1; do
  "$FB" render e.json --backend native --quiet --set "layers.e.$kv" -o k.exr && "$FB" compare base.exr k.exr --layer e > /dev/null
  [ $? -eq 1 ] && ok || bad "erode $kv changed nothing"
done
# the mass of the settled height (Y: bed plus suspended sediment) is the input's, to rounding
"$FB" render e.json --backend native -o m.exr 2> sum.txt && grep -q "mass change [-0-9.e]*" sum.txt &&
  awk '/mass change/ {for (i = 1; i < NF; i++) if ($i == "change") v = $(i + 1); v = v < 0 ? -v : v; exit !(v < 1e-5)}' sum.txt && ok ||
  bad "erode summary: $(cat sum.txt)"
# a half layer, and a terrain input: its world gives the cell size
scene h.json ', "half": true'
"$FB" render h.json --backend native --quiet -o h.exr && "$FB" info h.exr | grep -q "layer e .*Y (half)" && ok || bad "half erode"
printf '{"size": [64, 64], "layers": [{"type": "terrain", "name": "t", "points": "%s/docs/examples/survey.csv", "insert": 500}, {"type": "erode", "input": "t", "iterations": 30}]}' \
  "$SRC" > t.json
"$FB" render t.json --backend native -o te.exr --preview te.png 2> te.txt && grep -q "64 x 64 cells of " te.txt &&
  ! grep -q "cells of 16," te.txt && [ "$(png_wh te.png)" = "64 64" ] && ok || bad "erode over terrain: $(cat te.txt)"
# the eroded heights as an engine heightmap: 16-bit raw, two bytes a pixel, the range named
"$FB" render e.json --backend native --set layers.e.heightmap=e.r16 -o hm.exr 2> hm.txt && [ "$(stat -c %s e.r16)" = $((2 * 96 * 80)) ] &&
  grep -q "heightmap e.r16: layer e's heights" hm.txt && ok || bad "erode heightmap: $(cat hm.txt)"
cli_finish
