#!/usr/bin/env bash
# The chaos game: .ifs files, maps, populations, determinism across threads, strips and backends,
# tone mapping.
# Needs a Vulkan device (lavapipe at least): it compares backends. Usage: ifs.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
require_vulkan
S="--size 96x64 --quiet"

# ---- bad input: ifs ----
I="ifs --size 96x64 --quiet --points 200000"
printf '{"size": [64, 32], "layers": [{"type": "ifs",\n "maps": []}]}' > empty.json
printf '{"size": [64, 32], "layers": [{"type": "ifs", "maps": [[0.5, 0, 0, 0.5, 0, 0],\n [0.5, 0, 0, 0.5, 1, NaN]]}]}' > nanmap.json
"$FB" ifs --size 64x48 --quiet --points 1e5 -o e5.exr && "$FB" info e5.exr | grep -q '"points": 100000' && ok || bad "--points 1e5 is not the integer 100000"
printf 'leaf {\n  .5 0 0 .5 0 0 .5\n  .5 0 0 .5 1 0 zz\n}\n' > broken.ifs
printf 'halves { .5 0 0 .5 0 0 .5 .5 0 0 .5 1 0 .5 }\nthirds {\n .33 0 0 .33 0 0 .3 .33 0 0 .33 .66 0 .3 .33 0 0 .33 .33 .5 .4\n}\n' > two.ifs
if "$FB" $I --file two.ifs --name thirds -o t.exr 2> err.txt; then ok; else bad "ifs from a file failed: $(cat err.txt)"; fi
"$FB" info t.exr | grep -q '0.66' && ok || bad "the file's maps are not stored in the scene"
"$FB" info t.exr | grep -q '"file"' && bad "the stored scene still names the file" || ok
"$FB" $I --maps ".33,0,0,.33,0,0,.3;.33,0,0,.33,.66,0,.3;.33,0,0,.33,.33,.5,.4" -o t2.exr --quiet
"$FB" compare t.exr t2.exr > /dev/null && ok || bad "the same maps from a file and from --maps differ"
if "$FB" ifs --size 96x64 --points 300000 --preset population -o pop.exr --preview pop.png --quiet 2> err.txt; then ok; else bad "population failed: $(cat err.txt)"; fi
[ -s err.txt ] && bad "a clean ifs bake wrote to stderr: $(cat err.txt)" || ok
valid_exr pop.exr
"$FB" info pop.exr > info3.txt
grep -q "layer plants .*count (uint)" info3.txt && grep -q "A (half)" info3.txt && grep -q "density (float)" info3.txt && ok || bad "ifs layer channels: $(cat info3.txt)"
[ "$(od -An -tu1 -j25 -N1 pop.png | tr -d ' ')" = "2" ] && ok || bad "the ifs preview is not an RGB PNG"
# the same bits on every thread count, strip height and backend
"$FB" $I --preset maple --oversample 2 --backend native --threads 1 --strip-rows 7 -o in1.exr
"$FB" $I --preset maple --oversample 2 --backend native --threads 3 --strip-rows 64 -o in2.exr
"$FB" $I --preset maple --oversample 2 -o iv1.exr
cmp -s in1.exr in2.exr && ok || bad "ifs (native) depends on threads or strip rows"
"$FB" compare in1.exr iv1.exr --max-abs 0 > /dev/null && ok || bad "ifs differs between lavapipe and native"
# tone mapping re-run from the stored channels: the same parameters give the same bytes, new ones
# the same pixels as a bake made with them
"$FB" $I -o tm1.exr --preview tm1.png
"$FB" tonemap tm1.exr -o tm1b.exr --quiet && cmp -s tm1.exr tm1b.exr && ok || bad "tonemap with unchanged parameters changed the file"
"$FB" $I --brightness 2.5 --gamma 3 --vibrancy 0.5 --highlight-power -1 --palette blossom -o tm2.exr --preview tm2.png
"$FB" tonemap tm1.exr -o tm2b.exr --brightness 2.5 --gamma 3 --vibrancy 0.5 --highlight-power -1 --palette blossom \
  --preview tm2b.png
# --preview: the re-toned layer drawn as the bake draws it
check "tonemap --preview is the preview of a bake with the same tone parameters" cmp -s tm2.png tm2b.png
cmp -s tm1.png tm2b.png && bad "tonemap --preview shows the old tone parameters" || ok
expect_fail 2 "preview" x.exr -- tonemap tm1.exr -o x.exr --preview x.jpg
expect_fail 2 "brightness" x.png -- tonemap tm1.exr -o x.exr --preview x.png --brightness -1
[ -e x.exr ] && bad "a refused tonemap left x.exr" || ok
"$FB" compare tm2.exr tm2b.exr --max-abs 0 > /dev/null && ok || bad "tonemap differs from a bake with the same tone parameters"
"$FB" info tm2b.exr | grep -q '"brightness": 2.5' && ok || bad "tonemap did not store the new parameters"
"$FB" compare tm1.exr tm2b.exr --layer plants > /dev/null; [ $? -eq 1 ] && ok || bad "new tone parameters changed nothing"
expect_fail 2 "not a tone-mapping flag" x.exr -- tonemap tm1.exr -o x.exr --points 5
expect_fail 2 "brightness" x.exr -- tonemap tm1.exr -o x.exr --brightness -1
"$FB" fbm $S -o f0.exr
expect_fail 2 "that tonemap can re-tone" x.exr -- tonemap f0.exr -o x.exr

cli_finish
