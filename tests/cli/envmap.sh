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

# ---- the preview: starlight is added over the sky behind it, hidden by an opaque sky in front ----
cat > night.json << 'EOF'
{"size": [128, 64], "seed": 3, "layers": [
  {"type": "julia", "name": "sky", "mapping": "latlong", "alpha": [-0.3, 0], "brightness": 0.5},
  {"type": "stars", "name": "stars", "mapping": "latlong", "limit": 7, "brightness": 0.01}]}
EOF
"$FB" render night.json -o n.exr --preview n-over.png 2> n.txt && ok || bad "the night sky bake failed"
check "the preview line says the stars are added as light" grep -q "sky and stars composited back to front by their coverage (light added: stars)" n.txt
"$FB" render night.json -o n1.exr --preview n-sky.png --preview-layer sky --quiet && ok || bad "the sky alone"
"$FB" render night.json -o n2.exr --preview n-stars.png --preview-layer stars --quiet && ok || bad "the stars alone"
# the stars first, then the opaque sky: the sky hides them, and the composite is the sky alone
cat > under.json << 'EOF'
{"size": [128, 64], "seed": 3, "layers": [
  {"type": "stars", "name": "stars", "mapping": "latlong", "limit": 7, "brightness": 0.01},
  {"type": "julia", "name": "sky", "mapping": "latlong", "alpha": [-0.3, 0], "brightness": 0.5}]}
EOF
"$FB" render under.json -o n3.exr --preview n-under.png --quiet && ok || bad "stars behind the sky"
python3 - n-over.png n-sky.png n-stars.png n-under.png << 'PY' && ok || bad "the composite does not add the starlight to the sky"
import struct, sys, zlib
def rgb(path):  # an 8-bit RGB PNG (filter types 0 to 4)
    d = open(path, 'rb').read()
    w, h, depth, kind = struct.unpack('>IIBB', d[16:26])
    assert depth == 8 and kind == 2, path
    i, idat = 8, b''
    while i < len(d):
        n, t = struct.unpack('>I4s', d[i:i + 8])
        idat += d[i + 8:i + 8 + n] if t == b'IDAT' else b''
        i += 12 + n
    raw, st, prev, out = zlib.decompress(idat), w * 3, bytearray(w * 3), []
    for y in range(h):
        f, row = raw[y * (st + 1)], bytearray(raw[y * (st + 1) + 1:(y + 1) * (st + 1)])
        for x in range(st):
            a, b, c = row[x - 3] if x >= 3 else 0, prev[x], prev[x - 3] if x >= 3 else 0
            p = a + b - c
            pred = a if abs(p - a) <= abs(p - b) and abs(p - a) <= abs(p - c) else b if abs(p - b) <= abs(p - c) else c
            row[x] = (row[x] + [0, a, b, (a + b) // 2, pred][f]) & 255
        prev, out = row, out + list(row)
    return out
over, sky, stars, under = (rgb(p) for p in sys.argv[1:5])
def lin(v):  # the sRGB curve's inverse
    v /= 255
    return v / 12.92 if v <= 0.04045 else ((v + 0.055) / 1.055) ** 2.4
assert under == sky, "an opaque sky in front does not hide the stars"
assert all(o >= s for o, s in zip(over, sky)), "adding starlight darkened a pixel of the sky"
lit = [i for i, t in enumerate(stars) if t > 40]
assert len(lit) > 20, len(lit)
# where a star shines the composite is the sum of the two lights, within the 8-bit rounding of each
for i in lit:
    want = min(1.0, lin(sky[i]) + lin(stars[i]))
    assert abs(lin(over[i]) - want) <= 0.03 * want + 0.004, (i, over[i], sky[i], stars[i])
PY

# ---- bad input: mappings ----
expect_fail 2 "size: a lat-long environment map is 2N x N pixels, found 100 x 60: the nearest is 104 x 52" o.exr -- julia --mapping latlong --size 100x60 -o o.exr
expect_fail 2 "a cube environment map is N x 6N pixels (six faces stacked), found 32 x 32: the nearest is 6 x 36" o.exr -- fbm --mapping cube --size 32x32 -o o.exr
printf '{"size": [64, 32], "layers": [{"type": "julia", "mapping": "latlong"}, {"type": "fbm"}]}' > mixed.json
expect_fail 2 'layers\[1\].mapping: layer "fbm" is a plane but layer "sky" (layers\[0\].mapping) is a lat-long environment map' o.exr -- render mixed.json -o o.exr --quiet
expect_fail 2 "an environment map has no edges to tile" o.exr -- fbm --mapping latlong --tileable --size 64x32 -o o.exr
expect_fail 2 '"double" is for the rect and polar grids' o.exr -- julia --mapping cube --precision double --size 8x48 -o o.exr

cli_finish
