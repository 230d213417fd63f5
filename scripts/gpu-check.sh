#!/usr/bin/env bash
# The GPU check in one call, for a machine with a real GPU (docs/ci.md#on-a-gpu): lists the
# devices, runs the `gpu` tests, checks the golden images on the device and on the native path,
# bakes every gallery scene and the large scenes of the issues on both backends and compares them
# bit for bit (timing each bake: what a user waits for), and runs `fractalbake bench` (and, when a
# baseline build is given, the same bench of that build, for the cost of the changes).
#
# Usage: scripts/gpu-check.sh OUTDIR
#   FB_BUILD_DIR=DIR            the build to check (default: build, configured and built if missing)
#   FB_GPU_CHECK_STEPS="..."    the steps, in order (default: devices tests golden gallery large huge
#                               bench; huge: the night sky at 32768 x 16384 within --max-memory 8G)
#   FB_GPU_CHECK_SMALL=1        the large scenes at a sixteenth of their area (to try the script on
#                               lavapipe; implies FB_GPU_CHECK_ALLOW_CPU=1)
#   FB_GPU_CHECK_ALLOW_CPU=1    run even where the only device is a CPU one
#   FB_GPU_CHECK_BASELINE=BIN   an earlier build's binary: its bench runs too, and ours against it
#   FB_GPU_CHECK_BENCH="..."    bench's arguments (default: --size 4096x4096)
# Every step has a timeout; the whole check is sized to finish in under eight minutes on the H200
# machine (16 cores). OUTDIR holds at most 8 files, written as the steps go: summary.txt,
# devices.txt, tests.txt, golden.txt, bakes.txt (gallery and large scenes: time and verdict per
# bake), bench.jsonl, baseline.jsonl and bench.err. Exit 0 when every step passed, 1 otherwise,
# 2 on bad usage.
set -uo pipefail
[ $# -eq 1 ] || { echo "usage: scripts/gpu-check.sh OUTDIR" >&2; exit 2; }
root=$(cd "$(dirname "$0")/.." && pwd)
out=$(mkdir -p "$1" && cd "$1" && pwd)
cd "$root" || exit 2 # scenes name their input files from the repository's root
build=${FB_BUILD_DIR:-$root/build}
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
small=${FB_GPU_CHECK_SMALL:-0}
[ "$small" = 1 ] && FB_GPU_CHECK_ALLOW_CPU=1
t0=$(date +%s)
status=0
scratch=$(mktemp -d "${TMPDIR:-/tmp}/fb-gpu-check-XXXXXX")
trap 'rm -rf "$scratch"' EXIT
step() { # NAME RESULT: one line of the summary
    printf '%-8s %s (%ds)\n' "$1" "$2" $(($(date +%s) - t0)) | tee -a "$out/summary.txt"
}
: > "$out/summary.txt"
echo "fractalbake GPU check, $(date -u +%Y-%m-%dT%H:%MZ), $(uname -m), $(nproc) cores, commit $(git -C "$root" rev-parse --short HEAD 2> /dev/null || echo '?')" >> "$out/summary.txt"

if [ ! -x "$build/fractalbake" ]; then
    if cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo > "$scratch/build.txt" 2>&1 &&
        cmake --build "$build" -j"$(nproc)" >> "$scratch/build.txt" 2>&1; then
        step build ok
    else
        cp "$scratch/build.txt" "$out/tests.txt"
        step build "FAILED (tests.txt)"
        exit 1
    fi
fi
fb=$build/fractalbake

# seconds a command took, its exit status kept: `timed SECONDS_VAR cmd...`
timed() {
    local var=$1 s e rc
    shift
    s=$(date +%s%N)
    "$@"
    rc=$?
    e=$(date +%s%N)
    local cs=$(((e - s) / 10000000))
    printf -v "$var" '%d.%02d' $((cs / 100)) $((cs % 100))
    return $rc
}

do_devices() {
    "$fb" devices > "$out/devices.txt" 2>&1
    local chosen
    chosen=$(sed -n 's/^[0-9]* *\* *\(.*\)$/\1/p' "$out/devices.txt" | head -1)
    if [ -z "$chosen" ]; then
        step devices "FAILED: no Vulkan device (devices.txt)"
        exit 1
    fi
    if grep -q '^[0-9]* *\*.* cpu ' "$out/devices.txt" && [ "${FB_GPU_CHECK_ALLOW_CPU:-0}" != 1 ]; then
        step devices "FAILED: the chosen device is a CPU implementation, not a GPU (devices.txt)"
        exit 1
    fi
    step devices "ok: $(echo $chosen | cut -c1-60); $(grep '^arithmetic' "$out/devices.txt" | cut -d: -f2- | cut -c1-90)"
}

do_tests() {
    # the validation layer on: any message fails a test
    if (cd "$build" && FB_VK_VALIDATION=1 timeout 150 ctest -L gpu -j4 --output-on-failure) > "$out/tests.txt" 2>&1; then
        step tests "ok ($(grep -c ' Passed ' "$out/tests.txt") passed, validation silent)"
    else
        step tests "FAILED: $(grep -cE 'Failed|Timeout' "$out/tests.txt") of $(grep -cE 'Test +#' "$out/tests.txt") (tests.txt)"
        status=1
    fi
}

do_golden() {
    : > "$out/golden.txt"
    local b ok=0
    for b in vulkan native; do
        echo "== FB_GOLDEN_BACKEND=$b" >> "$out/golden.txt"
        FB_GOLDEN_BACKEND=$b FB_VK_VALIDATION=1 timeout 60 bash "$root/scripts/golden.sh" check "$fb" "$scratch/golden-$b" \
            >> "$out/golden.txt" 2>&1 && ok=$((ok + 1))
    done
    local exact
    exact=$(grep -c ': ok (exact)' "$out/golden.txt")
    if [ $ok -eq 2 ]; then
        step golden "ok: $exact exact (device and native; golden.txt)"
    else
        step golden "FAILED: $exact exact (golden.txt)"
        status=1
    fi
}

# bake NAME TIMEOUT ARGS...: the scene on both backends, timed, then compared bit for bit
bake_both() {
    local name=$1 limit=$2 tn tv
    shift 2
    if ! timed tn timeout "$limit" "$fb" render "$@" --backend native --quiet -o "$scratch/n.exr" 2>> "$out/bakes.txt"; then
        echo "$name: native bake FAILED or cut at ${limit}s" >> "$out/bakes.txt"
        return 1
    fi
    if ! timed tv timeout "$limit" "$fb" render "$@" --backend vulkan --validation --quiet -o "$scratch/v.exr" \
        2>> "$out/bakes.txt"; then
        echo "$name: vulkan bake FAILED or cut at ${limit}s (native ${tn}s)" >> "$out/bakes.txt"
        return 1
    fi
    local verdict
    verdict=$("$fb" compare "$scratch/n.exr" "$scratch/v.exr" --max-abs 0 2>&1 | tail -1)
    printf '%-34s native %7ss  vulkan %7ss  %s\n' "$name" "$tn" "$tv" "$verdict" >> "$out/bakes.txt"
    rm -f "$scratch/n.exr" "$scratch/v.exr"
    [[ $verdict == *PASS* ]]
}

do_gallery() {
    local f n=0 ok=0
    echo "== every gallery scene at its own size: native and vulkan, compare --max-abs 0" >> "$out/bakes.txt"
    for f in "$root"/docs/examples/gallery-*.json; do
        n=$((n + 1))
        bake_both "$(basename "$f" .json)" 90 "$f" && ok=$((ok + 1))
    done
    if [ $ok -eq $n ]; then step gallery "ok: $n of $n scenes the same bits (bakes.txt)"; else
        step gallery "FAILED: $ok of $n scenes the same bits (bakes.txt)"
        status=1
    fi
}

do_large() {
    local d=1 ok=0 n=3
    [ "$small" = 1 ] && d=4
    echo "== the large scenes (issue 40's list), size divided by $d each way" >> "$out/bakes.txt"
    bake_both "default $((8192 / d))x$((4096 / d))" 120 --set size=$((8192 / d))x$((4096 / d)) && ok=$((ok + 1))
    bake_both "night sky $((16384 / d))x$((8192 / d))" 150 "$root/docs/examples/gallery-night-sky.json" \
        --set size=$((16384 / d))x$((8192 / d)) && ok=$((ok + 1))
    # the flame's histogram itself (a points part keeps it), then the picture
    local q=1000
    [ "$small" = 1 ] && q=20
    bake_both "flame gold $((2048 / d))^2 q$q part 1/1" 150 "$root/docs/examples/gallery-flame.json" \
        --set size=$((2048 / d))x$((2048 / d)) --set layers.flame.quality=$q --points-part 1/1 && ok=$((ok + 1))
    if [ $ok -eq $n ]; then step large "ok: $n of $n the same bits (bakes.txt)"; else
        step large "FAILED: $ok of $n the same bits (bakes.txt)"
        status=1
    fi
}

# The memory bound on the device: the night sky at 32768 x 16384 (a sixteenth with SMALL) on it with
# --max-memory 8G, its peak RSS against the limit and against --dry-run's prediction, and its time.
do_huge() {
    local d=1 w h pred rss t
    [ "$small" = 1 ] && d=4
    w=$((32768 / d)) h=$((16384 / d))
    local args=("$root/docs/examples/gallery-night-sky.json" --set size=${w}x$h --backend vulkan --max-memory 8G)
    pred=$("$fb" render "${args[@]}" --dry-run --json -o "$scratch/h.exr" | sed -n 's/.*"peak_bytes": \([0-9]*\).*/\1/p')
    if [ ! -x /usr/bin/time ]; then
        step huge "not run: no /usr/bin/time to measure the peak RSS"
        return
    fi
    if ! timed t /usr/bin/time -f %M -o "$scratch/rss" timeout 150 "$fb" render "${args[@]}" --quiet \
        -o "$scratch/h.exr" 2>> "$out/bakes.txt"; then
        step huge "FAILED or cut at 150 s: night sky ${w}x$h within --max-memory 8G (bakes.txt)"
        status=1
        return
    fi
    rss=$(($(tail -1 "$scratch/rss") << 10))
    rm -f "$scratch/h.exr"
    printf 'night sky %sx%s vulkan --max-memory 8G: %ss, peak RSS %d MiB, predicted %d MiB\n' "$w" "$h" "$t" \
        $((rss >> 20)) $((${pred:-0} >> 20)) >> "$out/bakes.txt"
    if [ "$rss" -le $((8 << 30)) ] && [ -n "$pred" ] && [ "$rss" -le $((pred * 5 / 4)) ]; then
        step huge "ok: night sky ${w}x$h in $t s, $((rss >> 20)) MiB (predicted $((pred >> 20)))"
    else
        step huge "FAILED: night sky ${w}x$h peak $((rss >> 20)) MiB: beyond 8 GiB or 1.25x the prediction"
        status=1
    fi
}

do_bench() {
    local args=${FB_GPU_CHECK_BENCH:---size 4096x4096}
    [ "$small" = 1 ] && args="--size 512x512 --points 1e7"
    if [ -n "${FB_GPU_CHECK_BASELINE:-}" ]; then
        # shellcheck disable=SC2086
        timeout 100 "$FB_GPU_CHECK_BASELINE" bench --json --quiet $args > "$out/baseline.jsonl" 2>> "$out/bench.err"
        step baseline "$(wc -l < "$out/baseline.jsonl") rows (baseline.jsonl: $FB_GPU_CHECK_BASELINE)"
        [ -s "$out/baseline.jsonl" ] && args="$args --compare $out/baseline.jsonl"
    fi
    # every generator's rows, its kernels beside their minimal shaders (bench/peers/): 150 s on the
    # H200; the small check on lavapipe's two cores takes longer
    local limit=150
    [ "$small" = 1 ] && limit=420
    # shellcheck disable=SC2086
    if timeout $limit "$fb" bench --json --quiet $args > "$out/bench.jsonl" 2>> "$out/bench.err"; then
        step bench "ok ($(wc -l < "$out/bench.jsonl") rows in bench.jsonl)"
    else
        step bench "FAILED or cut at $limit s (bench.err; $(wc -l < "$out/bench.jsonl") rows)"
        status=1
    fi
    [ -s "$out/bench.err" ] || rm -f "$out/bench.err"
}

for s in ${FB_GPU_CHECK_STEPS:-devices tests golden gallery large huge bench}; do
    case $s in
    devices | tests | golden | gallery | large | huge | bench) "do_$s" ;;
    *)
        echo "gpu-check.sh: unknown step $s (devices tests golden gallery large huge bench)" >&2
        exit 2
        ;;
    esac
done
echo "total $(($(date +%s) - t0)) s" >> "$out/summary.txt"
exit $status
