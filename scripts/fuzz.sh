#!/usr/bin/env bash
# Fuzzes the readers with libFuzzer: the scene parser with --set, the .ifs reader, the point, centre,
# region and profile readers, the L-system parser and the EXR reader of info/compare/merge/tonemap.
#   scripts/fuzz.sh [SECONDS]   each harness for SECONDS (default 60); exit 77 without clang's libFuzzer
# Builds into build-fuzz/ (clang, -fsanitize=fuzzer,address,undefined). Seeds come from the
# repository (tests/fuzz/seeds, the golden scenes and small goldens, docs/examples) and from tiny
# EXRs baked here; the corpora grow under build-fuzz/corpus. A crash leaves
# build-fuzz/crashes/NAME-crash-*; reproduce it with build-fuzz/tests/fuzz/fuzz_NAME FILE.
set -uo pipefail
cd "$(dirname "$0")/.."
SECONDS_EACH=${1:-60}
B=${FB_FUZZ_BUILD_DIR:-build-fuzz}
if ! command -v clang > /dev/null || ! echo 'int LLVMFuzzerTestOneInput(const char *d, long n) { return 0; }' |
  clang -x c -fsanitize=fuzzer - -o /tmp/fb-fuzz-probe.$$ 2> /dev/null; then
  echo "fuzz: clang with libFuzzer not found (Debian: apt-get install clang): not run"
  exit 77
fi
rm -f /tmp/fb-fuzz-probe.$$
if [ ! -f "$B/CMakeCache.txt" ]; then
  CC=clang cmake -S . -B "$B" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFB_FUZZ=ON -DBUILD_TESTING=OFF > /dev/null || exit 1
fi
# the command line and the harnesses alone: the shared library (libfractalbake) is linked with
# --no-undefined, which a sanitizer's runtime, provided by the executable, cannot satisfy
harnesses="scene ifs points lsys exr" # tests/fuzz/CMakeLists.txt
targets="fractalbake $(printf 'fuzz_%s ' $harnesses)"
# shellcheck disable=SC2086
cmake --build "$B" -j"$(nproc)" --target $targets > "$B/build.log" 2>&1 || { tail -20 "$B/build.log"; exit 1; }

# corpora: the repository's inputs, then whatever the fuzzer found before
C=$B/corpus
mkdir -p "$C"/{scene,ifs,points,lsys,exr} "$B/crashes"
cp tests/fuzz/seeds/scene/* tests/golden/scenes/*.json "$C/scene/"
for f in docs/examples/*.json; do cp "$f" "$C/scene/example-$(basename "$f")"; done
cp tests/fuzz/seeds/ifs/* "$C/ifs/"
cp docs/examples/fractint.ifs "$C/ifs/example-fractint.ifs"
cp tests/fuzz/seeds/points/* "$C/points/"
for f in docs/examples/*.csv docs/examples/*.xyz; do cp "$f" "$C/points/example-$(basename "$f")"; done
cp tests/fuzz/seeds/lsys/* "$C/lsys/"
find tests/golden -name '*.exr' -size -70k -exec cp {} "$C/exr/" \;
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
for comp in zip piz none; do
  "$B/fractalbake" fbm --backend native --size 16x12 --compression "$comp" -o "$C/exr/fbm-$comp.exr" --quiet
done
"$B/fractalbake" render --backend native --set size=24x16 --set parts=per-layer -o "$C/exr/parts.exr" --quiet
"$B/fractalbake" render --backend native --set size=24x16 --region 0,4,24,8 -o "$C/exr/region.exr" --quiet

pass=0
fail=0
for h in $harnesses; do
  log=$B/fuzz-$h.log
  ASAN_OPTIONS=detect_leaks=1 "$B/tests/fuzz/fuzz_$h" -max_total_time="$SECONDS_EACH" -timeout=20 -rss_limit_mb=3072 \
    -max_len=65536 -artifact_prefix="$B/crashes/$h-" -print_final_stats=1 "$C/$h" > "$log" 2>&1
  rc=$?
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  if [ $rc -eq 0 ]; then
    pass=$((pass + 1))
    echo "fuzz_$h: ${runs:-?} inputs in ${SECONDS_EACH} s, clean"
  else
    fail=$((fail + 1))
    echo "FAIL: fuzz_$h exited $rc after ${runs:-?} inputs; see $log and $B/crashes/$h-*"
    grep -m5 -E "ERROR|SUMMARY|runtime error" "$log"
  fi
done
echo "$pass passed, $fail failed"
[ $fail -eq 0 ]
