#!/usr/bin/env bash
# Skies as environment maps through the command line: lat-long and cube bakes carry the envmap
# attribute as OpenImageIO and OpenEXR's own tools read it, maketx takes the lat-long map as written,
# region bakes merge with it, info shows it, and the bad inputs of the mappings are refused.
# Usage: envmap.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"

# ---- the attribute, as other tools read it ----
"$FB" julia --mapping latlong --size 128x64 --alpha -0.3,0 --quiet -o ll.exr && ok || bad "julia latlong bake"
"$FB" fbm --mapping cube --size 32x192 --quiet -o cu.exr && ok || bad "fbm cube bake"
valid_exr ll.exr
valid_exr cu.exr
oiiotool --info -v ll.exr | grep -q 'textureformat: "LatLong Environment"' && ok || bad "oiiotool does not see a lat-long environment"
oiiotool --info -v cu.exr | grep -q 'textureformat: "CubeFace Environment"' && ok || bad "oiiotool does not see a cube environment"
exrheader ll.exr | grep -q 'envmap (type envmap): latitude-longitude map' && ok || bad "exrheader: no latlong envmap"
exrheader cu.exr | grep -q 'envmap (type envmap): cube-face map' && ok || bad "exrheader: no cube envmap"
"$FB" info ll.exr | grep -q '^envmap: *latlong' && ok || bad "info does not show the envmap"
[ "$("$FB" info --json cu.exr | python3 -c 'import json,sys; print(json.load(sys.stdin)["envmap"])')" = cube ] && ok || bad "info --json: no envmap"
# a plane has none
"$FB" fbm --size 32x32 --quiet -o plane.exr && ! exrheader plane.exr | grep -q envmap && ok || bad "a rect bake has an envmap"
# maketx (OpenImageIO) makes its lat-long environment texture from the file as written
maketx --envlatl ll.exr -o ll.tx > /dev/null 2>&1 && oiiotool --info -v ll.tx | grep -q 'LatLong Environment' && ok ||
  bad "maketx --envlatl refused the lat-long bake"

# ---- a scene of environment layers, in regions, merged: the attribute survives ----
cat > sky.json << 'EOF'
{"size": [128, 64], "seed": 4, "layers": [
  {"type": "julia", "name": "sky", "mapping": "latlong", "alpha": [-0.3, 0], "turbulence": 0.1, "channels": ["n", "R", "G", "B"]},
  {"type": "fbm", "name": "clouds", "mapping": "latlong", "octaves": 6},
  {"type": "op", "name": "mix", "op": "add", "inputs": ["sky.n", "clouds"]}]}
EOF
"$FB" render sky.json -o whole.exr --quiet && ok || bad "the env scene does not bake"
"$FB" render sky.json --region 0,0,128,32 -o r0.exr --quiet && "$FB" render sky.json --region 0,32,128,32 -o r1.exr --quiet &&
  "$FB" merge r0.exr r1.exr -o merged.exr --quiet && cmp -s whole.exr merged.exr && ok || bad "regions of an env map do not merge to the whole bake"
exrheader merged.exr | grep -q 'latitude-longitude map' && ok || bad "merge drops the envmap"
# the same scene at another thread count: the same bytes
"$FB" render sky.json --threads 1 -o t1.exr --quiet && cmp -s whole.exr t1.exr && ok || bad "threads change an env bake"

# ---- bad input: mappings ----
expect_fail 2 "size: a lat-long environment map is 2N x N pixels, found 100 x 60: the nearest is 104 x 52" o.exr -- julia --mapping latlong --size 100x60 -o o.exr
expect_fail 2 "a cube environment map is N x 6N pixels (six faces stacked), found 32 x 32: the nearest is 6 x 36" o.exr -- fbm --mapping cube --size 32x32 -o o.exr
printf '{"size": [64, 32], "layers": [{"type": "julia", "mapping": "latlong"}, {"type": "fbm"}]}' > mixed.json
expect_fail 2 'layers\[1\].mapping: layer "fbm" is a plane but layer "sky" (layers\[0\].mapping) is a lat-long environment map' o.exr -- render mixed.json -o o.exr --quiet
expect_fail 2 "an environment map has no edges to tile" o.exr -- fbm --mapping latlong --tileable --size 64x32 -o o.exr
expect_fail 2 '"double" is for the rect and polar grids' o.exr -- julia --mapping cube --precision double --size 8x48 -o o.exr

cli_finish
