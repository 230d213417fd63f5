#!/usr/bin/env bash
# Scenes: the default showcase, previews, --set, --from, regions, merges, points parts, op layers,
# multi-part files, the Slurm example.
# Needs a Vulkan device (lavapipe at least): it compares backends. Usage: scenes.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
require_vulkan
S="--size 96x64 --quiet"

printf '{"size": [120, 60], "seed": 4, "layers": [{"type": "julia", "name": "sky", "mapping": "polar", "alpha": [-0.3, 0]}, {"type": "fbm", "name": "height", "octaves": 5}]}' > mixed.json
# ---- scenes: the default showcase, previews, --set, --from, --region and merge ----
if "$FB" render -o def.exr --preview def.png --quiet 2> err.txt; then ok; else bad "the default scene failed: $(cat err.txt)"; fi
"$FB" info def.exr > def.txt
grep -q "size: *1024 x 512" def.txt && ok || bad "the default scene is not 1024 x 512"
grep -q "layer sky .*B (half), G (half), R (half)" def.txt && ok || bad "default scene: no sky colour: $(cat def.txt)"
grep -q "layer terrain .*Y (float)" def.txt && ok || bad "default scene: no terrain.Y"
grep -q "layer plants .*A (half)" def.txt && ok || bad "default scene: no plants.A"
[ "$(png_wh def.png)" = "1024 512" ] && [ "$(od -An -tu1 -j25 -N1 def.png | tr -d ' ')" = "2" ] && ok || bad "the default preview is not a 1024 x 512 RGB PNG"
# the over composite differs from the sky alone; a layer by name; an unknown layer is refused
# the checks below use the default's sky, terrain (uncoloured) and plants: three layers
"$FB" scene default | python3 -c "
import json, sys
s = json.load(sys.stdin)
s['layers'] = [l for l in s['layers'] if l['name'] in ('sky', 'terrain', 'plants')]
for k in ('stops', 'light', 'ambient'): s['layers'][1].pop(k)
print(json.dumps(s))" > three.json
S3="three.json --set size=128x64 --set layers.plants.points=200000 --set layers.terrain.insert=2000 --quiet"
"$FB" render --set size=128x64 --set layers.terrain.insert=2000 -o lit.exr --preview lit.png --preview-layer terrain --quiet
check "the default's terrain previews in colour (lit, coloured by height)" test "$(od -An -tu1 -j25 -N1 lit.png | tr -d ' ')" = 2
"$FB" render $S3 -o c.exr --preview over.png && "$FB" render $S3 -o c2.exr --preview sky.png --preview-layer sky && ok || bad "previews failed"
cmp -s over.png sky.png && bad "the over composite equals the sky alone" || ok
"$FB" render $S3 -o c3.exr --preview ter.png --preview-layer terrain && [ "$(od -An -tu1 -j25 -N1 ter.png | tr -d ' ')" = "0" ] && ok || bad "the terrain preview is not a grey hillshade"
expect_fail 2 'no layer named "moon" (layers: sky, terrain, plants' o.exr -- render $S3 -o o.exr --preview o.png --preview-layer moon
[ -e o.png ] && bad "a failed preview left o.png" || ok
# what the preview shows, in one line; --preview-layer all: a contact sheet, a labelled tile per layer
"$FB" render ${S3% --quiet} -o c4.exr --preview over4.png 2> pv.txt
check "the preview's line names the composited layers" grep -q "^fractalbake: preview over4.png: sky, terrain and plants composited back to front" pv.txt
"$FB" render ${S3% --quiet} -o c5.exr --preview sheet.png --preview-layer all 2> pv.txt
check "the sheet's line" grep -q "^fractalbake: preview sheet.png: a contact sheet of every layer (sky, terrain and plants)" pv.txt
# three tiles of at most 1024 x 512 (the 128 x 64 region, unscaled) in two columns, each under a 22-pixel label band
check "the sheet is an RGB PNG of two columns and two rows of tiles" test "$(png_wh sheet.png) $(od -An -tu1 -j25 -N1 sheet.png | tr -d ' ')" = "$((8 + 2 * (128 + 8))) $((8 + 2 * (22 + 64 + 8))) 2"
python3 - << 'PY' && ok || bad "the sheet's tiles or labels are not where they belong"
import struct, zlib
d = open('sheet.png', 'rb').read()
w, h = struct.unpack('>II', d[16:24])
idat, i = b'', 8
while i < len(d):
    n, kind = struct.unpack('>I4s', d[i:i + 8])
    if kind == b'IDAT': idat += d[i + 8:i + 8 + n]
    i += 12 + n
raw, rows, prev, p = zlib.decompress(idat), [], bytearray(w * 3), 0
for y in range(h):  # undo the PNG filters (RGB, 8 bits)
    f, line = raw[p], bytearray(raw[p + 1:p + 1 + w * 3]); p += 1 + w * 3
    for x in range(w * 3):
        a = line[x - 3] if x >= 3 else 0; b = prev[x]; c = prev[x - 3] if x >= 3 else 0
        if f == 1: line[x] = (line[x] + a) & 255
        elif f == 2: line[x] = (line[x] + b) & 255
        elif f == 3: line[x] = (line[x] + (a + b) // 2) & 255
        elif f == 4:
            pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
            line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
    rows.append(line); prev = line
px = lambda x, y: tuple(rows[y][3 * x:3 * x + 3])
assert px(2, 2) == (24, 24, 24)                                  # the background
ink = [px(x, y) for y in range(11, 25) for x in range(8, 8 + 16)]  # "SK" of the first label
assert (235, 235, 225) in ink, ink[:8]
assert px(8 + 136 + 64, 8 + 94 + 22 + 60) == (24, 24, 24)       # no fourth tile
PY
expect_fail 2 'no layer named "moon" (layers: sky, terrain, plants; or "over" or "all")' o.exr -- render $S3 -o o.exr --preview o.png --preview-layer moon
# --set: overrides reach the stored scene and the pixels; bad overrides name the --set
"$FB" render $S3 --set seed=9 --set layers.sky.c=-0.7,0.27 -o set.exr && ok || bad "--set failed"
"$FB" info set.exr | tr -d ' \n' | grep -q '"c":\[-0.7,0.27\]' && ok || bad "--set c not stored (in shortest form)"
"$FB" info set.exr | grep -q '"seed": 9' && ok || bad "--set seed not stored"
"$FB" compare c.exr set.exr --layer sky > /dev/null; [ $? -eq 1 ] && ok || bad "--set c changed no pixel"
expect_fail 2 "\-\-set layers.sky.foo=1: unknown key for a julia layer" o.exr -- render $S3 --set layers.sky.foo=1 -o o.exr
expect_fail 2 '\-\-set layers.moon.c=1: no element named "moon"' o.exr -- render $S3 --set layers.moon.c=1 -o o.exr
expect_fail 2 "\-\-set layers.sky.c=1: expected \[x, y\]" o.exr -- render $S3 --set layers.sky.c=1 -o o.exr
expect_fail 2 "\-\-set layers.7.c=1: index 7 is out of range" o.exr -- render $S3 --set layers.7.c=1 -o o.exr
expect_fail 2 "\-\-set seed: expected KEY.PATH=VALUE" o.exr -- render $S3 --set seed -o o.exr
# --from: the same file, byte for byte (same backend); with an override, another
if "$FB" render --from set.exr -o from.exr --quiet; then ok; else bad "--from failed"; fi
cmp -s set.exr from.exr && ok || bad "--from did not reproduce the file byte for byte"
"$FB" render --from set.exr --set layers.sky.max-iter=50 -o from2.exr --quiet && ! cmp -s set.exr from2.exr && ok || bad "--from with --set changed nothing"
printf 'not an exr' > junk.exr
expect_fail 2 "not a readable OpenEXR" o.exr -- render --from junk.exr -o o.exr
expect_fail 2 "either a scene file or --from" o.exr -- render mixed.json --from set.exr -o o.exr
# --region and merge: the parts, merged, are the whole bake byte for byte, whatever the strips and backend
for be in vulkan native; do
  "$FB" render $S3 --backend $be -o whole_$be.exr --strip-rows 7 || bad "whole bake ($be) failed"
  "$FB" render $S3 --backend $be -o pa_$be.exr --region 0,0,128,21 --strip-rows 5 &&
    "$FB" render $S3 --backend $be -o pb_$be.exr --region 0,21,50,43 &&
    "$FB" render $S3 --backend $be -o pc_$be.exr --region 50,21,78,43 --strip-rows 64 && ok || bad "region bakes ($be) failed"
  "$FB" merge pc_$be.exr pa_$be.exr pb_$be.exr -o merged_$be.exr --quiet && ok || bad "merge ($be) failed"
  cmp -s whole_$be.exr merged_$be.exr && ok || bad "merged regions ($be) differ from the whole bake"
  valid_exr pb_$be.exr
done
# --backend auto with layers on both (lavapipe: fBm natively, a Julia set of 8.4 million samples on
# the device): the merged bands keep the fractalbake/layer-backends attribute, byte for byte
printf '{"size": [2048, 1024], "layers": [{"type": "fbm", "octaves": 3}, {"type": "julia", "samples": 4, "max-iter": 30, "precision": "double"}]}' > mix.json
"$FB" render mix.json --quiet -o mix_whole.exr && "$FB" render mix.json --quiet --region 0,0,2048,512 -o mix_a.exr &&
  "$FB" render mix.json --quiet --region 0,512,2048,512 -o mix_b.exr && "$FB" merge mix_b.exr mix_a.exr -o mix_m.exr --quiet &&
  ok || bad "the auto region bakes failed"
if "$FB" devices --json | grep -q '"auto": *"per layer"'; then # lavapipe: each layer where it is faster
  "$FB" info mix_whole.exr | grep -q "fractalbake/layer-backends string *fbm=native;sky=vulkan" && ok || bad "the auto bake did not run a layer on each backend"
fi
cmp -s mix_whole.exr mix_m.exr && ok || bad "merged auto regions differ from the whole auto bake"
rm -f mix_*.exr
"$FB" info pb_vulkan.exr | grep -q "the region 0,21,50,43 of a 128 x 64 image" && ok || bad "info does not show the region"
"$FB" merge pc_vulkan.exr pa_vulkan.exr pb_vulkan.exr -o merged_t1.exr --threads 1 --quiet && cmp -s merged_vulkan.exr merged_t1.exr && ok || bad "merge --threads 1 differs"
"$FB" compare c.exr set.exr --max-abs 0.01 --diff-png cd.png > /dev/null; [ $? -eq 1 ] && [ "$(od -An -tu1 -j25 -N1 cd.png | tr -d ' ')" = "2" ] && [ "$(png_wh cd.png)" = "128 64" ] && ok || bad "compare --diff-png wrote no RGB picture"
"$FB" compare pb_vulkan.exr pc_vulkan.exr > /dev/null; [ $? -eq 1 ] && ok || bad "compare of two regions passed"
"$FB" render --from pb_vulkan.exr -o pb2.exr --quiet && cmp -s pb_vulkan.exr pb2.exr && ok || bad "--from a region file did not reproduce it"
expect_fail 2 "a region is missing" o.exr -- merge pa_vulkan.exr pb_vulkan.exr -o o.exr
expect_fail 2 "overlap" o.exr -- merge pa_vulkan.exr pb_vulkan.exr pc_vulkan.exr pb_vulkan.exr -o o.exr
expect_fail 2 "another scene" o.exr -- merge pa_vulkan.exr pb_vulkan.exr set.exr -o o.exr
expect_fail 2 "not inside the 128 x 64 image" o.exr -- render $S3 --region 100,0,29,64 -o o.exr
expect_fail 2 "region: expected X,Y,W,H" o.exr -- render $S3 --region 1,2,3 -o o.exr

# one EXR part per layer, each with its own compression: the same pixels as one part; regions merge
MP="--set parts=per-layer --set layers.sky.compression=piz --set layers.terrain.compression=none"
"$FB" render $S3 $MP -o mp.exr && ok || bad "multi-part bake failed"
"$FB" info mp.exr > mp.txt
grep -q "parts: *3" mp.txt && grep -q "part 0  sky *compression piz" mp.txt && grep -q "part 1  terrain *compression none" mp.txt && grep -q "part 2  plants *compression zip" mp.txt && ok || bad "multi-part structure: $(cat mp.txt)"
exr_strict mp.exr && [ "$(exrinfo --strict mp.exr 2>/dev/null | grep -c "^ *dataWindow: ")" = 3 ] && ok || bad "the multi-part file fails the strict header check (3 parts)"
rm -rf sep && mkdir sep && exrmultipart -separate -i mp.exr -o sep/p > /dev/null 2>&1 && [ -e sep/p.3.exr ] && ok || bad "exrmultipart cannot separate the parts"
"$FB" compare c.exr mp.exr > /dev/null && ok || bad "multi-part pixels differ from the single-part bake"
"$FB" render $S3 $MP --region 0,0,128,30 -o mpa.exr && "$FB" render $S3 $MP --region 0,30,128,34 -o mpb.exr && "$FB" merge mpa.exr mpb.exr -o mpm.exr --quiet && cmp -s mp.exr mpm.exr && ok || bad "multi-part regions do not merge to the whole file"
"$FB" render --from mp.exr -o mp2.exr --quiet && cmp -s mp.exr mp2.exr && ok || bad "--from a multi-part file did not reproduce it"
expect_fail 2 "its EXR parts differ" o.exr -- merge mpa.exr pb_vulkan.exr -o o.exr
expect_fail 2 'set layers.sky.compression=piz: a compression per layer needs "parts": "per-layer"' o.exr -- render $S3 --set layers.sky.compression=piz -o o.exr
"$FB" fbm $S --compression piz -o fpiz.exr && "$FB" info fpiz.exr | grep -q "compression: piz" && ok || bad "fbm --compression piz"

# a bake split by chaos-game points: three parts' hits add up to the whole game, byte for byte
printf '{"size": [120, 72], "seed": 4, "layers": [{"type": "fbm", "name": "ground", "octaves": 5, "warp": 0.5},
 {"type": "ifs", "name": "fern", "preset": "fern", "points": 2000000, "oversample": 2},
 {"type": "ifs", "name": "pop", "preset": "population", "points": 600000, "half": false}]}' > pp.json
for be in vulkan native; do
  "$FB" render pp.json --backend $be -o ppw_$be.exr --quiet
  for k in 1 2 3; do "$FB" render pp.json --backend $be --points-part $k/3 -o pp${k}_$be.exr --quiet || bad "points part $k ($be) failed"; done
  "$FB" merge pp2_$be.exr pp3_$be.exr pp1_$be.exr -o ppm_$be.exr --quiet && cmp -s ppw_$be.exr ppm_$be.exr && ok || bad "points parts ($be) do not merge to the whole bake"
  "$FB" compare ppw_$be.exr pp2_$be.exr --layer fern > /dev/null; [ $? -eq 1 ] && ok || bad "a points part ($be) holds the whole game"
done
# the backends give the same bits here, so parts from both merge to the same file
"$FB" merge pp1_vulkan.exr pp2_native.exr pp3_vulkan.exr -o ppx.exr --quiet && "$FB" compare ppw_vulkan.exr ppx.exr > /dev/null && ok || bad "parts from two backends do not merge"
"$FB" info pp1_vulkan.exr | grep -q "fractalbake/points-part *string *1/3" && ok || bad "the part is not recorded"
"$FB" render --from pp2_vulkan.exr -o pp2b.exr --quiet && cmp -s pp2_vulkan.exr pp2b.exr && ok || bad "--from a points part did not reproduce it"
expect_fail 2 "points part 2/3 is missing" o.exr -- merge pp1_vulkan.exr pp3_vulkan.exr -o o.exr
expect_fail 2 "points part 1/3 is given twice" o.exr -- merge pp1_vulkan.exr pp1_vulkan.exr pp3_vulkan.exr -o o.exr
expect_fail 2 "merge one kind at a time" o.exr -- merge pp1_vulkan.exr pa_vulkan.exr -o o.exr
expect_fail 2 "no chaos-game layer" o.exr -- render mixed.json --points-part 1/2 -o o.exr
expect_fail 2 "not with --region" o.exr -- render pp.json --points-part 1/2 --region 0,0,10,10 -o o.exr
expect_fail 2 "points-part: expected K/N" o.exr -- render pp.json --points-part 3/2 -o o.exr

# op layers: fBm detail on a refined terrain, plants masked by height; a cycle names both layers
printf '{"size": [96, 48], "layers": [{"type": "op", "name": "ground", "op": "add", "inputs": ["terrain.Y", "detail"], "weights": [1, 4]},
 {"type": "terrain", "points": [[0,0,0],[10,0,1],[0,5,2],[10,5,4],[5,2.5,9]], "insert": 500},
 {"type": "fbm", "name": "detail", "octaves": 4},
 {"type": "op", "name": "high", "op": "threshold", "inputs": ["ground"], "level": 3, "width": 1},
 {"type": "ifs", "points": 100000},
 {"type": "op", "name": "lowplants", "op": "mix", "inputs": ["plants.A", 0], "mask": "high"}]}' > ops.json
"$FB" render ops.json -o ops.exr --preview ops.png --quiet && ok || bad "op scene failed"
"$FB" info ops.exr | grep -q "layer lowplants *Y (float)" && ok || bad "op layer missing from the file"
"$FB" render ops.json -o ops_n.exr --backend native --quiet && "$FB" compare ops.exr ops_n.exr --layer lowplants > /dev/null && ok || bad "op layer differs between backends"
printf '{"layers": [{"type": "fbm"}, {"type": "op", "name": "a", "op": "add", "inputs": ["fbm", "b"]},\n {"type": "op", "name": "b", "op": "add", "inputs": ["a", 1]}]}' > cyc.json
expect_fail 2 'cyc.json:2: layers\[2\]: layer "b" uses layer "a", which depends on "b": a cycle' o.exr -- render cyc.json -o o.exr
printf '{"layers": [{"type": "fbm"}, {"type": "op", "op": "add", "inputs": ["fbm", "sky.R"]}]}' > miss.json
expect_fail 2 'no layer is named "sky"' o.exr -- render miss.json -o o.exr

slurm=$ROOT/docs/examples/slurm-bake.sh
# the Slurm recipe's task and merge bodies (docs/examples/slurm-bake.sh; tests/cli/slurm.sh runs it
# on a real Slurm), as an array 1-7:2 would run them (K from the array's min and step); the default
# scene at 1024 x 512 gives 4 tasks work for 3 or more
"$FB" scene default > def.json
mkdir -p bands
for id in 1 3 5 7; do
  PATH=$(dirname "$FB"):$PATH SLURM_ARRAY_TASK_ID=$id SLURM_ARRAY_TASK_MIN=1 SLURM_ARRAY_TASK_STEP=2 \
    bash "$slurm" --task "$PWD/def.json" bands 4 2> /dev/null || bad "slurm task $id failed"
done
check "the array's tasks wrote task-0000 to task-0002" test -s bands/task-0000.exr -a -s bands/task-0001.exr -a -s bands/task-0002.exr
PATH=$(dirname "$FB"):$PATH bash "$slurm" --merge bands def_m.exr > /dev/null 2>&1 && cmp -s def.exr def_m.exr && ok || bad "the Slurm recipe's tasks do not merge to the default bake"

# mismatched sizes: region files of two different images do not merge
"$FB" render $S3 --set size=128x32 --region 0,0,128,32 -o small.exr && ok || bad "small region failed"
expect_fail 2 "a region of a 128 x 32 image, but pa_vulkan.exr is of a 128 x 64 image" o.exr -- merge pa_vulkan.exr small.exr -o o.exr

# bounded memory: the bake streams strips to the file, so peak RSS does not grow with the image.
# 16384^2 has 4x the pixels of 8192^2 (384 MiB more half data): RSS may grow by < 64 MiB (the
# writer's queue grows with the width), and stays under 512 MiB, the size of the image held whole
# (an AddressSanitizer build adds ~300 MiB of its own, the same at both sizes).
for n in 8192 16384; do # /usr/bin/time: Debian's `time` package (scripts/setup.sh)
  /usr/bin/time -f "%M" -o rss_$n.txt "$FB" fbm --size ${n}x${n} --octaves 2 --half --compression none --backend native -o big.exr --quiet || bad "the ${n}^2 bake failed"
  rm -f big.exr
done
k1=$(tail -1 rss_8192.txt) k2=$(tail -1 rss_16384.txt)
[ "$k2" -lt 524288 ] && [ $((k2 - k1)) -lt 65536 ] && ok || bad "peak RSS $k1 KiB at 8192^2, $k2 KiB at 16384^2: not bounded"

cli_finish
