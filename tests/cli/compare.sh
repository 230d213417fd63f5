#!/usr/bin/env bash
# compare in idiff's vocabulary: --fail/--max-abs, --failpercent, --hardfail, the warn family (exit
# 0 with WARN), per-channel and per-layer thresholds, the JSON report, PNG inputs, mismatched sizes
# and channel sets as failures with a reason, the heat-map picture, and SSIM against an independent
# implementation (tests/ref/ssim_reference.py) and the closed form for constant pictures.
# Usage: compare.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
N="--backend native --quiet"
# two layers; in b.exr layer a is off by 1e-3 everywhere and layer b by 1e-5
scene() { # scene DA DB
  cat << JSON
{"size": [48, 40], "layers": [{"type": "fbm", "name": "h", "octaves": 3},
 {"type": "op", "name": "a", "op": "add", "inputs": ["h", $1]},
 {"type": "op", "name": "b", "op": "add", "inputs": ["h", $2]}]}
JSON
}
scene 0 0 > a.json
scene 0.001 0.00001 > b.json
"$FB" render a.json $N -o a.exr
"$FB" render b.json $N -o b.exr
# json_get FILE EXPR: a value of the JSON report (python3 reads it: an independent parser)
json_get() { python3 -c "import json,sys; r=json.load(open('$1')); print($2)"; }
code() { "$FB" compare "$@" > out.txt 2> err.txt; echo $?; }

check "identical files pass" test "$(code a.exr a.exr)" = 0
check "identical: the result line" grep -qx "result: PASS" out.txt
check "no threshold: any difference fails" test "$(code a.exr b.exr)" = 1
check "--fail is --max-abs" test "$(code a.exr b.exr --fail 0.002)" = 0
check "--max-abs 0.002 passes" test "$(code a.exr b.exr --max-abs 0.002)" = 0
check "--max-abs 0.0005 fails (layer a is off by 1e-3)" test "$(code a.exr b.exr --max-abs 0.0005)" = 1
check "the reason names the channel" grep -q "result: FAIL: a.Y: 100% of pixels beyond 0.0005" out.txt
# per layer and per channel, in one run
check "per layer: a=2e-3,b=2e-5 passes" test "$(code a.exr b.exr --max-abs a=2e-3,b=2e-5)" = 0
check "per layer: b=1e-6 fails" test "$(code a.exr b.exr --max-abs a=2e-3,b=1e-6)" = 1
check "per layer: the failing channel is b.Y" grep -q "result: FAIL: b.Y" out.txt
check "a channel rule beats the value for all" test "$(code a.exr b.exr --max-abs 1e-6,a.Y=2e-3,b.Y=2e-5,h=0)" = 0
check "a channel rule beats its layer's" test "$(code a.exr b.exr --max-abs a=1e-9,a.Y=2e-3,b=2e-5)" = 0
check "a rule naming no channel is bad usage" test "$(code a.exr b.exr --max-abs c.Y=1)" = 2
check "... named on stderr" grep -q "no compared channel is c.Y" err.txt
check "a malformed rule is bad usage" test "$(code a.exr b.exr --max-abs a.Y=)" = 2
check "a negative value is bad usage" test "$(code a.exr b.exr --fail -1)" = 2
# --failpercent and --hardfail
check "--failpercent 100 lets every pixel fail" test "$(code a.exr b.exr --failpercent 100)" = 0
check "--fail-percent is --failpercent" test "$(code a.exr b.exr --fail-percent 100)" = 0
check "--hardfail beyond the largest error passes" test "$(code a.exr b.exr --failpercent 100 --hardfail 0.01)" = 0
check "--hardfail below it fails whatever --failpercent" test "$(code a.exr b.exr --failpercent 100 --hardfail 1e-4)" = 1
check "--hardfail alone: only the largest error counts" test "$(code a.exr b.exr --hardfail 2e-3)" = 0
# warnings: exit 0, told apart by the line and the JSON
check "a warning exits 0" test "$(code a.exr b.exr --max-abs 0.01 --warn 1e-4)" = 0
check "a warning says WARN" grep -q "result: WARN: a.Y" out.txt
check "--warnpercent 100 silences it" test "$(code a.exr b.exr --max-abs 0.01 --warn 1e-4 --warnpercent 100)" = 0
check "... to a pass" grep -qx "result: PASS" out.txt
check "--hardwarn" test "$(code a.exr b.exr --max-abs 0.01 --hardwarn 1e-4)" = 0
check "--hardwarn warns" grep -q "result: WARN" out.txt
check "a failure outranks a warning" test "$(code a.exr b.exr --max-abs b=0.01,a=1e-4 --warn 1e-9)" = 1
# the JSON report
"$FB" compare a.exr b.exr --max-abs 0.01 --warn a=1e-4 --json > r.json
check "JSON: result warn" test "$(json_get r.json "r['result']")" = warn
check "JSON: three channels" test "$(json_get r.json "len(r['channels'])")" = 3
check "JSON: a.Y's largest error is 1e-3 (float)" test "$(json_get r.json "round([c for c in r['channels'] if c['name']=='a.Y'][0]['max_abs'], 7)")" = 0.001
check "JSON: the thresholds per channel (a.Y, b.Y, h.Y)" test "$(json_get r.json "[c['thresholds'].get('warn') for c in r['channels']]")" = "[0.0001, None, None]"
check "JSON: the size" test "$(json_get r.json "r['size']")" = "[48, 40]"
# mismatches are failures with a reason, not errors
"$FB" fbm $N --size 40x40 -o small.exr
check "different sizes fail" test "$(code a.exr small.exr)" = 1
check "... saying so" grep -q "result: FAIL: the sizes differ: a.exr is 48 x 40, small.exr is 40 x 40" out.txt
"$FB" compare a.exr small.exr --json > m.json
check "... in JSON too" test "$(json_get m.json "r['result'] + ': ' + r['reason'][:16]")" = "fail: the sizes differ"
"$FB" fbm $N --size 48x40 --layer q -o q.exr
check "different channel sets fail" test "$(code a.exr q.exr)" = 1
check "... naming the channels" grep -q "result: FAIL: the channel sets differ: a.Y only in a.exr, b.Y only in a.exr, h.Y only in a.exr, q.Y only in q.exr" out.txt
check "a missing file is an error (2)" test "$(code a.exr nothere.exr)" = 2
check "--quiet: the result line alone" test "$("$FB" compare a.exr b.exr --max-abs 0.002 --quiet)" = "result: PASS"
check "a misspelt flag gets a hint" test "$(code a.exr b.exr --failpercnt 1)" = 2
check "... the hint" grep -q "did you mean --failpercent" err.txt
# pictures: the threshold picture and the heat map (PNG, RGB, 48 x 40)
"$FB" compare a.exr b.exr --max-abs 1e-4 --diff-png d.png > /dev/null
"$FB" compare a.exr b.exr --heat --diff-png heat.png > heat.txt
png_rgb() { python3 -c "
import struct,sys
d=open('$1','rb').read(); w,h,bits,ct=struct.unpack('>IIBB',d[16:26]); print(w,h,bits,ct)"; }
check "the diff picture is an RGB PNG of the image's size" test "$(png_rgb d.png)" = "48 40 8 2"
check "the heat map too" test "$(png_rgb heat.png)" = "48 40 8 2"
check "the heat map's scale is printed" grep -q "black 1e-8" heat.txt
# PNG inputs
python3 "$ROOT/tests/ref/ssim_reference.py" . > ssim.json
check "PNG against itself passes" test "$(code base.png base.png)" = 0
check "PNG channels are named Y" grep -q "^Y " out.txt
check "a PNG beside an EXR: the channel sets differ" test "$(code base.png a.exr)" = 1
# SSIM: the same as an independent implementation, and the closed form for constant pictures
for v in noisy shifted flat; do
  "$FB" compare base.png $v.png --ssim 0 --json > s.json
  got=$(json_get s.json "r['channels'][0]['ssim']")
  want=$(json_get ssim.json "r['$v']")
  check "SSIM base/$v: $got, the reference $want" python3 -c "import sys; sys.exit(abs($got - $want) > 1e-9)"
done
"$FB" compare c02.png c04.png --ssim 0 --json > s.json
got=$(json_get s.json "r['channels'][0]['ssim']")
want=$(json_get ssim.json "r['constant_closed_form']")
check "SSIM of constants 0.2 and 0.4: $got, (2ab + C1) / (a^2 + b^2 + C1) = $want" python3 -c "import sys; sys.exit(abs($got - $want) > 1e-12)"
check "SSIM of a picture with itself is 1" test "$(code base.png base.png --ssim 1)" = 0
check "--ssim above the measured value fails" test "$(code base.png noisy.png --ssim 0.97)" = 1
check "--ssim below it passes" test "$(code base.png noisy.png --ssim 0.95)" = 0
"$FB" fbm $N --size 8x8 -o tiny.exr
check "--ssim on 8 x 8 is bad usage" test "$(code tiny.exr tiny.exr --ssim 0.5)" = 2
# the same bits on any thread count: every statistic, FLIP and the diff EXR, 1, 2 and 3 threads
# (130 rows: two blocks of 64 and a partial one; FLIP's bands of 64 likewise)
cat > t1.json << 'JSON'
{"size": [150, 130], "layers": [{"type": "fbm", "name": "h", "octaves": 3},
 {"type": "op", "name": "a", "op": "add", "inputs": ["h", 0.5]}, {"type": "fbm", "name": "c", "octaves": 4}]}
JSON
sed 's/"octaves": 3/"octaves": 4/; s/"octaves": 4}]}/"octaves": 5}]}/' t1.json > t2.json
"$FB" render t1.json $N -o t1.exr
"$FB" render t2.json $N -o t2.exr
for t in 1 2 3; do
  "$FB" compare t1.exr t2.exr --fail 0.01 --ssim 0.5 --idiff-stats --flip --json --threads $t --diff td$t.exr > tj$t.json
  "$FB" compare "$ROOT/tests/data/flip/j4_rgb.exr" "$ROOT/tests/data/flip/j1_rgb.exr" --flip --max-abs 1 --json \
    --threads $t > tc$t.json
done
check "--threads 1, 2, 3: the same report" sh -c "cmp tj1.json tj2.json && cmp tj1.json tj3.json"
check "  and the same diff EXR" sh -c "cmp td1.exr td2.exr && cmp td1.exr td3.exr"
check "  and the same colour FLIP" sh -c "cmp tc1.json tc2.json && cmp tc1.json tc3.json"
check "  (the report holds three FLIP layers and idiff's block)" \
  test "$(json_get tj1.json "len(r['flip']), 'idiff' in r")" = "3 True"
check "--threads 0 is bad usage" test "$(code t1.exr t2.exr --threads 0)" = 2

# standard output carries one document: the JUnit file alone (the lines go to stderr), never it and
# the --json summary, nor two files
"$FB" compare t1.exr t2.exr --fail 0.01 --junit - > ju.xml 2> ju.txt
check "--junit -: exit 1 (beyond --fail)" test $? = 1
check "  standard output is the JUnit XML alone" python3 -c "import xml.dom.minidom as m; m.parse('ju.xml')"
check "  the lines went to stderr" grep -q "^result: FAIL" ju.txt
for two in "--junit - --json" "--json --junit -" "--report - --json" "--report - --junit -" "--diff - --json"; do
  # shellcheck disable=SC2086
  "$FB" compare t1.exr t2.exr --fail 0.01 $two > two.out 2> two.txt
  rc=$?
  check "$two: exit $rc, wanted 2" test $rc = 2
  check "  nothing on standard output ($(wc -c < two.out) bytes)" test ! -s two.out
  check "  one line naming standard output: $(cat two.txt)" \
    sh -c 'test "$(wc -l < two.txt)" = 1 && grep -q "standard output .*carries" two.txt'
done
cli_finish
