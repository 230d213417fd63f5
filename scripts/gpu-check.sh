#!/usr/bin/env bash
# The GPU check in one call: builds (unless FB_BUILD_DIR names a build), lists the Vulkan devices,
# runs the `gpu` test label on the device fractalbake chooses (a discrete GPU first), checks the
# golden images against their lavapipe references, and runs `fractalbake bench --json`. Everything
# lands in OUTDIR (few files: devices.txt, gpu-tests.txt, golden.txt, bench.jsonl, summary.txt).
# Usage: scripts/gpu-check.sh OUTDIR
#   FB_BUILD_DIR=DIR         use this build (default: build, configured and built if missing)
#   FB_GPU_CHECK_ALLOW_CPU=1 run even where the only device is a CPU one (to try the script)
#   FB_GPU_CHECK_BENCH="..." the benchmark's arguments (default: --size 4096x4096; on a CPU-only
#                            machine try "--size 512x512 --points 1e7")
# Exit 0 when every step passed, 1 when a step failed (summary.txt says which), 2 on bad usage.
set -uo pipefail
[ $# -eq 1 ] || { echo "usage: scripts/gpu-check.sh OUTDIR" >&2; exit 2; }
root=$(cd "$(dirname "$0")/.." && pwd)
out=$(mkdir -p "$1" && cd "$1" && pwd)
build=${FB_BUILD_DIR:-$root/build}
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
t0=$(date +%s)
status=0
step() { # NAME RESULT: one line of the summary
    printf '%-10s %s (%ds)\n' "$1" "$2" $(($(date +%s) - t0)) | tee -a "$out/summary.txt"
}
: > "$out/summary.txt"
echo "fractalbake GPU check, $(date -u +%Y-%m-%dT%H:%MZ), $(uname -m), $(nproc) cores, commit $(git -C "$root" rev-parse --short HEAD 2> /dev/null || echo '?')" >> "$out/summary.txt"

if [ ! -x "$build/fractalbake" ]; then
    if cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo > "$out/build.txt" 2>&1 &&
        cmake --build "$build" -j"$(nproc)" >> "$out/build.txt" 2>&1; then
        step build ok
    else
        step build "FAILED (build.txt)"
        exit 1
    fi
fi
fb=$build/fractalbake

"$fb" devices > "$out/devices.txt" 2>&1
chosen=$(sed -n 's/^[0-9]* *\* *\(.*\)$/\1/p' "$out/devices.txt" | head -1)
if [ -z "$chosen" ]; then
    step devices "FAILED: no Vulkan device (devices.txt)"
    exit 1
fi
if grep -q '^[0-9]* *\*.* cpu ' "$out/devices.txt" && [ "${FB_GPU_CHECK_ALLOW_CPU:-0}" != 1 ]; then
    step devices "FAILED: the chosen device is a CPU implementation, not a GPU (devices.txt)"
    exit 1
fi
step devices "ok: $chosen"

if (cd "$build" && timeout 300 ctest -L gpu --output-on-failure) > "$out/gpu-tests.txt" 2>&1; then
    step gpu-tests "ok ($(grep -c 'Passed' "$out/gpu-tests.txt") passed)"
else
    step gpu-tests "FAILED (gpu-tests.txt)"
    status=1
fi

# the goldens were rendered on lavapipe: the device's pixels within their thresholds
if FB_VK_VALIDATION=0 timeout 180 bash "$root/scripts/golden.sh" check "$fb" "$out/golden" > "$out/golden.txt" 2>&1; then
    step golden "ok (every reference within its threshold)"
else
    step golden "FAILED (golden.txt; renders and diffs in golden/)"
    status=1
fi

if timeout 240 "$fb" bench --json ${FB_GPU_CHECK_BENCH:---size 4096x4096} > "$out/bench.jsonl" 2> "$out/bench.err"; then
    step bench "ok ($(wc -l < "$out/bench.jsonl") rows in bench.jsonl)"
else
    step bench "FAILED or cut at 240 s (bench.err; $(wc -l < "$out/bench.jsonl") rows)"
    status=1
fi
[ -s "$out/bench.err" ] || rm -f "$out/bench.err"
exit $status
