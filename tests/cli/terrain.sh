#!/usr/bin/env bash
# Terrain: survey points, centres, meshes, height fields, determinism.
# Needs a Vulkan device (lavapipe at least): it compares backends. Usage: terrain.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
require_vulkan
S="--size 96x64 --quiet"

# ---- terrain ----
Tr="terrain --size 64x64 --quiet"
awk 'BEGIN { srand(4); print "# survey"; print "x,y,z"; for (i = 0; i < 300; i++) { x = rand() * 100; y = rand() * 100; printf "%.4f,%.4f,%.4f\n", x, y, 10 * sin(x / 9) + y / 10 } }' > pts.csv
printf '0 0 1\n1 0 2\n2 0 nan\n' > nanpts.xyz
printf '0 0 1\n1 0 2\n2 0\n' > short.xyz
printf '0 0 1\n1 1 2\n2 2 3\n3 3 4\n' > line.xyz
printf '# nothing here\n' > empty.xyz
printf '1,1,3.4,1\n' > badcenters.csv
printf '1 1 1\n1 1 1\n1 1 1\n' > same.xyz
expect_fail 2 "nanpts.xyz:3: coordinate is not a finite number" o.exr -- $Tr --points nanpts.xyz -o o.exr
expect_fail 2 "short.xyz:3: expected three numbers" o.exr -- $Tr --points short.xyz -o o.exr
expect_fail 2 "empty.xyz: no points" o.exr -- $Tr --points empty.xyz -o o.exr
expect_fail 2 "all points are collinear" o.exr -- $Tr --points line.xyz -o o.exr
expect_fail 2 "fewer than three distinct points" o.exr -- $Tr --points same.xyz -o o.exr
expect_fail 2 "nofile.xyz: cannot open points" o.exr -- $Tr --points nofile.xyz -o o.exr
expect_fail 2 "badcenters.csv:1: fractal dimension D = 3.4 is outside (2, 3)" o.exr -- $Tr --points pts.csv --centers badcenters.csv -o o.exr
expect_fail 2 "dimension" o.exr -- $Tr --points pts.csv --dimension 3 -o o.exr
expect_fail 2 "hurst" o.exr -- $Tr --points pts.csv --hurst 1 -o o.exr
expect_fail 2 "not both" o.exr -- $Tr --points pts.csv --hurst 0.5 --dimension 2.5 -o o.exr
expect_fail 2 "give the survey points" o.exr -- $Tr -o o.exr
expect_fail 2 "sample is the step of from-heightfield" o.exr -- $Tr --points pts.csv --sample 4 -o o.exr
expect_fail 2 "insert" o.exr -- $Tr --points pts.csv --insert 1000000000 -o o.exr
expect_fail 2 "mesh format comes from the extension" o.exr -- $Tr --points pts.csv --mesh m.stl -o o.exr
expect_fail 2 "drop hurst" o.exr -- $Tr --points pts.csv --centers badcenters.csv --hurst 0.7 -o o.exr
printf '0 0 5\n1 0 5\n0 1 5\n' > flat.xyz
expect_fail 2 "give sigma" o.exr -- $Tr --points flat.xyz -o o.exr
expect_fail 2 "nodir/m.ply: cannot create the mesh" o.exr -- $Tr --points pts.csv --mesh nodir/m.ply -o o.exr
[ ! -e nodir/m.ply ] && ok || bad "a mesh was left behind"
expect_fail 2 "nodir/o.exr: cannot create the output" tm.ply -- $Tr --points pts.csv --mesh tm.ply -o nodir/o.exr
if "$FB" terrain --size 64x64 --points pts.csv --insert 5000 --mesh tm.ply -o tr.exr --preview tr.png --json > tr.json 2> err.txt; then ok; else bad "terrain failed: $(cat err.txt)"; fi
valid_exr tr.exr
# --json: one object; the layer's summary within it, the outputs with their sizes
tsum() { python3 -c "import json; r = json.load(open('tr.json')); s = r['layers'][0]['summary']; print($1)"; }
[ "$(tsum "s['input_points'], s['duplicates'], s['inserted']")" = "300 0 5000" ] && ok || bad "terrain --json summary: $(cat tr.json)"
[ "$(tsum "[(o['path'], o['what']) for o in r['outputs']]")" = "[('tr.exr', 'output'), ('tr.png', 'preview'), ('tm.ply', 'mesh')]" ] && ok ||
  bad "terrain --json outputs: $(tsum "r['outputs']")"
[ "$(tsum "[o['bytes'] for o in r['outputs'] if o['path'] == 'tm.ply'][0]")" = "$(stat -c %s tm.ply)" ] && ok || bad "--json: the mesh's size"
[ "$(tsum "r['layers'][0]['backend'], r['command']")" = "native terrain" ] && ok || bad "--json: backend and command"
"$FB" info tr.exr | grep -q "layer terrain .*Y (float)" && ok || bad "terrain layer channels"
# the PLY: header counts match the summary, and the size is exact (44 bytes a vertex: x, y, z as
# double, the normal and u, v as float; 13 a face)
nv=$(grep -a -m1 "element vertex" tm.ply | awk '{print $3}')
nf=$(grep -a -m1 "element face" tm.ply | awk '{print $3}')
hdr=$(grep -a -b -m1 "end_header" tm.ply | cut -d: -f1)
[ "$nv" = 5300 ] && ok || bad "PLY vertices $nv, wanted 5300"
[ "$(stat -c %s tm.ply)" = $((hdr + 11 + 44 * nv + 13 * nf)) ] && ok || bad "PLY size does not match its header"
# normals and texture coordinates: on a plane z = 0.1 x + 0.2 y + 5 with sigma 0 every inserted point
# stays on it, so every normal is the plane's, (-0.1, -0.2, 1) / |.|; u, v run 0..1 over the frame
printf '0 0 5\n100 0 15\n0 50 15\n100 50 25\n30 20 12\n' > plane.xyz
for fmt in ply obj; do
  "$FB" terrain --size 32x16 --points plane.xyz --insert 500 --sigma 0 --mesh plane.$fmt -o plane.exr --quiet
  python3 - plane.$fmt << 'PY' && ok || bad "mesh normals or texture coordinates ($fmt)"
import math, struct, sys
path = sys.argv[1]
want = [c / math.sqrt(0.01 + 0.04 + 1) for c in (-0.1, -0.2, 1)]
verts = []
if path.endswith('.ply'):
    d = open(path, 'rb').read()
    head = d[:d.index(b'end_header\n') + 11].decode()
    assert 'property float nx' in head and 'property float u' in head, head
    nv = int(head.split('element vertex ')[1].split()[0])
    for i in range(nv):
        x, y, z, nx, ny, nz, u, v = struct.unpack('<3d5f', d[len(head) + 44 * i:len(head) + 44 * (i + 1)])
        verts.append((x, y, z, (nx, ny, nz), u, v))
else:
    vs, vn, vt = [], [], []
    for line in open(path):
        w = line.split()
        if not w: continue
        if w[0] == 'v': vs.append(tuple(map(float, w[1:4])))
        elif w[0] == 'vn': vn.append(tuple(map(float, w[1:4])))
        elif w[0] == 'vt': vt.append(tuple(map(float, w[1:3])))
        elif w[0] == 'f': assert all(len(c.split('/')) == 3 for c in w[1:]), line
    assert len(vs) == len(vn) == len(vt) == 505, (len(vs), len(vn), len(vt))
    verts = [(p[0], p[1], p[2], n, t[0], t[1]) for p, n, t in zip(vs, vn, vt)]
assert len(verts) == 505
for x, y, z, n, u, v in verts:
    assert abs(z - (0.1 * x + 0.2 * y + 5)) < 1e-9, (x, y, z)
    assert all(abs(a - b) < 1e-6 for a, b in zip(n, want)), (n, want)
    assert abs(u - x / 100) < 1e-6 and abs(v - y / 50) < 1e-6, (x, y, u, v)
assert min(t[4] for t in verts) == 0 and max(t[4] for t in verts) == 1
PY
done
[ "$(tsum "s['triangles']")" = "$nf" ] && ok || bad "PLY faces $nf differ from the summary"
# the smooth surface is the same whatever the threads and strips
"$FB" $Tr --points pts.csv --insert 5000 --interpolation smooth --backend native --threads 1 --strip-rows 3 -o sm1.exr
"$FB" $Tr --points pts.csv --insert 5000 --interpolation smooth --backend native -o sm2.exr
check "smooth: the same bits for 1 thread and 3-row strips as for the defaults" "$FB" compare sm1.exr sm2.exr --quiet
check "smooth differs from linear" test "$("$FB" compare sm2.exr tr.exr --quiet 2>/dev/null | tail -1)" != "result: PASS"
# determinism: threads, strip rows, backend; the seed changes the terrain
"$FB" $Tr --points pts.csv --insert 5000 --backend native --threads 1 --strip-rows 3 -o tn1.exr
"$FB" $Tr --points pts.csv --insert 5000 --backend native --threads 2 --strip-rows 64 -o tn2.exr
"$FB" $Tr --points pts.csv --insert 5000 -o tv1.exr
cmp -s tn1.exr tn2.exr && ok || bad "terrain depends on threads or strip rows"
"$FB" compare tn1.exr tv1.exr --max-abs 0 > /dev/null && ok || bad "terrain differs between backends"
"$FB" $Tr --points pts.csv --insert 5000 --seed 2 -o ts2.exr
"$FB" compare tn1.exr ts2.exr > /dev/null; [ $? -eq 1 ] && ok || bad "terrain ignores the seed"
# every refinement flag changes the terrain
for f in "--order sweep" "--variance local" "--variance additions" "--hurst 0.5" "--dimension 2.5" "--sigma 3" "--insert 4000" "--bounds 10,90,10,90"; do
  "$FB" $Tr --points pts.csv --insert 5000 $f -o tf.exr
  "$FB" compare tn1.exr tf.exr > /dev/null; [ $? -eq 1 ] && ok || bad "terrain $f changed nothing"
done
# a height field sampled back: the refined terrain of a sampled fbm
"$FB" fbm --size 65x65 --quiet --float -o hf.exr
if "$FB" $Tr --from-heightfield hf.exr --sample 8 --insert 2000 --sigma 0.01 --mesh hf.obj -o th.exr; then ok; else bad "from-heightfield failed"; fi
[ "$(grep -c '^v ' hf.obj)" = $((81 + 2000)) ] && ok || bad "height field sampled at step 8 of 65 should give 81 points"
expect_fail 2 "no channel fbm.X" o.exr -- $Tr --from-heightfield hf.exr:fbm.X -o o.exr
# centres: regions of their own D
printf 'x,y,D,sigma\n25,50,2.1,\n75,50,2.7,0.5\n' > centers.csv
"$FB" $Tr --points pts.csv --centers centers.csv --insert 3000 -o tc.exr && ok || bad "terrain with centres failed"
"$FB" $Tr --points pts.csv --centers centers.csv --insert 3000 --variance additions -o tca.exr && ok ||
  bad "terrain additions with centres failed"
"$FB" compare tc.exr tca.exr > /dev/null; [ $? -eq 1 ] && ok || bad "additions with centres changed nothing"
# --variance additions on the docs' survey: no variance clamped (the stage variance clamps most of them),
# the same bits for any thread count
"$FB" terrain --points "$ROOT/docs/examples/survey.csv" --insert 20000 --size 128x100 --variance additions --threads 1 \
  -o sa1.exr --json > sa.json && ok || bad "additions on the survey failed"
"$FB" terrain --points "$ROOT/docs/examples/survey.csv" --insert 20000 --size 128x100 --variance additions --threads 2 \
  --strip-rows 16 -o sa2.exr && cmp -s sa1.exr sa2.exr && ok || bad "additions depends on the thread count"
[ "$(python3 -c "import json; s = json.load(open('sa.json'))['layers'][0]['summary']; print(s['clamped_variances'], s['inserted'])")" = "0 20000" ] &&
  ok || bad "additions clamped variances: $(cat sa.json)"
"$FB" terrain --help | grep -q -- "--from-heightfield" && ok || bad "terrain --help lists no --from-heightfield"

cli_finish
