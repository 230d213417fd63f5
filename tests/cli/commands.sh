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
