#!/usr/bin/env bash
# The rivers layer end to end: its channels; the same bits for any thread count and strip height, on
# either backend (it runs on the host), for regions (cut from the whole: merged, the one bake) and
# for tasks (plan, render --task, merge); every key reaches the model; the summary; the heights as
# an engine heightmap and as tiles; plant instances standing on it, kept off the river mask and off
# steep slopes; amplified from a coarse grid, the same bits for threads, strips, regions, tasks and
# backends, and within the memory limit where the whole grid is not. Usage: rivers.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
# an fBm shape drives the uplift, a second fBm layer is banded (so that tasks split something)
cat > s.json << 'EOF'
{"size": [97, 81], "seed": 4, "layers": [
  {"type": "fbm", "name": "shape", "octaves": 3, "frequency": 1.5},
  {"type": "rivers", "name": "r", "uplift-map": "shape", "extent": 9700, "steps": 40, "dt": 20000, "kd": 0.05},
  {"type": "fbm", "name": "detail", "octaves": 4}]}
EOF
"$FB" render s.json --backend native --quiet -o base.exr && ok || bad "rivers render failed"
"$FB" info base.exr | grep -q "layer r .*Y (float), area (float), lake (float), river (half)" && ok ||
  bad "rivers channels: $("$FB" info base.exr | grep 'layer r')"
same() { "$FB" compare base.exr "$1" --max-abs 0 > /dev/null; }
# the bits of scene $1 (baked in $2) do not depend on threads, strips or the backend
invariant() {
  for f in "--threads 1" "--threads 2 --strip-rows 7" "--threads 3 --strip-rows 1"; do
    "$FB" render "$1" --backend native --quiet $f -o t.exr && "$FB" compare "$2" t.exr --max-abs 0 > /dev/null &&
      ok || bad "$1 differs with $f"
  done
  if have_vulkan; then
    "$FB" render "$1" --backend vulkan --quiet -o v.exr && "$FB" compare "$2" v.exr --max-abs 0 > /dev/null &&
      ok || bad "$1 differs on Vulkan"
  fi
}
invariant s.json base.exr
# regions cut the whole result: three bands and a window merge into the one bake
for r in "0,0,97,30" "0,30,97,31" "0,61,97,20"; do
  "$FB" render s.json --backend native --quiet --region "$r" -o "reg-${r//,/-}.exr" || bad "region $r"
done
"$FB" merge reg-*.exr -o merged.exr --quiet && same merged.exr && ok || bad "rivers regions do not merge into the bake"
"$FB" render s.json --backend native --quiet --region 20,10,40,30 -o win.exr &&
  "$FB" render s.json --backend native --quiet --region 0,0,20,81 -o w1.exr &&
  "$FB" render s.json --backend native --quiet --region 60,0,37,81 -o w2.exr &&
  "$FB" render s.json --backend native --quiet --region 20,0,40,10 -o w3.exr &&
  "$FB" render s.json --backend native --quiet --region 20,40,40,41 -o w4.exr &&
  "$FB" merge win.exr w1.exr w2.exr w3.exr w4.exr -o m2.exr --quiet && same m2.exr && ok ||
  bad "a window of rivers is not the whole's"
# tasks: the plan cuts the layer into bands (each task runs the model: the same bits); the tasks
# merge into the one bake
"$FB" plan s.json --tasks 3 --task-startup 0 --json > plan.json &&
  python3 -c "import json, sys; p = json.load(open('plan.json')); s = {l['name']: l['split'] for l in p['layers']}; sys.exit(not (s['r'] == 'bands' and s['detail'] == 'bands'))" &&
  ok || bad "the plan does not cut rivers into bands: $(cat plan.json)"
for k in 0 1 2; do "$FB" render s.json --backend native --quiet --task $k/3 --task-startup 0 -o task$k.exr || bad "task $k"; done
"$FB" merge task*.exr -o tasks.exr --quiet && same tasks.exr && ok || bad "rivers tasks do not merge into the bake"
# amplified: a 50 x 42 model carved into 200 x 167 pixels; the same bits for threads, strips, the
# backend, regions and tasks (each task runs the model); coarse and detail change it
cat > a.json << 'EOF'
{"size": [200, 167], "seed": 4, "layers": [
  {"type": "fbm", "name": "shape", "octaves": 3, "frequency": 1.5},
  {"type": "rivers", "name": "r", "uplift-map": "shape", "extent": 20000, "steps": 40, "dt": 20000, "kd": 0.05,
   "coarse": 50, "river-area": 1e6, "sea-level": 1, "stops": [[0, 0.2, 0.3, 0.1], [1, 0.9, 0.9, 0.9]]}]}
EOF
"$FB" render a.json --backend native --quiet -o abase.exr --json > a.txt 2> /dev/null &&
  python3 -c "import json, sys; r = [l for l in json.load(open('a.txt'))['layers'] if l['name'] == 'r'][0]['summary']; sys.exit(not (r['model'] == [50, 42] and r['width'] == 200))" &&
  ok || bad "rivers amplified: the model's grid: $(cat a.txt)"
asame() { "$FB" compare abase.exr "$1" --max-abs 0 > /dev/null; }
invariant a.json abase.exr
mkdir -p areg
for r in "0,0,200,50" "0,50,200,1" "0,51,120,116" "120,51,80,116"; do
  "$FB" render a.json --backend native --quiet --region "$r" -o "areg/${r//,/-}.exr" || bad "region $r"
done
"$FB" merge areg/*.exr -o merged.exr --quiet && asame merged.exr && ok || bad "amplified regions do not merge into the bake"
"$FB" plan a.json --tasks 4 --task-startup 0 --json > plan.json &&
  python3 -c "import json, sys; p = json.load(open('plan.json')); s = {l['name']: l['split'] for l in p['layers']}; sys.exit(not (s['r'] == 'bands' and p['bands'] == 4))" &&
  ok || bad "the plan does not cut amplified rivers into 4 bands: $(cat plan.json)"
mkdir -p atask
for k in 0 1 2 3; do "$FB" render a.json --backend native --quiet --task $k/4 --task-startup 0 -o atask/$k.exr || bad "task $k"; done
"$FB" merge atask/*.exr -o tasks.exr --quiet && asame tasks.exr && ok || bad "amplified tasks do not merge into the bake"
for kv in coarse=40 detail=0.3; do
  "$FB" render a.json --backend native --quiet --set "layers.r.$kv" -o k.exr &&
    "$FB" compare abase.exr k.exr --layer r --max-abs 1e30,r.Y=0 > /dev/null
  [ $? -eq 1 ] && ok || bad "rivers $kv changed nothing"
done
# the amplified heights for engines: 2 x 2 tiles sharing their edges
mkdir -p atiles
"$FB" render a.json --backend native --quiet --set size=201x167 --set layers.r.heightmap=atiles/r.png --set 'layers.r.tiles=[2, 2]' -o ti.exr &&
  [ "$(ls atiles | grep -c '^r_x[01]_y[01]\.png$')" = 4 ] && [ "$(png_wh atiles/r_x1_y1.png)" = "101 84" ] && ok ||
  bad "amplified rivers tiles: $(ls atiles) $(png_wh atiles/r_x1_y1.png)"
# a coarse grid over half the image's width is the whole grid: the bits of coarse 200
"$FB" render a.json --backend native --quiet --set layers.r.coarse=101 -o k1.exr &&
  "$FB" render a.json --backend native --quiet --set layers.r.coarse=200 -o k2.exr &&
  "$FB" compare k1.exr k2.exr --max-abs 0 > /dev/null && ok || bad "coarse over half the width is not the whole grid"
# the memory: the whole grid of 8192 x 8192 is refused under 1G; amplified (the default above 2047
# wide) it is predicted within it
"$FB" rivers --size 8192x8192 --coarse 8192 --max-memory 1G -o x.exr 2> m.txt
[ $? -eq 2 ] && [ ! -e x.exr ] && grep -q "stream-power erosion of 8192 x 8192 cells needs about" m.txt && ok ||
  bad "whole 8192: $(cat m.txt)"
"$FB" rivers --size 8192x8192 --coarse 8192 --max-memory 1G --dry-run -o x.exr > m.txt 2>&1 &&
  grep -q "so the bake would be refused" m.txt && ok || bad "whole 8192, --dry-run: $(cat m.txt)"
"$FB" rivers --size 8192x8192 --max-memory 1G --dry-run -o x.exr > m.txt 2>&1 && ! grep -q "would be refused" m.txt &&
  ok || bad "amplified 8192: $(cat m.txt)"
# every key of the model changes the heights (river-area the mask alone)
for kv in uplift=0.002 K=1e-5 m=0.45 n=1.2 kd=0.2 dt=30000 steps=30 noise=3 lakes=keep 'outlets=["south"]' \
  sea-level=2 extent=8000 'uplift-range=[-0.5,0.5]' input=5; do
  "$FB" render s.json --backend native --quiet --set "layers.r.$kv" -o k.exr &&
    "$FB" compare base.exr k.exr --layer r --max-abs 1e30,r.Y=0 > /dev/null
  [ $? -eq 1 ] && ok || bad "rivers $kv changed nothing"
done
"$FB" render s.json --backend native --quiet --set layers.r.river-area=1e6 -o k.exr &&
  "$FB" compare base.exr k.exr --layer r --max-abs 1e30,r.Y=0 > /dev/null &&
  ! "$FB" compare base.exr k.exr --layer r --max-abs 1e30,r.river=0 > /dev/null && ok || bad "river-area"
# the summary, as text and JSON
"$FB" render s.json --backend native -o j.exr --json > j.json 2> /dev/null &&
  python3 -c "import json, sys; r = [l for l in json.load(open('j.json'))['layers'] if l['name'] == 'r'][0]['summary']; sys.exit(not (r['generator'] == 'rivers' and r['steps'] == 40 and 0 < r['largest_basin'] <= 1 and r['river_cells'] > 0))" &&
  ok || bad "rivers JSON summary: $(cat j.json)"
# the heights for engines: one 16-bit heightmap, and 2 x 2 tiles sharing their edges
"$FB" render s.json --backend native --set layers.r.heightmap=r.r16 -o hm.exr 2> hm.txt && [ "$(stat -c %s r.r16)" = $((2 * 97 * 81)) ] &&
  grep -q "heightmap r.r16: layer r's heights" hm.txt && ok || bad "rivers heightmap: $(cat hm.txt)"
mkdir -p tiles
"$FB" render s.json --backend native --quiet --set layers.r.heightmap=tiles/r.png --set 'layers.r.tiles=[2, 2]' -o ti.exr &&
  [ "$(ls tiles | grep -c '^r_x[01]_y[01]\.png$')" = 4 ] && [ "$(png_wh tiles/r_x1_y1.png)" = "49 41" ] && ok ||
  bad "rivers tiles: $(ls tiles)"
# its benchmark row
"$FB" bench --generator rivers --size 64x64 --json --quiet > bench.json &&
  python3 -c "import json, sys; r = [json.loads(l) for l in open('bench.json')]; r = [x for x in r if x.get('generator') == 'rivers']; sys.exit(not (r and r[0]['unit'] == 'Mcell-steps/s' and r[0]['rate'] > 0))" &&
  ok || bad "rivers bench: $(cat bench.json)"
# colour by height: R, G, B; under an overhead light with no ambient and one grey, the land is that
# grey times the cosine of its slope (from the EXR's own heights, central differences), the water
# its colour times the same
python3 - << 'PY' > c.json
import json
s = json.load(open('s.json'))
s['compression'] = 'none'
s['layers'][1].update({'stops': [[0, 0.5, 0.5, 0.5], [1, 0.5, 0.5, 0.5]], 'light': [0, 90], 'ambient': 0,
                       'water-colour': [0, 0, 1]})
print(json.dumps(s))
PY
"$FB" render c.json --backend native --quiet -o c.exr && "$FB" info c.exr | grep -q "layer r .*B (float), G (float), R (float), Y (float)" &&
  python3 - << 'PY' && ok || bad "rivers colour"
import math, struct, sys
def channels(path):
    d = open(path, 'rb').read()
    i, attrs = 8, {}
    while d[i] != 0:
        n = d.index(b'\0', i); t = d.index(b'\0', n + 1); size = struct.unpack('<i', d[t + 1:t + 5])[0]
        attrs[d[i:n].decode()] = d[t + 5:t + 5 + size]; i = t + 5 + size
    chans, j, cl = [], 0, attrs['channels']
    while cl[j] != 0:
        n = cl.index(b'\0', j); chans.append((cl[j:n].decode(), struct.unpack('<i', cl[n + 1:n + 5])[0])); j = n + 17
    x0, y0, x1, y1 = struct.unpack('<4i', attrs['dataWindow']); W, H = x1 - x0 + 1, y1 - y0 + 1
    out, off = {c: [] for c, _ in chans}, i + 1 + 8 * H
    for y in range(H):
        p = off + 8
        for c, t in chans:
            sz = 2 if t == 1 else 4
            out[c].append(struct.unpack('<%d%s' % (W, 'e' if t == 1 else 'f' if t == 2 else 'I'), d[p:p + sz * W]))
            p += sz * W
        off = p
    return W, H, out
W, H, c = channels('c.exr')
Y, R, G, B, river = c['r.Y'], c['r.R'], c['r.G'], c['r.B'], c['r.river']
cell, worst, water = 9700 / W, 0, 0
for y in range(H):
    for x in range(W):
        xl, xr, yu, yd = max(x - 1, 0), min(x + 1, W - 1), max(y - 1, 0), min(y + 1, H - 1)
        gx = (Y[y][xr] - Y[y][xl]) / ((xr - xl) * cell)
        gy = (Y[yu][x] - Y[yd][x]) / ((yd - yu) * cell)
        light = 1 / math.sqrt(gx * gx + gy * gy + 1)
        want = (0, 0, light) if river[y][x] > 0 else (0.5 * light,) * 3
        water += river[y][x] > 0
        worst = max(worst, max(abs(a - b) for a, b in zip((R[y][x], G[y][x], B[y][x]), want)))
print('colour: largest difference %.3g, %d water pixels' % (worst, water))
sys.exit(not (worst < 1e-5 and water > 0))
PY
# plants on it: instances stand on the surface; kept off the river mask (none within 100 units of a
# river pixel's centre, by this script's own reading of the mask) and off slopes steeper than 20
# degrees; some are kept and some left out
cat > p.json << 'EOF'
{"size": [200, 167], "seed": 4, "compression": "none", "layers": [
  {"type": "fbm", "name": "shape", "octaves": 3, "frequency": 1.5},
  {"type": "rivers", "name": "r", "uplift-map": "shape", "extent": 10000, "steps": 40, "dt": 20000, "kd": 0.05,
   "river-area": 1e6},
  {"type": "ifs", "name": "plants", "maps": [[0.5, 0, 0, 0.5, 0, 0, 1], [0.5, 0, 0, 0.5, 0.5, 0, 1],
   [0.5, 0, 0, 0.5, 0.25, 0.45, 1]], "condensation": {"preset": "bush", "height": 0.1}, "bounds": [0, 1, 0, 0.835],
   "points": 100000, "instances": "all.csv", "instances-surface": "r", "instances-min-size": 0.3}]}
EOF
"$FB" render p.json --backend native --quiet -o p.exr &&
  "$FB" render p.json --backend native --quiet --set layers.plants.instances=away.csv --set layers.plants.instances-avoid=r.river \
    --set layers.plants.instances-avoid-distance=100 --set layers.plants.instances-max-slope=20 -o p2.exr &&
  python3 - << 'PY' && ok || bad "instances kept off the rivers and steep slopes"
import csv, math, struct, sys
def channel(path, name):
    d = open(path, 'rb').read()
    i, attrs = 8, {}
    while d[i] != 0:
        n = d.index(b'\0', i); t = d.index(b'\0', n + 1); size = struct.unpack('<i', d[t + 1:t + 5])[0]
        attrs[d[i:n].decode()] = d[t + 5:t + 5 + size]; i = t + 5 + size
    chans, j, cl = [], 0, attrs['channels']
    while cl[j] != 0:
        n = cl.index(b'\0', j); chans.append((cl[j:n].decode(), struct.unpack('<i', cl[n + 1:n + 5])[0])); j = n + 17
    x0, y0, x1, y1 = struct.unpack('<4i', attrs['dataWindow']); W, H = x1 - x0 + 1, y1 - y0 + 1
    off = i + 1 + 8 * H
    rows = []
    for y in range(H):
        p = off + 8; vals = {}
        for c, t in chans:
            sz = 2 if t == 1 else 4
            raw = d[p:p + sz * W]; p += sz * W
            vals[c] = struct.unpack('<%d%s' % (W, 'e' if t == 1 else 'f' if t == 2 else 'I'), raw)
        rows.append(vals[name]); off = p
    return W, H, rows
W, H, river = channel('p2.exr', 'r.river')
cell = 10000 / W
wet = [((x + 0.5) * cell, H * cell - (y + 0.5) * cell) for y in range(H) for x in range(W) if river[y][x] >= 0.5]
def near(rows):
    return sum(1 for r in rows if any(math.hypot(float(r['x']) - X, -float(r['z']) - Y) < 100 - 1e-3 for X, Y in wet))
def steep(rows):
    return sum(1 for r in rows if float(r['ny']) < math.cos(math.radians(20)) - 1e-6)
rows, every = list(csv.DictReader(open('away.csv'))), list(csv.DictReader(open('all.csv')))
ok = wet and near(rows) == 0 and steep(rows) == 0 and near(every) > 0 and steep(every) > 0 and len(rows) >= 20
print('%d of %d plants kept; %d (of %d) near a river pixel, %d (of %d) on steep slopes'
      % (len(rows), len(every), near(rows), near(every), steep(rows), steep(every)))
sys.exit(not ok)
PY
cli_finish
