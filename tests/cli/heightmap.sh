#!/usr/bin/env bash
# Heightmaps for engines and GIS: --heightmap OUT.png|OUT.r16 (16 bits, the range printed and, in the
# PNG, stored), OUT.tif for a terrain (a float GeoTIFF that GIS tools read: listgeo), and their bad
# inputs. The round trip within one 16-bit step is tests/test_heightmap.c.
# Usage: heightmap.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
N="--backend native"
"$FB" fbm $N --size 64x40 -o h.exr --heightmap h.png 2> err.txt
check "the heightmap's line: its range" grep -q "^fractalbake: heightmap h.png: layer fbm's heights .* (0) to .* (65535), 16-bit grey PNG$" err.txt
lo=$(sed -n 's/.*heights \(.*\) (0) to.*/\1/p' err.txt)
hi=$(sed -n 's/.*(0) to \(.*\) (65535).*/\1/p' err.txt)
python3 - "$lo" "$hi" << 'PY' && ok || bad "the PNG's text chunks do not hold the printed range $lo..$hi"
import struct, sys, zlib
d = open('h.png', 'rb').read()
w, h, bits, ct = struct.unpack('>IIBB', d[16:26])
assert (w, h, bits, ct) == (64, 40, 16, 0), (w, h, bits, ct)
text, i = {}, 8
while i < len(d):
    n, kind = struct.unpack('>I4s', d[i:i + 8])
    if kind == b'tEXt':
        k, v = d[i + 8:i + 8 + n].split(b'\0', 1)
        text[k.decode()] = v.decode()
    i += 12 + n
assert float(text['fractalbake/height-min']) == float(sys.argv[1]), text
assert float(text['fractalbake/height-max']) == float(sys.argv[2]), text
PY
"$FB" fbm $N --size 64x40 -o h.exr --heightmap h.r16 --heightmap-range -1,1 --quiet
check "RAW: 2 bytes a pixel, nothing else" test "$(stat -c %s h.r16)" = $((2 * 64 * 40))
"$FB" constrain $N --size 65x65 -o c.exr --heightmap c.png --quiet
check "constrain writes a heightmap" test -s c.png
# render: a scene's layer, by its key; --json lists it with its range
printf '{"size": [48, 32], "layers": [{"type": "fbm", "name": "ground", "heightmap": "g.r16", "heightmap-range": [-2, 2]}]}' > hm.json
"$FB" render hm.json $N -o g.exr --json > g.json
check "--json: the heightmap, its format and range" test "$(python3 -c "import json; h = json.load(open('g.json'))['heightmaps'][0]; print(h['layer'], h['path'], h['format'], h['height_at_0'], h['height_at_65535'])")" = \
  "ground g.r16 16-bit little-endian raw -2.0 2.0"
check "--json: the heightmap among the outputs" test "$(python3 -c "import json; print([o['bytes'] for o in json.load(open('g.json'))['outputs'] if o['what'] == 'heightmap'])")" = "[3072]"
# --from does not write the stored scene's heightmap (as with every side output), --set names it back
"$FB" render --from g.exr -o g2.exr 2> from.txt
check "--from leaves the heightmap (and its range) out, saying so" grep -q "not writing the stored scene's outputs (layers.ground.heightmap=g.r16 with its heightmap-range)" from.txt
check "--from bakes without the heightmap" test -s g2.exr -a "$(ls g*.r16 | wc -l)" = 1
# a terrain's GeoTIFF, read by the GeoTIFF library's own tool
printf 'x,y,z\n500000,4600000,100\n500600,4600000,130\n500000,4600400,90\n500600,4600400,150\n500300,4600200,240\n' > utm.csv
"$FB" terrain $N --points utm.csv --size 120x80 --insert 2000 --crs EPSG:32633 -o t.exr --heightmap t.tif --quiet
check "GeoTIFF written" test -s t.tif
if command -v listgeo > /dev/null; then
  listgeo t.tif > geo.txt 2>&1
  check "listgeo: the projected CRS" grep -q "ProjectedCSTypeGeoKey (Short,1): PCS_WGS84_UTM_zone_33N" geo.txt
  check "listgeo: the tie point at the frame's top-left corner" grep -q "500000  *4600400" geo.txt
  check "listgeo: 5 m pixels" grep -A1 "ModelPixelScaleTag" geo.txt | grep -q "5  *5"
fi
# tiles: named OUT_x<column>_y<row> (north-west first) without an engine, every one of the one range;
# the tile edges, the engines' names and sidecars, and the sizes are tests/test_heightmap.c's
"$FB" fbm $N --size 65x33 -o f.exr --heightmap f.png --tiles 2x2 2> tiles.txt
check "tiles: the four files, no single heightmap, no sidecar" test "$(ls f*.png f.* | sort | tr '\n' ' ')" = "f.exr f_x0_y0.png f_x0_y1.png f_x1_y0.png f_x1_y1.png "
check "tiles: the summary line" grep -q "^fractalbake: heightmap f_x0_y0.png to f_x1_y1.png: 2 x 2 tiles of 33 x 17 sharing their edges, layer fbm's heights .* (0) to .* (65535) in every one, 16-bit grey PNG$" tiles.txt
python3 - << 'PY' && ok || bad "the tiles do not share their edges or their range"
import struct, zlib
def png(path):  # a 16-bit grey PNG's samples and text chunks (filters undone)
    d = open(path, 'rb').read()
    w, h = struct.unpack('>II', d[16:24])
    idat, text, i = b'', {}, 8
    while i < len(d):
        n, kind = struct.unpack('>I4s', d[i:i + 8])
        if kind == b'IDAT': idat += d[i + 8:i + 8 + n]
        if kind == b'tEXt':
            k, v = d[i + 8:i + 8 + n].split(b'\0', 1)
            text[k] = v
        i += 12 + n
    raw, bpp, stride, rows, prev = zlib.decompress(idat), 2, 2 * w, [], bytearray(2 * w)
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = line[x - bpp] if x >= bpp else 0
            b, c = prev[x], prev[x - bpp] if x >= bpp else 0
            p = a + b - c
            pred = [0, a, b, (a + b) // 2, a if abs(p - a) <= abs(p - b) and abs(p - a) <= abs(p - c) else b if abs(p - b) <= abs(p - c) else c][f]
            line[x] = (line[x] + pred) & 255
        rows.append([line[2 * x] << 8 | line[2 * x + 1] for x in range(w)])
        prev = line
    return rows, text
t = {(c, r): png('f_x%d_y%d.png' % (c, r)) for c in (0, 1) for r in (0, 1)}
assert all(len(v[0]) == 17 and len(v[0][0]) == 33 for v in t.values())
assert len({(v[1][b'fractalbake/height-min'], v[1][b'fractalbake/height-max']) for v in t.values()}) == 1
for r in (0, 1):  # x0's east column is x1's west column
    assert [row[32] for row in t[0, r][0]] == [row[0] for row in t[1, r][0]]
for c in (0, 1):  # y0's south row is y1's north row
    assert t[c, 0][0][16] == t[c, 1][0][0]
PY
"$FB" fbm $N --size 65x33 -o f.exr --heightmap f.png --tiles 2x2 --json > ft.json 2> /dev/null
check "--json: the tiles and their files" test "$(python3 -c "import json; h = json.load(open('ft.json'))['heightmaps'][0]; print(h['tiles'], h['tile_files'])")" = \
  "[2, 2] ['f_x0_y0.png', 'f_x1_y0.png', 'f_x0_y1.png', 'f_x1_y1.png']"
check "--json: every tile among the outputs" test "$(python3 -c "import json; print(sum(o['what'] == 'heightmap tile' for o in json.load(open('ft.json'))['outputs']))")" = 4
# a name with a quote and a backslash: the sidecar is still JSON, and names the files written
"$FB" fbm $N --size 253x253 -o q.exr --heightmap 'q"a\b.png' --heightmap-engine unreal --quiet &&
  "$FB" fbm $N --size 505x505 -o q2.exr --heightmap 'q"t\b.png' --heightmap-engine unreal --tiles 2x2 --quiet && ok ||
  bad "engine bakes with a quote in the heightmap's name"
python3 - << 'PY' && ok || bad "a sidecar with an odd file name is not JSON naming its files"
import json, os
one = json.load(open('q"a\\b.import.json'))
assert one['heightmap'] == 'q"a\\b.png' and os.path.exists(one['heightmap']), one['heightmap']
tiles = json.load(open('q"t\\b.import.json'))['tiles']['files']
assert [f['file'] for f in tiles] == ['q"t\\b_x%d_y%d.png' % (c, r) for r in (0, 1) for c in (0, 1)], tiles
assert all(os.path.exists(f['file']) for f in tiles)
PY

# a split bake (--task): the task that computes the layer writes its tiles, the whole bake's
printf '{"size": [65, 65], "layers": [{"type": "fbm", "name": "a", "heightmap": "a.png", "tiles": [2, 2]}, {"type": "fbm", "name": "b", "hurst": 0.3}]}' > tt.json
"$FB" render tt.json $N --task 0/2 -o tt0.exr --quiet && "$FB" render tt.json $N --task 1/2 -o tt1.exr --quiet
"$FB" render tt.json $N -o tw.exr --quiet --set layers.a.heightmap=w.png
check "--task: the tiles of a split bake are the whole bake's" sh -c 'for t in x0_y0 x1_y0 x0_y1 x1_y1; do cmp -s a_$t.png w_$t.png || exit 1; done'
"$FB" render --from f.exr -o f2.exr 2> from2.txt
check "--from leaves the tiles out with the heightmap" grep -q "(layers.fbm.heightmap=f.png with its tiles)" from2.txt
# bad inputs: one line, exit 2, nothing written
expect_fail 2 '^fractalbake: --heightmap: "h.jpg": the format comes from the extension: .png (16-bit grey), .r16 (16-bit raw)$' o.exr -- fbm $N --size 8x8 -o o.exr --heightmap h.jpg
expect_fail 2 'a GeoTIFF needs world coordinates, which an fbm layer has not' o.exr -- fbm $N --size 8x8 -o o.exr --heightmap h.tif
expect_fail 2 'heightmap-range: expected LO,HI with LO < HI, found 2,1' o.exr -- fbm $N --size 8x8 -o o.exr --heightmap h.png --heightmap-range 2,1
expect_fail 2 'heightmap-range: a range for a heightmap, and no "heightmap" is written' o.exr -- fbm $N --size 8x8 -o o.exr --heightmap-range 0,1
expect_fail 2 'crs: EPSG:4326 is a geographic system (degrees)' o.exr -- terrain $N --points utm.csv --size 8x8 --crs EPSG:4326 -o o.exr
expect_fail 2 'crs: expected EPSG:N' o.exr -- terrain $N --points utm.csv --size 8x8 --crs utm33 -o o.exr
expect_fail 2 'h2.png: named as the preview and as the heightmap' o.exr -- fbm $N --size 8x8 -o o.exr --heightmap h2.png --preview h2.png
check "no heightmap left by the failures" test ! -e h.jpg -a ! -e h2.png
cli_finish
