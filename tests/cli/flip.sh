#!/usr/bin/env bash
# compare --flip: the numbers of NVIDIA's FLIP tool (v1.6, tests/data/flip/expected.csv) through the
# command line and its JSON, for an LDR (PNG) and an HDR (EXR) pair; --flip-fail, --flip-warn and
# --flip-stat on both sides of the measured values; the error map in the diff EXR (LAYER.FLIP) and
# as --flip-png against the tool's own map; the zero-median rule on a reference three quarters
# black, against the exposure solved here; a layer's Y as grey; a non-finite pixel that differs
# failing every statistic.
# Usage: flip.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
D=$ROOT/tests/data/flip
code() { "$FB" compare "$@" > out.txt 2> err.txt; echo $?; }
# expected ROWKEY: checks out.json against expected.csv's row "REF,TEST,MODE" (python3: an independent reader)
expected() {
  python3 - "$D/expected.csv" "$1" << 'PY'
import csv, json, sys
rows = {f"{r['reference']},{r['test']},{r['mode']}": r for r in csv.DictReader(open(sys.argv[1]))}
e = rows[sys.argv[2]]
f = json.load(open("out.json"))["flip"]
assert len(f) == 1, f
f = f[0]
for k, j in [("mean", "mean"), ("weighted_median", "weighted_median"), ("weighted_q1", "weighted_q1"),
             ("weighted_q3", "weighted_q3"), ("min", "min"), ("max", "max")]:
    assert abs(f[j] - float(e[k])) <= 1e-4, (k, f[j], e[k])
assert f["mode"] == e["mode"], f["mode"]
if e["mode"] == "HDR":
    assert abs(f["start_exposure"] - float(e["start_exposure"])) <= 1e-4
    assert abs(f["stop_exposure"] - float(e["stop_exposure"])) <= 1e-4
    assert f["num_exposures"] == int(e["num_exposures"]) and f["zero_median"] is False
PY
}
"$FB" compare "$D/j4_rgb.png" "$D/j1_rgb.png" --flip --max-abs 1 --json > out.json
check "LDR-FLIP through compare matches the tool (j4 vs j1)" expected "j4_rgb.png,j1_rgb.png,LDR"
"$FB" compare "$D/b8_rgb.exr" "$D/b6_rgb.exr" --flip --max-abs 1 --json > out.json
check "HDR-FLIP through compare matches the tool (b8 vs b6)" expected "b8_rgb.exr,b6_rgb.exr,HDR"
"$FB" compare "$D/j4_rgb.exr" "$D/j4v_rgb.exr" --flip --max-abs 1 --json > out.json
check "HDR-FLIP through compare matches the tool (j4 vs j4v)" expected "j4_rgb.exr,j4v_rgb.exr,HDR"

# thresholds on both sides of the measured mean 0.015374 and max 0.307867 (b8 vs b6, HDR)
P="$D/b8_rgb.exr $D/b6_rgb.exr"
check "--flip-fail below the mean fails" test "$(code $P --flip-fail 0.015)" = 1
check "  and says why" grep -q "RGB: FLIP mean 0.015374 beyond --flip-fail 0.015" out.txt
check "--flip-fail above the mean passes" test "$(code $P --flip-fail 0.016)" = 0
check "--flip-warn below the mean warns (exit 0)" test "$(code $P --flip-warn 0.015 --max-abs 1)" = 0
check "  with WARN" grep -q "^result: WARN: RGB: FLIP mean" out.txt
check "--flip-stat max below the max fails" test "$(code $P --flip-stat max --flip-fail 0.3)" = 1
check "--flip-stat max above it passes" test "$(code $P --flip-stat max --flip-fail 0.31)" = 0
check "--flip-stat median (0.034050) below fails" test "$(code $P --flip-stat median --flip-fail RGB=0.034)" = 1
check "--flip-stat median above passes" test "$(code $P --flip-stat median --flip-fail RGB=0.0341)" = 0
check "a FLIP rule naming no layer is bad usage" test "$(code $P --flip-fail sky=0.1)" = 2
check "--flip-mode ldr on the EXRs is LDR-FLIP" test "$(code $P --flip-mode ldr --max-abs 1 --json)" = 0
check "  (mode LDR in the JSON)" python3 -c "import json; assert json.load(open('out.txt'))['flip'][0]['mode'] == 'LDR'"

# the maps: the diff EXR's FLIP channel and --flip-png against the tool's map (round(255 e)), 1/255 apart
"$FB" compare $P --flip --max-abs 1 --diff d.exr --flip-png f.png --quiet > /dev/null
check "the diff EXR holds FLIP" sh -c "'$FB' info d.exr | grep -q 'FLIP (float)'"
oiiotool "$D/maps/flip.b8.b6.exr.png" --ch Y=R -o tool.png
oiiotool "$D/maps/flip.b8.b6.exr.png" --ch FLIP=R -d float -o tool.exr
check "--flip-png is the tool's map within 1/255" test "$(code f.png tool.png --max-abs 0.00393)" = 0
# the EXR holds e, the tool's map round(255 e) / 255: within 1.5/255
check "the diff's FLIP is the tool's map within 1.5/255" \
  test "$(code d.exr tool.exr --ignore-missing --max-abs 0.00589)" = 0

# zero median: three quarters black, the rest white; the tool's stop exposure would be +inf, ours
# comes from the positive luminances' median (1): start = stop = log2(x) with ACES(x) = 0.85
oiiotool --create 64x64 3 --fill:color=1,1,1 16x64+48+0 -d float -o zref.exr
oiiotool --create 64x64 3 --fill:color=0.8,0.8,0.8 16x64+48+0 -d float -o ztest.exr
"$FB" compare zref.exr ztest.exr --flip --max-abs 1 --json > out.json
check "the zero-median reference gets the documented exposures" python3 - << 'PY'
import json, math
f = json.load(open("out.json"))["flip"][0]
c0, c1, c3, c4, c5, t = 0.36 * 2.51, 0.6 * 0.03, 0.36 * 2.43, 0.6 * 0.59, 0.14, 0.85
a, b, c = c0 - t * c3, c1 - t * c4, -t * c5
x = (-b + math.sqrt(b * b - 4 * a * c)) / (2 * a)
assert f["zero_median"] is True, f
assert abs(f["start_exposure"] - math.log2(x)) < 1e-5 and abs(f["stop_exposure"] - math.log2(x)) < 1e-5, f
assert f["num_exposures"] == 2 and 0.01 < f["mean"] < 1, f
PY

# a layer's Y as grey: the same picture as R = G = B, within what both promise against the tool
# (the grey path filters Y alone; the colour path carries the tool's rounding in Cx and Cz)
oiiotool zref.exr --ch Y=R -o yref.exr
oiiotool ztest.exr --ch Y=R -o ytest.exr
"$FB" compare yref.exr ytest.exr --flip --max-abs 1 --json > y.json
check "Y as grey equals R = G = B" python3 -c "
import json
a = json.load(open('out.json'))['flip'][0]; b = json.load(open('y.json'))['flip'][0]
assert b['channels'] == 'Y' and b['name'] == 'Y', b
assert all(abs(a[k] - b[k]) <= 1e-4 for k in ('mean', 'weighted_median', 'weighted_q1', 'weighted_q3', 'max')), (a, b)
assert a['num_exposures'] == b['num_exposures'] and a['start_exposure'] == b['start_exposure'], (a, b)"

# non-finite: one infinite pixel in the test fails RMSE, PSNR, SSIM and FLIP (each at its worst)
oiiotool zref.exr --fill:color=1e39,1e39,1e39 1x1+3+3 -d float -o inf.exr
check "an infinite pixel fails --rmse" test "$(code zref.exr inf.exr --rmse 0.001)" = 1
check "  and --psnr" test "$(code zref.exr inf.exr --psnr 10)" = 1
check "  and --ssim" test "$(code zref.exr inf.exr --ssim 0.5)" = 1
check "  and --flip-stat max --flip-fail 0.99" test "$(code zref.exr inf.exr --flip-stat max --flip-fail 0.99)" = 1
check "identical files pass every statistic" test "$(code zref.exr zref.exr --rmse 0 --psnr 100 --ssim 1 --flip-fail 0)" = 0
cli_finish
