#!/usr/bin/env bash
# compare in idiff's own terms, against OpenImageIO's idiff on six pairs: --idiff-stats gives idiff's
# mean error, RMS error, peak SNR, max error and the pixels over the warning and failure thresholds
# (with -failrelative too), each equal to idiff's printed value at its printed precision; idiff's
# single-dash flags are taken (or answered with ours); --allowfailures and --failrelative give
# idiff's verdicts (exit 0 where idiff passes, 1 where it fails); --hardfail beside idiff's verdict
# for each combination of -fail, -failpercent and -hardfail.
# Usage: idiff.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
command -v idiff > /dev/null || { echo "idiff (openimageio-tools) is not installed" >&2; exit 77; }
D=$ROOT/tests/data/flip
N="--backend native --quiet"
oiiotool --create 8x8 1 --fill:color=1 8x8+0+0 -d float -o one.exr
oiiotool --create 8x8 1 --fill:color=1.1 8x8+0+0 --fill:color=3 2x2+1+1 -d float -o onep.exr
cat > sc.json << 'JSON'
{"size": [120, 80], "layers": [{"type": "fbm", "name": "h", "octaves": 3},
 {"type": "op", "name": "a", "op": "add", "inputs": ["h", 0.5]}]}
JSON
sed 's/"octaves": 3/"octaves": 4/' sc.json > sc2.json
"$FB" render sc.json $N -o s1.exr
"$FB" render sc2.json $N -o s2.exr
oiiotool --create 64x64 3 --fill:color=1,1,1 16x64+48+0 -d float -o zref.exr
oiiotool --create 64x64 3 --fill:color=0.8,0.8,0.8 16x64+48+0 -d float -o ztest.exr
# same PAIR ARGS...: idiff's numbers and ours (--idiff-stats, the same flags single-dashed)
same() {
  local a=$1 b=$2
  shift 2
  idiff "$@" "$a" "$b" > idiff.txt
  "$FB" compare "$a" "$b" "$@" --idiff-stats --ignore-missing > ours.txt
  python3 - << 'PY'
import re
def grab(path):
    t = open(path).read()
    v = {k: float(re.search(k + r" += (\S+)", t).group(1)) for k in ("Mean error", "RMS error", "Peak SNR", "Max error")}
    v["over"] = [(int(n), float(p)) for n, p in re.findall(r"(\d+) pixels \(([\d.e+-]+)%\) over", t)]
    return v
i, o = grab("idiff.txt"), grab("ours.txt")
for k in ("Mean error", "RMS error", "Peak SNR", "Max error"):  # idiff prints 6 significant digits
    assert abs(i[k] - o[k]) <= 5e-6 * max(abs(i[k]), 1e-30) + 1e-12, (k, i[k], o[k])
assert len(i["over"]) == 2 and [n for n, _ in i["over"]] == [n for n, _ in o["over"]], (i["over"], o["over"])
for (_, p), (_, q) in zip(i["over"], o["over"]):
    assert abs(p - q) <= 0.006 * max(p, 1) , (p, q)
PY
}
check "pair 1: b8 vs b6 (HDR sky, -fail 0.005)" same "$D/b8_rgb.exr" "$D/b6_rgb.exr" -fail 0.005
check "pair 2: j4 vs j1 (PNG, -fail 0.1 -warn 0.01)" same "$D/j4_rgb.png" "$D/j1_rgb.png" -fail 0.1 -warn 0.01
check "pair 3: j4 vs j4v (EXR, the defaults)" same "$D/j4_rgb.exr" "$D/j4v_rgb.exr"
check "pair 4: constants, peak 3 (-fail 0.01 -failrelative 0.5)" same one.exr onep.exr -fail 0.01 -failrelative 0.5
check "pair 5: two-layer bakes (-fail 0.02 -failpercent 5)" same s1.exr s2.exr -fail 0.02 -failpercent 5
check "pair 6: three quarters black (-fail 0.1 -warn 0.05)" same zref.exr ztest.exr -fail 0.1 -warn 0.05

# verdicts with idiff's rules: 64 pixels, 60 off by 0.1, 4 by 2
v() { "$FB" compare one.exr onep.exr "$@" > out.txt 2> err.txt; echo $?; }
iv() { idiff "$@" one.exr onep.exr > /dev/null; echo $?; }
check "allowfailures 64: idiff passes" test "$(iv -fail 0.01 -allowfailures 64)" = 0
check "  and so does compare" test "$(v -fail 0.01 -allowfailures 64)" = 0
check "allowfailures 63: idiff fails" test "$(iv -fail 0.01 -allowfailures 63)" = 2
check "  and so does compare" test "$(v --fail 0.01 --allowfailures 63)" = 1
check "allowfailures 63 with -failpercent 99 and -hardfail 1: idiff fails on hardfail" \
  test "$(iv -fail 0.01 -allowfailures 63 -failpercent 99 -hardfail 1)" = 2
check "  and so does compare" test "$(v -fail 0.01 -allowfailures 63 -failpercent 99 -hardfail 1)" = 1
check "allowfailures 64 and -hardfail 1: idiff passes (allowed failures pass hardfail)" \
  test "$(iv -fail 0.01 -allowfailures 64 -hardfail 1)" = 0
check "  and so does compare" test "$(v -fail 0.01 -allowfailures 64 -hardfail 1)" = 0
# relative: 0.1 / 1.05 = 0.0952 and 2 / 2 = 1 relative
check "-failrelative 0.5: only the 4 pixels at 2 fail, idiff fails" test "$(iv -fail 0.01 -failrelative 0.5)" = 2
check "  and so does compare" test "$(v -fail 0.01 -failrelative 0.5)" = 1
check "  4 pixels beyond" grep -q "(4 px)" out.txt
check "-failrelative 1: none fails, idiff passes" test "$(iv -fail 0.01 -failrelative 1 -warn 10)" = 0
check "  and so does compare" test "$(v -fail 0.01 -failrelative 1)" = 0
check "idiff's -o is answered with --diff" test "$(v -o d.exr)" = 2
check "  naming it" grep -q -- "-o: idiff's flag; fractalbake compare: the difference image: --diff OUT.exr" err.txt
check "--allowfailures 1.5 is refused" test "$(v --allowfailures 1.5)" = 2
check "  with one line" grep -q "expected a whole number of pixels >= 0" err.txt
# --hardfail fails on any pixel beyond it, whatever --fail and --failpercent say: each combination
# of the three beside idiff's own verdict on the same pair and flags. Pair A: one.exr and a3.exr, one
# pixel of 64 off by 1.53; pair B: one.exr and onep.exr, 60 off by 0.1 and 4 by 1.9. Columns: pair,
# flags, compare's exit (1 fail), idiff's exit (2 fail, 1 warn, 0 pass), and where the verdicts
# differ, why. idiff 2.4 skips -hardfail while no pixel is beyond -fail (its -allowfailures 0 lets
# them pass), against its help ("Fail if any one pixel exceeds this error"); with only --hardfail,
# compare has no per-pixel --fail test (idiff's default -fail is 1e-6).
oiiotool --create 8x8 1 --fill:color=1 8x8+0+0 --fill:color=2.53 1x1+3+3 -d float -o a3.exr
rows=0
while IFS='|' read -r pair flags want iwant why; do
  [ -n "$pair" ] || continue
  rows=$((rows + 1))
  b=$([ "$pair" = A ] && echo a3.exr || echo onep.exr)
  # shellcheck disable=SC2086
  "$FB" compare one.exr $b $flags > /dev/null 2> err.txt
  ours=$?
  # shellcheck disable=SC2086
  idiff $flags one.exr $b > /dev/null
  theirs=$?
  check "hardfail table, $pair $flags: compare exits $ours, wanted $want ($(cat err.txt))" test $ours = "$want"
  check "hardfail table, $pair $flags: idiff exits $theirs, wanted $iwant" test $theirs = "$iwant"
  if [ -z "$why" ]; then
    check "hardfail table, $pair $flags: the same verdict as idiff" test $((ours == 1)) = $((theirs == 2))
  else
    check "hardfail table, $pair $flags: a verdict unlike idiff's ($why)" test $((ours == 1)) != $((theirs == 2))
  fi
done << 'TABLE'
A|-fail 1|1|2|
A|-fail 2|0|0|
A|-failpercent 50|0|1|
B|-failpercent 50|1|2|
A|-hardfail 1|1|2|
A|-hardfail 2|0|2|compare: with only --hardfail, no per-pixel --fail test
B|-fail 0.05 -failpercent 50|1|2|
B|-fail 1 -failpercent 10|0|1|
A|-fail 1 -hardfail 0.1|1|2|
A|-fail 1 -hardfail 2|1|2|
A|-fail 10 -hardfail 0.1|1|0|idiff skips -hardfail with no pixel beyond -fail
A|-fail 10 -hardfail 2|0|0|
B|-failpercent 100 -hardfail 1|1|2|
B|-failpercent 100 -hardfail 2|0|1|
A|-fail 10 -failpercent 100 -hardfail 0.1|1|0|idiff skips -hardfail with no pixel beyond -fail
B|-fail 0.5 -failpercent 10 -hardfail 1|1|2|
B|-fail 2 -failpercent 10 -hardfail 1|1|0|idiff skips -hardfail with no pixel beyond -fail
B|-fail 0.5 -failpercent 10 -hardfail 3|0|1|
B|-fail 0.01 -failpercent 99 -hardfail 1 -allowfailures 3|1|2|
B|-fail 0.01 -failpercent 100 -hardfail 1 -allowfailures 4|1|2|
B|-fail 0.01 -failpercent 100 -hardfail 1 -allowfailures 64|0|0|
B|-fail 1 -hardfail 0.5 -allowfailures 4|0|0|
B|-fail 1 -hardfail 0.05 -allowfailures 4|1|0|idiff's allowance counts only the 4 pixels beyond -fail, not the 64 beyond -hardfail
TABLE
check "the hardfail table has $rows rows" test $rows = 23
"$FB" compare one.exr a3.exr -fail 10 -failpercent 100 -hardfail 0.1 --junit hf.xml > /dev/null
check "  its JUnit case fails too" grep -q 'name="no pixel beyond 0.1".*<failure' hf.xml

# a non-finite value in one file only: a failing pixel in idiff's counts, and the errors at their
# worst (mean and RMS error inf, peak SNR -inf, the max error inf where it is), as in every statistic
oiiotool one.exr --fill:color=1e39 1x1+3+2 -d float -o inf.exr
vi() { "$FB" compare one.exr inf.exr "$@" > out.txt 2> err.txt; echo $?; }
check "an infinite pixel fails --idiff-stats" test "$(vi --fail 0.1 --idiff-stats)" = 1
check "  its max error is inf, there" grep -q "Max error  = inf @ (3, 2, Y)" out.txt
check "  mean and RMS error inf, peak SNR -inf" sh -c "grep -q 'Mean error = inf' out.txt && grep -q 'RMS error = inf' out.txt && grep -q 'Peak SNR = -inf' out.txt"
"$FB" compare one.exr inf.exr --fail 0.1 --idiff-stats --json > inf.json
check "  the JSON: one failing pixel, one non-finite value, no finite error" python3 -c "
import json
i = json.load(open('inf.json'))['idiff']
assert i['fail_pixels'] == 1 and i['warn_pixels'] == 1 and i['nonfinite_differ'] == 1, i
assert i['max_error'] is None and i['rms_error'] is None and i['mean_error'] is None and i['peak_snr'] is None, i
assert i['max_at'] == [3, 2, 'Y'], i"
cli_finish
