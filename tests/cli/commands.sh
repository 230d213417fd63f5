#!/usr/bin/env bash
# Device selection and the other commands: devices, --version, --help, bench.
# Needs a Vulkan device (lavapipe at least): it compares backends. Usage: commands.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
require_vulkan
S="--size 96x64 --quiet"

# ---- device selection (where a Vulkan device exists) ----
if "$FB" devices | grep -q '^0 '; then
  "$FB" fbm $S --backend vulkan --device 0 -o d0.exr && ok || bad "--device 0 failed"
  first=$("$FB" devices | awk 'NR == 2 {print $3}')
  "$FB" fbm $S --backend vulkan --device "$first" -o d1.exr && ok || bad "--device $first (a name) failed"
  "$FB" info d1.exr | grep -q "fractalbake/device .*$first" && ok || bad "device not stored in the file"
  expect_fail 2 "out of range" d2.exr -- fbm $S --backend vulkan --device 99 -o d2.exr
fi

# ---- the other commands ----
"$FB" devices > dev.txt && ok || bad "devices failed"
grep -q -E "\*|no Vulkan device" dev.txt && ok || bad "devices marks no chosen device"
"$FB" --version | grep -q "fractalbake 0" && ok || bad "--version"
"$FB" fbm --help | grep -q -- "--octaves" && ok || bad "fbm --help lists no --octaves"
# other command lines' habits: --flag=value, -q, help CMD, --help everywhere
"$FB" fbm --size=24x16 --octaves=3 --backend=native -q --output=eq.exr 2> eq.txt
check "--flag=value and -q: baked" test -s eq.exr
check "-q: nothing on stderr" test ! -s eq.txt
"$FB" fbm --size 24x16 --octaves 3 --backend native --quiet -o sp.exr
check "--flag=value: the same file as --flag value" cmp -s eq.exr sp.exr
check "help fbm is fbm --help" cmp -s <("$FB" help fbm) <("$FB" fbm --help)
"$FB" fbm --help > fh.txt
check "--help: ranges as users write them" grep -q -- "--seed .*\[0\.\.4294967295\]" fh.txt
check "--help: no exponent where an integer is meant" grep -q "(0\.\.1000000\]" fh.txt
check "--help: the help texts start in one column" test "$(grep '^  --' fh.txt | sed 's/^  --[a-z-]* *//; s/.*//' | wc -l)" -gt 10 -a \
  "$(grep '^  --' fh.txt | awk '{ match($0, /^  --[a-z-]+ +/); print RLENGTH }' | sort -u | wc -l)" -eq 1
for c in render fbm julia ifs lsystem terrain constrain compare merge tonemap devices bench; do
  "$FB" $c --help > h.txt 2>&1
  rc=$?
  check "$c --help exits 0 with a usage line" test $rc -eq 0 -a -n "$(grep -i usage h.txt)"
done
for c in info devices scene; do
  check "$c --help exits 0" "$FB" $c --help > /dev/null
done
# standard input and output: `render -` reads the scene, `-o -` writes the EXR, the same bytes
printf '{"size": [40, 24], "seed": 3, "layers": [{"type": "fbm", "octaves": 4}]}' > in.json
"$FB" render in.json --backend native -q -o file.exr
"$FB" render - --backend native -q -o stdin.exr < in.json
check "render - reads the scene from standard input: the same file" cmp -s file.exr stdin.exr
"$FB" render in.json --backend native -q -o - > stdout.exr
check "-o - writes the EXR to standard output: the same bytes" cmp -s file.exr stdout.exr
"$FB" render - --backend native -q -o - < in.json | cat > piped.exr
check "render - -o - through pipes: the same bytes" cmp -s file.exr piped.exr
if command -v script > /dev/null; then
  script -qc "'$FB' render in.json --backend native -q -o -" /dev/null > tty.txt 2>&1
  check "-o - to a terminal is refused" grep -q "would go to a terminal" tty.txt
fi
# `cmake --install`: the one binary, which runs from anywhere (its shaders are embedded)
if [ -f "$(dirname "$FB")/cmake_install.cmake" ]; then
  cmake --install "$(dirname "$FB")" --prefix "$T/inst" > /dev/null
  check "cmake --install: bin/fractalbake, which bakes" "$T/inst/bin/fractalbake" fbm --size 16x8 --backend native -q -o inst.exr
fi
# `scene default`: the embedded scene with its defaults, which bakes the same file as `render`
"$FB" scene default > sd.json
"$FB" render sd.json --set size=96x48 --backend native -q -o sd.exr
"$FB" render --set size=96x48 --backend native -q -o sdd.exr
check "scene default > s.json bakes what render bakes, byte for byte" cmp -s sd.exr sdd.exr
check "scene default is one compact line" test "$(wc -l < sd.json)" = 1 -a -z "$(grep ': ' sd.json)"
check "scene FILE --set: the override in the printed scene" grep -q '"size":\[32,16\]' <("$FB" scene in.json --set size=32x16)
check "scene - reads standard input" cmp -s <("$FB" scene in.json) <("$FB" scene - < in.json)
check "scene --pretty: indented" grep -q '^  "layers": \[' <("$FB" scene default --pretty)
# stored scenes never give a named palette beside a gradient or cosine one (the named one would be
# ignored, and is refused when a scene is read): the default, the gallery, a bake's stored scene
palettes_() { python3 -c "import json, sys; t = sys.stdin.read(); s = json.loads(t[t.find('{', t.find('stored scene:')):] if 'stored scene:' in t else t); print(sum('palette' in l and ('stops' in l or 'cosine' in l) for l in s['layers']), sum('stops' in l or 'cosine' in l for l in s['layers']))"; }
for sc in default "$ROOT"/docs/examples/gallery-*.json; do
  n=$(cd "$ROOT" && "$FB" scene "$sc" | palettes_)
  check "scene $(basename "$sc"): no palette beside stops or cosine (both, gradients: $n)" test "${n% *}" = 0
  [ "$sc" = default ] && check "... the default scene has gradient layers to test" test "${n#* }" -ge 2
done
"$FB" julia --size 32x16 --backend native --stops '0,0,0,0;1,1,1,1' -q -o pst.exr
check "a bake with --stops stores no palette beside them" test "$("$FB" info pst.exr | palettes_)" = "0 1"
check "... and its stored scene bakes again" "$FB" render --from pst.exr --backend native -q -o pst2.exr
check "... the same pixels" "$FB" compare pst.exr pst2.exr --quiet
# --json: one JSON object on stdout, the same keys everywhere a command writes files
jq_() { python3 -c "import json,sys; r = json.load(open('$1')); print($2)"; }
"$FB" fbm $S --backend native -o j.exr --preview j.png --json > j.json
check "fbm --json: what was written, with sizes" test "$(jq_ j.json "[(o['path'], o['what'], o['bytes'] > 0) for o in r['outputs']]")" =   "[('j.exr', 'output', True), ('j.png', 'preview', True)]"
check "fbm --json: the layer's backend, the size, the time" test "$(jq_ j.json "r['layers'][0]['backend'], r['size'], r['seconds'] > 0")" =   "native [96, 64] True"
check "fbm --json: the EXR's size is the file's" test "$(jq_ j.json "r['outputs'][0]['bytes']")" = "$(stat -c %s j.exr)"
"$FB" render --set size=64x32 --backend auto --json -o jr.exr > jr.json
check "render --json: every layer's backend" test "$(jq_ jr.json "sorted((l['name'], l['backend'] in ('vulkan', 'native')) for l in r['layers'])")" =   "[('detail', True), ('gentle', True), ('ground', True), ('plants', True), ('sky', True), ('snow', True), ('terrain', True)]"
"$FB" merge j.exr -o jm.exr --json > jm.json
check "merge --json" test "$(jq_ jm.json "r['command'], r['parts'], r['outputs'][0]['path']")" = "merge ['j.exr'] jm.exr"
"$FB" ifs --size 32x24 --points 1e5 --backend native -q -o jt0.exr
"$FB" tonemap jt0.exr -o jt.exr --brightness 2 --json > jt.json
check "tonemap --json" test "$(jq_ jt.json "r['command'], r['outputs'][0]['path']")" = "tonemap jt.exr"
"$FB" devices --json > jd.json
check "devices --json: the devices and the chosen one" test "$(jq_ jd.json "len(r['devices']) > 0, r['chosen'] >= 0")" = "True True"
# the subnormal probe on the chosen device (lavapipe keeps them: the CPU's SSE with MXCSR's default);
# the validation layer, on for this test, watched it and is required once asked for
if "$FB" devices | grep -q '^0 *\* *llvmpipe'; then
  check "devices --json: lavapipe keeps fp32 subnormals" \
    test "$(jq_ jd.json "[d['subnormals'] for d in r['devices'] if 'subnormals' in d][0]")" = \
    "{'fp32': 'kept', 'operand_bits': 58720256, 'product_bits': 4194304}"
  check "devices: the probe's line" grep -q '^fp32 subnormals on llvmpipe.*, measured: kept (' dev.txt
fi
check "devices: the validation layer on and silent" grep -qx 'validation layer: on, silent' dev.txt
VK_LAYER_PATH=$T/none FB_VK_VALIDATION=1 "$FB" devices > nolayer.txt 2> nolayer.err
rc=$?
check "devices: FB_VK_VALIDATION=1 without the layer fails (exit $rc), nothing on stdout" test $rc -eq 3 -a ! -s nolayer.txt
check "... naming the layer" grep -q 'FB_VK_VALIDATION=1 but VK_LAYER_KHRONOS_validation is not installed' nolayer.err
"$FB" info j.exr --json > ji.json
check "info --json" test "$(jq_ ji.json "r['size'], r['layers'][0]['layer']")" = "[96, 64] fbm"
"$FB" compare j.exr j.exr --json > jc.json
check "compare --json" test "$(jq_ jc.json "r['result']")" = pass
for c in "info j.exr" "devices" "compare j.exr j.exr" "merge j.exr -o jq.exr" "tonemap jt0.exr -o jq2.exr"; do
  # shellcheck disable=SC2086
  "$FB" $c --quiet > /dev/null 2> q.txt
  check "$c --quiet: accepted, nothing on stderr" test $? -eq 0 -a ! -s q.txt
done
# the progress bar on a terminal: redrawn at least 4 times a second (counted here at 2 a second, for a
# loaded machine) with a rate and the time left
if command -v script > /dev/null; then
  start=$EPOCHREALTIME
  script -qc "'$FB' julia --size 512x256 --samples 64 --max-iter 3000 --backend native --threads 1 -o pb.exr" /dev/null > pb.txt 2>&1
  el=$(awk -v a="$start" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.2f", b - a }')
  draws=$(tr '\r' '\n' < pb.txt | grep -c '^bake \[')
  check "progress: $draws redraws in $el s" awk -v d="$draws" -v e="$el" 'BEGIN { exit !(e < 1.5 || d >= 2 * (e - 1)) }'
  check "progress: a rate in pix/s and the time left" grep -q 'pix/s .* left' <(tr '\r' '\n' < pb.txt)
  check "progress: no zero rate" test -z "$(tr '\r' '\n' < pb.txt | grep '^bake \[' | grep ' 0 pix/s')"
fi
# the terrain benchmark's JSON lines (rates are measured, not asserted: only their form and sign)
"$FB" bench --generator terrain --json > bt.json && ok || bad "bench --generator terrain failed"
grep -q '"generator": "delaunay", "backend": "native".*"unit": "Minserts/s", "rate": [0-9]*\.[0-9]*[1-9]' bt.json && ok || bad "bench: no delaunay line: $(cat bt.json)"
grep -q '"generator": "refine", "backend": "native".*"unit": "Minserts/s", "rate": [0-9]*\.[0-9]*[1-9]' bt.json && ok || bad "bench: no refine line: $(cat bt.json)"
"$FB" bench --generator constrain --size 256x256 --json > bc.json && grep -q '"generator": "constrain", "backend": "native".*"unit": "Mpix/s", "rate": [0-9]*\.[0-9]*[1-9]' bc.json && ok || bad "bench: no constrain line: $(cat bc.json)"

# --threads bounds every pool: native workers, EXR encoders and lavapipe's compute threads
threads_of() { # the most threads seen in 3 s of a bake (sampled every 0.1 s), then Ctrl-C
  # (without the validation layer, which runs threads of its own)
  FB_VK_VALIDATION=0 "$FB" julia --size 8192x8192 --backend "$1" --threads "$2" -o th.exr --quiet &
  local pid=$! n max=0
  for _ in $(seq 30); do
    n=$(ls /proc/$pid/task 2> /dev/null | wc -l)
    [ "$n" -gt "$max" ] && max=$n
    sleep 0.1
  done
  kill -INT $pid
  wait $pid 2> /dev/null
  echo "$max"
}
backends=native
"$FB" devices | grep -q '^0 *\* *llvmpipe' && backends="native vulkan" # lavapipe's pool is what is counted
native_one=0
for be in $backends; do
  one=$(threads_of $be 1)
  four=$(threads_of $be 4)
  check "--backend $be: --threads 1 ran $one threads, --threads 4 ran $four: wanted 3 more" test $((four - one)) -ge 3
  if [ $be = native ]; then
    native_one=$one
  else # lavapipe adds one compute thread and its queue, cache and fence threads, not one per core
    check "--backend vulkan --threads 1: $one threads, native $native_one: wanted at most 4 more" \
      test "$one" -le $((native_one + 4))
  fi
done

cli_finish
