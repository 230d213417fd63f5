#!/usr/bin/env bash
# Memory is predicted, not discovered: --dry-run's prediction against the measured peak RSS of the
# same bake (within 25%) for every generator, and a bake beyond --max-memory refused at once.
# Usage: memory.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
if sanitized; then
  echo "sanitizer build: its shadow memory makes RSS meaningless here (not run)"
  exit 77
fi
printf 'x,y,z\n0,0,0\n10,0,1\n0,10,2\n10,10,3\n5,5,1\n' > pts.csv
# The unit square as its own attractor (four half-size copies): every histogram cell is hit, so every
# page the prediction counts is touched.
cat > square.json << 'JSON'
{"size": [4096, 4096], "layers": [{"type": "ifs", "name": "square", "bounds": [0, 1, 0, 1], "points": 100000000,
 "maps": [[0.5, 0, 0, 0.5, 0, 0], [0.5, 0, 0, 0.5, 0.5, 0], [0.5, 0, 0, 0.5, 0, 0.5], [0.5, 0, 0, 0.5, 0.5, 0.5]]}]}
JSON

# predicted_vs_measured NAME ARGS...: the dry run's peak within 25% of the real run's peak RSS
# (LO=0.75 HI=1.25 before the call set another band)
predicted_vs_measured() {
  local name=$1 pred rss lo=${LO:-0.75} hi=${HI:-1.25}
  shift
  pred=$("$FB" "$@" -o m.exr --dry-run --json | sed -n 's/.*"peak_bytes": \([0-9]*\).*/\1/p')
  rss=$( (/usr/bin/time -f "%M" "$FB" "$@" -o m.exr --quiet > /dev/null) 2>&1 | tail -1)
  if [ -z "$pred" ] || [ -z "$rss" ]; then bad "$name: no prediction ($pred) or no measurement ($rss)"; return; fi
  if [ ! -s m.exr ]; then bad "$name: the bake wrote nothing"; return; fi
  rm -f m.exr
  local r
  r=$(awk -v p="$pred" -v k="$rss" 'BEGIN { printf "%.3f", p / (k * 1024) }')
  echo "$name: predicted $((pred >> 20)) MiB, measured $((rss >> 10)) MiB, ratio $r"
  if awk -v r="$r" -v lo="$lo" -v hi="$hi" 'BEGIN { exit !(r >= lo && r <= hi) }'; then ok; else bad "$name: prediction/measured = $r, outside $lo..$hi"; fi
}

N="--backend native"
# The EXR writer's queue is predicted full. It fills when compressing is slower than generating, as
# at --zip-level 12 (there, within 25%); at the default level compression often keeps up, the queue
# holds less, and the prediction is a bound: never below the measurement, at most twice it.
predicted_vs_measured "fbm, native, zip level 12" fbm $N --size 16384x4096 --zip-level 12
predicted_vs_measured "julia, native, zip level 12" julia $N --size 8192x2048 --zip-level 12
LO=0.9 HI=2 predicted_vs_measured "fbm, native, zip level 1 (a bound)" fbm $N --size 16384x4096
LO=0.9 HI=2 predicted_vs_measured "julia, native, zip level 1 (a bound)" julia $N --size 8192x2048
predicted_vs_measured "ifs, native" render square.json $N
LO=0.9 HI=2 predicted_vs_measured "lsystem, native (a bound)" lsystem $N --preset tree --size 8192x8192
predicted_vs_measured "terrain, native" terrain $N --points pts.csv --insert 3000000 --size 1024x1024
predicted_vs_measured "terrain, native, additions" terrain $N --points pts.csv --insert 1000000 --size 1024x1024 --variance additions
predicted_vs_measured "constrain, native" constrain $N --size 4097x4097
cat > ops.json << 'JSON'
{"size": [8192, 4096], "layers": [{"type": "fbm", "name": "height", "octaves": 6},
 {"type": "op", "name": "snow", "op": "threshold", "inputs": ["height"], "level": 0.2, "width": 0.1}]}
JSON
predicted_vs_measured "op, native, zip level 12" render ops.json $N --zip-level 12
cat > erode.json << 'JSON'
{"size": [2048, 2048], "layers": [{"type": "fbm", "name": "h", "octaves": 4},
 {"type": "erode", "name": "e", "input": "h", "iterations": 2}]}
JSON
predicted_vs_measured "erode, native" render erode.json $N
if have_vulkan; then
  V="--backend vulkan"
  predicted_vs_measured "fbm, vulkan" fbm $V --size 8192x4096
  predicted_vs_measured "julia, vulkan" julia $V --size 4096x4096
  predicted_vs_measured "ifs, vulkan" render square.json $V
  LO=0.9 HI=2 predicted_vs_measured "lsystem, vulkan (a bound)" lsystem $V --preset tree --size 4096x4096
  predicted_vs_measured "terrain, vulkan" terrain $V --points pts.csv --insert 2000000 --size 2048x2048
  predicted_vs_measured "default scene, vulkan" render $V
  # the discrete GPU's path: device buffers copied back through host buffers, pieces of 2^22 pixels
  FB_VK_STAGING=1 predicted_vs_measured "fbm, vulkan, staged" fbm $V --size 8192x4096
fi

# A 32768 x 16384 bake of the night sky (the gallery's scene) is predicted within --max-memory 8G on
# each path: native, a CPU device, a discrete GPU's (a real run of that size is for a GPU machine).
big_within_8g() {
  local what=$1 pred
  shift
  pred=$("$FB" render "$ROOT/docs/examples/gallery-night-sky.json" --set size=32768,16384 --max-memory 8G \
    -o big.exr --dry-run --json "$@" | sed -n 's/.*"peak_bytes": \([0-9]*\).*/\1/p')
  echo "32768 x 16384 night sky, $what: predicted $((${pred:-0} >> 20)) MiB"
  check "32768 x 16384 night sky, $what: predicted ${pred:-nothing} bytes, wanted at most 8 GiB" \
    test "${pred:-0}" -gt 0 -a "${pred:-0}" -le $((8 << 30))
}
big_within_8g native $N
if have_vulkan; then
  big_within_8g vulkan $V
  FB_VK_STAGING=1 big_within_8g "vulkan, staged" $V
fi

# Beyond --max-memory: refused before allocating, in a moment, one line naming the layer.
refused() {
  local what=$1 pat=$2
  shift 2
  local t0 rc ms rss
  t0=$(date +%s%N)
  /usr/bin/time -f "%M" -o rss.txt "$FB" "$@" -o r.exr > /dev/null 2> r.txt
  rc=$?
  ms=$((($(date +%s%N) - t0) / 1000000))
  rss=$(tail -1 rss.txt)
  check "$what: exit $rc, wanted 2" test $rc -eq 2
  check "$what: message: $(cat r.txt)" grep -q -- "$pat" r.txt
  check "$what: one line" test "$(wc -l < r.txt)" -eq 1
  check "$what: took $ms ms and $((rss >> 10)) MiB before refusing" test $ms -lt 3000 -a "$rss" -lt 400000
  check "$what: no output" test ! -e r.exr
}
refused "erode 16384^2 under 4G" "layer e: erosion of 16384 x 16384 cells needs about 24.00 GiB, more than --max-memory 4.00 GiB" \
  render erode.json $N --set size=16384x16384 --max-memory 4G
refused "ifs 16384^2 under 4G" "needs about 10.[0-9]* GiB (10.[0-9]* GiB with the fewest pieces in flight), more than --max-memory 4.00 GiB; layer plants alone" \
  ifs $N --size 16384x16384 --max-memory 4G
# the refusal's figure is --dry-run's prediction of the same bake (one plan computes both)
dry=$("$FB" ifs $N --size 16384x16384 -o r.exr --dry-run | sed -n 's/^predicted peak *\([0-9.]* [KMG]i*B\) .*/\1/p')
fewest=$("$FB" ifs $N --size 16384x16384 -o r.exr --max-memory 10.2G --dry-run |
  sed -n 's/^predicted peak *\([0-9.]* [KMG]i*B\) .*/\1/p')
check "the refusal says the --dry-run's $dry and its smallest ring's $fewest: $(cat r.txt)" \
  grep -q "needs about $dry ([0-9.]* GiB with the fewest" r.txt
check "a ring shrunk to fit --max-memory predicts less ($fewest) than every piece in flight ($dry)" \
  test -n "$fewest" -a "$fewest" != "$dry"
refused "constrain 65536x32768 under 8G" "layer terrain needs about .* GiB, more than --max-memory 8.00 GiB" \
  constrain $N --size 65536x32768 --max-memory 8G
refused "terrain of 1e8 insertions under 2G" "more than --max-memory 2.00 GiB; layer terrain" \
  terrain $N --points pts.csv --insert 100000000 --max-memory 2G
refused "an exploding L-system" "would exceed max-symbols (2147483648) at iteration 18 of 20" \
  lsystem $N --preset tree --iterations 20 --max-symbols 2147483648
refused "an L-system whose strings pass --max-memory" "needs at least .* for its strings, more than --max-memory 64.0 MiB" \
  lsystem $N --axiom X --rule X=XX --iterations 27 --max-memory 64M
refused "an L-system drawing more than the rasteriser takes" "would draw at least 7.109e+06 segments" \
  lsystem $N --preset tree --iterations 13

# --dry-run writes nothing; --max-memory takes sizes people write and refuses the rest
"$FB" fbm $N --size 64x64 -o d.exr --preview d.png --dry-run > dry.txt
check "--dry-run wrote a file" test ! -e d.exr -a ! -e d.png
check "--dry-run prints the predicted peak" grep -q "predicted peak" dry.txt
# A dry run beyond --max-memory prints its prediction (and says the bake would be refused); the bake
# itself is still refused at once. --coarse 40000: the whole grid (by default a range this wide is
# amplified from a coarse model, and fits).
"$FB" rivers $N --size 40000x40000 --max-memory 8G -o big.exr --dry-run > dry.txt 2>&1
check "rivers 40000^2 amplified: predicted within 8G: $(grep peak dry.txt)" grep -q "^predicted peak .*(--max-memory 8.00 GiB)$" dry.txt
"$FB" rivers $N --size 40000x40000 --coarse 40000 -o big.exr --dry-run > dry.txt 2> dry.err
rc=$?
check "rivers 40000^2 --dry-run: exit $rc, wanted 0, stderr: $(cat dry.err)" test $rc -eq 0 -a ! -s dry.err
check "  its prediction: $(grep -E 'layer|peak' dry.txt | tr '\n' ' ')" \
  grep -q "^predicted peak .* GiB  (--max-memory .*: more than it, so the bake would be refused)$" dry.txt
layer=$("$FB" rivers $N --size 40000x40000 --coarse 40000 --dry-run --json | sed -n 's/.*"name": "rivers", "bytes": \([0-9]*\).*/\1/p')
# the model's state alone, 1.6e9 cells of at least 4 floats, is more than 24 GiB
check "  the layer's bytes in --json (${layer:-none}) are those of 40000 x 40000 cells" \
  test "${layer:-0}" -gt $((24 << 30))
check "  no file written" test ! -e big.exr
refused "rivers 40000^2, the bake itself" "layer rivers: stream-power erosion of 40000 x 40000 cells needs about" \
  rivers $N --size 40000x40000 --coarse 40000 --max-memory 8G
"$FB" render erode.json $N --set size=16384x16384 --max-memory 4G -o big.exr --dry-run > dry.txt
check "erode 16384^2 under 4G --dry-run: exit $?, its prediction" grep -q "more than it, so the bake would be refused" dry.txt

for v in 512M 8G 1.5GiB 50% 1073741824; do
  "$FB" fbm $N --size 16x16 -o v.exr --max-memory $v --quiet && ok || bad "--max-memory $v refused"
done
rm -f v.exr
for v in abc 0 -1G 101% 12Q 100; do
  expect_fail 2 "max-memory: expected a size" v.exr -- fbm $N --size 16x16 -o v.exr --max-memory "$v"
done

cli_finish
