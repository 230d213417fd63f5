#!/usr/bin/env bash
# The FBM constraint model: macro shapes, constraints, regions, 1D profiles, CSV and plots.
# Needs a Vulkan device (lavapipe at least): it compares backends. Usage: constrain.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
require_vulkan
S="--size 96x64 --quiet"

# ---- constrain: the FBM constraint model ----
C="constrain --size 120x80 --quiet"
printf '10,10\n60,40\n119,79\n' > cpts.csv
printf 'x,y,kind,value\n30,30,H,0.95\n90,50,T,0.05\n' > cregs.csv
if "$FB" $C --points cpts.csv --regions cregs.csv --water 5 -o con.exr --preview con.png 2> err.txt; then ok; else bad "constrain failed: $(cat err.txt)"; fi
"$FB" info con.exr | grep -q "layer terrain .*A (half), H (float), T (float), Y (float), detail (float), macro (float)" && ok || bad "constrain channels: $("$FB" info con.exr | grep layer)"
"$FB" $C --points cpts.csv --regions cregs.csv --water 5 --backend native -o con_n.exr && "$FB" compare con.exr con_n.exr > /dev/null && ok || bad "constrain differs between backends"
"$FB" $C --points cpts.csv --regions cregs.csv --water 5 --threads 1 --backend native -o con_1.exr && "$FB" compare con.exr con_1.exr > /dev/null && ok || bad "constrain depends on the thread count"
"$FB" $C --T 0.05 -o con_t.exr && "$FB" compare con.exr con_t.exr --layer terrain > /dev/null; [ $? -eq 1 ] && ok || bad "--T changed nothing"
# every model key reaches the computation: each one changes the result
"$FB" $C --points cpts.csv --regions cregs.csv -o cbase.exr
for f in "--macro cone" "--macro-height 5" "--hurst 0.6" "--sigma 2" "--delta 0.5" "--buffering naive" "--domain 2" "--falloff 0.5" "--seed 9" "--interpolation linear" "--soften 0.3"; do
  "$FB" $C --points cpts.csv --regions cregs.csv $f -o cf.exr
  "$FB" compare cbase.exr cf.exr > /dev/null; [ $? -eq 1 ] && ok || bad "constrain $f changed nothing"
done
# 1D: a CSV profile in, x,d,D out; the constraint rows have D == d
printf 'x,d\n0,0\n50,10\n100,0\n' > prof.csv
"$FB" constrain --size 256x1 --profile prof.csv --points <(printf '128,0\n40,0\n') --csv out1d.csv -o p1d.exr --quiet && ok || bad "1D constrain failed"
[ "$(wc -l < out1d.csv)" = 257 ] && head -1 out1d.csv | grep -q "^x,d,D$" && ok || bad "1D CSV: $(head -2 out1d.csv)"
awk -F, '$1 == 128 || $1 == 40 {if ($2 != $3) bad = 1} END {exit bad}' out1d.csv && ok || bad "1D constraints not exact in the CSV"
"$FB" constrain --size 256x1 --profile prof.csv --points <(printf '128,0\n') --plot p1d.png -o p1d2.exr --quiet &&
  [ "$(od -An -tu1 -j25 -N1 p1d.png | tr -d ' ')" = "2" ] && [ "$(png_wh p1d.png)" = "256 240" ] && ok || bad "1D plot is not a 256 x 240 RGB PNG"
# a macro shape from an EXR channel, and its size must match
"$FB" fbm --size 120x80 --quiet --octaves 3 -o macro.exr
"$FB" $C --macro macro.exr:fbm.Y -o cm.exr && ok || bad "macro from an EXR failed"
expect_fail 2 "macro.exr: 120 x 80, but the scene is 64 x 64" o.exr -- constrain --size 64x64 --macro macro.exr -o o.exr
expect_fail 2 "cpts.csv:3: the pixel is outside the image" o.exr -- constrain --size 100x50 --points cpts.csv -o o.exr
expect_fail 2 "H must be in (0, 1)" o.exr -- constrain --size 120x80 --regions <(printf '1,1,H,1.5\n') -o o.exr
printf '1,2\n3\n' > bad.csv
printf '{"size": [64, 64], "layers": [{"type": "constrain", "points": [[3, 4], [64, 2]]}]}' > cbad.json
expect_fail 2 'cbad.json:1: layers\[0\].points\[1\]: pixel (64, 2) is outside the 64 x 64 image' o.exr -- render cbad.json -o o.exr
"$FB" constrain --help | grep -c -- "--compression" | grep -q "^1$" && ok || bad "constrain --help lists --compression twice"
# the macro shape from another layer of the scene (listed after it) equals the same layer baked to an EXR first
printf '{"size": [96, 64], "seed": 2, "layers": [{"type": "constrain", "name": "shaped", "macro": "terrain", "T": 0.5, "points": [[10, 10], [50, 30]]},
 {"type": "terrain", "points": [[0,0,0],[10,0,3],[0,5,6],[10,5,2],[5,2.5,9]], "insert": 800}]}' > mac.json
"$FB" render mac.json -o mac.exr --quiet && ok || bad "macro from a layer failed"
printf '0 0 0\n10 0 3\n0 5 6\n10 5 2\n5 2.5 9\n' > mac.xyz
"$FB" terrain --size 96x64 --seed 2 --points mac.xyz --insert 800 -o mact.exr --quiet
"$FB" constrain --size 96x64 --seed 2 --layer shaped --macro mact.exr:terrain.Y --T 0.5 --points <(printf '10,10\n50,30\n') -o macc.exr --quiet
"$FB" compare macc.exr mac.exr --layer shaped > /dev/null && ok || bad "a macro from a layer differs from the same layer's EXR"
printf '{"layers": [{"type": "constrain", "macro": "m"}, {"type": "op", "name": "m", "op": "add", "inputs": ["terrain", 1]}]}' > mcyc.json
expect_fail 2 'layer "m" uses layer "terrain", which depends on "m": a cycle' o.exr -- render mcyc.json -o o.exr
printf '{"layers": [{"type": "constrain", "macro": "hill.Y"}]}' > mmiss.json
expect_fail 2 'layers\[0\].macro: "hill.Y" is not cone' o.exr -- render mmiss.json -o o.exr
printf '{"size": [32, 32], "layers": [{"type": "constrain", "macro": "sky.iter"}, {"type": "julia"}]}' > mint.json
expect_fail 2 'a channel of integers' o.exr -- render mint.json -o o.exr

cli_finish
