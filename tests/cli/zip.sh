#!/usr/bin/env bash
# ZIP chunks deflated by libdeflate: the pixels equal the uncompressed file's at every level, the
# files decode through the OpenEXR C++ library and through OpenImageIO, a larger level never makes
# a larger file here, and --zip-level is checked. Usage: zip.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
if ! command -v idiff > /dev/null || ! command -v exrmaketiled > /dev/null; then
  echo "OpenImageIO's idiff or OpenEXR's exrmaketiled missing (scripts/setup.sh installs them): not run"
  exit 77
fi
N="--backend native --quiet"
# float (fbm), half + uint + float (julia: R, G, B half, iter uint, n float), uint + half (ifs),
# and a multi-part scene with a ZIP part beside a PIZ part
"$FB" fbm $N --size 257x131 --compression none -o fbm-none.exr
"$FB" julia $N --size 203x97 --channels iter,n,R,G,B --compression none -o julia-none.exr
"$FB" ifs $N --size 128x96 --points 200000 --compression none -o ifs-none.exr
for g in fbm julia ifs; do
  case $g in
  fbm) args="--size 257x131" ;;
  julia) args="--size 203x97 --channels iter,n,R,G,B" ;;
  ifs) args="--size 128x96 --points 200000" ;;
  esac
  for level in 1 6 12; do
    # shellcheck disable=SC2086
    "$FB" $g $N $args --zip-level $level -o $g-$level.exr
    check "$g level $level: the same pixels as uncompressed (fractalbake compare)" "$FB" compare $g-none.exr $g-$level.exr > /dev/null
    check "$g level $level: the same pixels as uncompressed (OpenImageIO idiff)" idiff -q -fail 0 -warn 0 $g-none.exr $g-$level.exr
    check "$g level $level: decodes through OpenEXR (exrmaketiled)" exrmaketiled $g-$level.exr tiled.exr
    check "$g level $level: the OpenEXR decode has the same pixels" idiff -q -fail 0 -warn 0 $g-none.exr tiled.exr
    rm -f tiled.exr
  done
  check "$g: level 12 is no larger than level 1" test "$(stat -c %s $g-12.exr)" -le "$(stat -c %s $g-1.exr)"
  check "$g: ZIP is smaller than none" test "$(stat -c %s $g-1.exr)" -lt "$(stat -c %s $g-none.exr)"
done
# Level 1 stores a chunk raw when a sample of it deflates by less than 1/16: float fBm (chunks of
# 4096 x 16 floats: its samples save about 1.5%) is stored as it is, level 2 deflates it (about 4%
# smaller), and compressible chunks of the same width (half fBm, Julia) are deflated at level 1.
"$FB" fbm $N --size 4096x48 --compression none -o wide-none.exr
"$FB" fbm $N --size 4096x48 -o wide-1.exr
"$FB" fbm $N --size 4096x48 --zip-level 2 -o wide-2.exr
none=$(stat -c %s wide-none.exr)
check "float fBm at level 1: stored raw (within 1% of the uncompressed file)" test "$(stat -c %s wide-1.exr)" -ge $((none * 99 / 100))
check "float fBm at level 2: deflated (at least 2% smaller than level 1)" test "$(stat -c %s wide-2.exr)" -le $((none * 98 / 100))
for level in 1 2; do
  check "float fBm 4096 wide, level $level: the same pixels as uncompressed" idiff -q -fail 0 -warn 0 wide-none.exr wide-$level.exr
  check "float fBm 4096 wide, level $level: decodes through OpenEXR" exrmaketiled wide-$level.exr tiled.exr
  check "float fBm 4096 wide, level $level: the OpenEXR decode has the same pixels" idiff -q -fail 0 -warn 0 wide-none.exr tiled.exr
  rm -f tiled.exr
done
"$FB" fbm $N --size 4096x48 --half --compression none -o half-none.exr
"$FB" fbm $N --size 4096x48 --half -o half-1.exr
check "half fBm at level 1: deflated (at least 25% smaller)" test "$(stat -c %s half-1.exr)" -le $(($(stat -c %s half-none.exr) * 3 / 4))
"$FB" julia $N --size 2048x48 --compression none -o jw-none.exr
"$FB" julia $N --size 2048x48 -o jw-1.exr
check "julia at level 1: deflated (at least 25% smaller)" test "$(stat -c %s jw-1.exr)" -le $(($(stat -c %s jw-none.exr) * 3 / 4))
check "julia 2048 wide, level 1: the same pixels as uncompressed" idiff -q -fail 0 -warn 0 jw-none.exr jw-1.exr
"$FB" fbm $N --size 257x131 -o default.exr
check "the default level is 1 (the same bytes)" cmp -s fbm-1.exr default.exr
cat > parts.json << 'JSON'
{"size": [96, 64], "parts": "per-layer",
 "layers": [{"type": "fbm", "name": "a", "compression": "zip"}, {"type": "fbm", "name": "b", "compression": "piz", "octaves": 3}]}
JSON
"$FB" render parts.json $N --zip-level 9 -o parts.exr
check "multi-part, a ZIP part beside a PIZ part: decodes through OpenEXR" exrmaketiled parts.exr tiled.exr
check "multi-part: OpenImageIO sees both parts" grep -q "(2 subimages)" <(iinfo parts.exr)
for sub in 0 1; do
  check "multi-part: OpenImageIO decodes part $sub" grep -q "Stats Avg" <(oiiotool parts.exr --subimage $sub --printstats 2>&1)
done
# bad values
for v in 0 13 x 1.5 ""; do
  expect_fail 2 "--zip-level: expected an integer in 1..12" z.exr -- fbm $N --size 8x8 --zip-level "$v" -o z.exr
  expect_fail 2 "--zip-level: expected an integer in 1..12" z.exr -- merge a.exr -o z.exr --zip-level "$v"
done
cli_finish
