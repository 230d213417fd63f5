#!/usr/bin/env bash
# Any EXR in, for compare and info: tiled files (tile sizes that do and do not divide the image,
# ZIP and uncompressed), a mip-mapped texture from maketx (its top level), multi-part files (one
# layer a part, scanline and tiled), and standard input (`-`) compare equal to their scanline
# original, every pixel; a tiled file of another image does not; info names the storage.
# The files are made by OpenImageIO's oiiotool and maketx, an independent writer.
# Usage: anyexr.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
N="--backend native --quiet"
cat > sc.json << 'JSON'
{"size": [203, 97], "layers": [{"type": "fbm", "name": "h", "octaves": 3},
 {"type": "op", "name": "a", "op": "add", "inputs": ["h", 0.5]}]}
JSON
"$FB" render sc.json $N -o o.exr
sed "s/\"octaves\": 3/\"octaves\": 4/" sc.json > sc2.json && "$FB" render sc2.json $N -o other.exr
code() { "$FB" compare "$@" > out.txt 2> err.txt; echo $?; }
oiiotool o.exr --tile 64 64 -o t64.exr
oiiotool o.exr --tile 40 24 -o t40.exr
oiiotool o.exr --tile 16 16 --compression none -o tnone.exr
maketx o.exr -o mip.exr > /dev/null
oiiotool o.exr --ch h.Y --attrib oiio:subimagename hpart o.exr --ch a.Y --attrib oiio:subimagename apart \
  --siappend -o parts.exr
oiiotool parts.exr --tile 40 24 -o tparts.exr
oiiotool other.exr --tile 64 64 -o tother.exr
for f in t64.exr t40.exr tnone.exr mip.exr parts.exr tparts.exr; do
  check "$f equals its scanline original (every pixel)" test "$(code o.exr "$f")" = 0
  check "  the other way round" test "$(code "$f" o.exr)" = 0
done
check "a tiled file of another image differs" test "$(code o.exr tother.exr)" = 1
check "  (the pixels, not the channel set)" grep -q "beyond" out.txt
check "tiled input with thresholds and SSIM" test "$(code t40.exr o.exr --ssim 1 --rmse 0)" = 0
check "compare - reads standard input" sh -c "'$FB' compare - t40.exr --quiet < o.exr"
check "compare A - too" sh -c "'$FB' compare mip.exr - --quiet < o.exr"
check "info - reads standard input" sh -c "'$FB' info - < tparts.exr | grep -q 'parts:       2'"
check "info names a mip-map's storage" sh -c "'$FB' info mip.exr | grep -q 'storage:     tiled 64 x 64, mip-mapped: the top level read'"
check "info names each part's tiles" sh -c "'$FB' info tparts.exr | grep -q 'part 1  apart        compression zip, tiled 40 x 24'"
check "info --json gives the storage" sh -c "'$FB' info t40.exr --json | python3 -c \"import json,sys; assert json.load(sys.stdin)['storage'] == 'tiled 40 x 24'\""
check "a scanline file says so" sh -c "'$FB' info o.exr | grep -q 'storage:     scanline'"
# a PNG on standard input, from a pipe and from a file: the same report as the file named
P="$ROOT/tests/data/flip"
"$FB" compare "$P/j4_rgb.png" "$P/j1_rgb.png" --max-abs 0.5 --flip --json > named.json
cat "$P/j4_rgb.png" | "$FB" compare - "$P/j1_rgb.png" --max-abs 0.5 --flip --json > piped.json
"$FB" compare "$P/j4_rgb.png" - --max-abs 0.5 --flip --json < "$P/j1_rgb.png" > redirected.json
check "compare - takes a PNG from a pipe" python3 -c "
import json
a, b = json.load(open('named.json')), json.load(open('piped.json'))
assert b['a'] == '-' and a['result'] == b['result'] and a['channels'] == b['channels'] and a['flip'] == b['flip'], b"
check "  and from a redirected file, as B" python3 -c "
import json
a, b = json.load(open('named.json')), json.load(open('redirected.json'))
assert b['b'] == '-' and a['channels'] == b['channels'] and a['flip'] == b['flip'], b"
check "an EXR from a pipe still works" sh -c "cat o.exr | '$FB' compare - t40.exr --quiet"
cli_finish
