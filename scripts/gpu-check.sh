#!/usr/bin/env bash
# The GPU check, in two calls that each fit a GPU machine's 10-minute command with room to spare:
# every step has a time limit, and the limits of a call add up to under 540 s (docs/ci.md#on-a-gpu).
#
#   scripts/gpu-check.sh correctness OUTDIR   the verdicts of correctness: `devices` with the
#       validation layer required (and its fp32 subnormal probe), `ctest -L gpu -LE staging` (a
#       skipped test is a failure: the check is for a machine that has a GPU), the golden images on
#       the device, and the gallery: each scene with a layer on the device baked on both backends and
#       compared with --max-abs 0, each scene of CPU layers alone (terrain, constraints, rivers)
#       baked once on the device's backend
#   scripts/gpu-check.sh speed OUTDIR         the speed against the issues' targets: the night sky at
#       16384 x 8192 (a whole bake in 3 s, 3x the native path's; its device time by timestamps), the
#       flame `gold` at 2048 x 2048 quality 1000 (10 G points/s by the device's timestamps), and
#       `fractalbake bench`: every kernel at >= 0.5x its minimal peer (vs_peer), whole bakes beside
#       encode-only rows
#
#   FB_BUILD_DIR=DIR              the build to check (default: build; configured and built, within a
#                                 limit, when it has no fractalbake)
#   FB_GPU_CHECK_SCALE=N          every size divided by N each way, the flame's quality by N, the
#                                 gallery's own sizes then doubled only where N is 1 (default 1; to try
#                                 the calls on lavapipe: its verdicts then say nothing of a GPU)
#   FB_GPU_CHECK_ALLOW_CPU=1      run where the chosen device is a CPU implementation (lavapipe)
#   FB_GPU_CHECK_STEPS="..."      the steps of the call, in order (default: all of them; correctness:
#                                 devices tests golden gallery; speed: sky flame bench)
#   FB_GPU_CHECK_TESTS=REGEX      the tests step runs only the gpu tests REGEX matches (ctest -R)
#   FB_GPU_CHECK_LIMIT_STEP=S     the time limit of STEP (build, devices, tests, golden, gallery, sky,
#                                 flame, bench) in seconds, instead of its default
#
# OUTDIR receives, as the steps go: summary.txt (a line a step, then the total, then one PASS or FAIL
# line per target: its last lines), and each step's log (devices.txt, tests.txt, golden.txt,
# gallery.txt, sky.txt, flame.txt, bench.jsonl, bench.txt). A step cut by its limit says "cut at N
# s" and its targets FAIL. Exit 0 when every target passed, 1 otherwise, 2 on bad usage.
set -uo pipefail
usage() {
    echo "usage: scripts/gpu-check.sh correctness|speed OUTDIR" >&2
    exit 2
}
[ $# -eq 2 ] || usage
call=$1
case $call in correctness | speed) ;; *) usage ;; esac
root=$(cd "$(dirname "$0")/.." && pwd)
out=$(mkdir -p "$2" && cd "$2" && pwd) || usage
cd "$root" || exit 2 # scenes name their input files from the repository's root
build=$(realpath -m "${FB_BUILD_DIR:-$root/build}")
fb=$build/fractalbake
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
scale=${FB_GPU_CHECK_SCALE:-1}
[[ $scale =~ ^[1-9][0-9]*$ ]] || {
    echo "gpu-check.sh: FB_GPU_CHECK_SCALE must be a positive integer, not '$scale'" >&2
    exit 2
}
t0=$(date +%s)
scratch=$(mktemp -d "${TMPDIR:-/tmp}/fb-gpu-check-XXXXXX")
trap 'rm -rf "$scratch"' EXIT
: > "$out/summary.txt"
: > "$scratch/verdicts"
echo "fractalbake GPU check ($call), $(date -u +%Y-%m-%dT%H:%MZ), $(uname -m), $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)," \
    "commit $(git -C "$root" rev-parse --short HEAD 2> /dev/null || echo '?'), scale 1/$scale" >> "$out/summary.txt"

line() { # STEP TEXT: one line of the summary, with the seconds since the start
    printf '%-8s %s (%ds)\n' "$1" "$2" $(($(date +%s) - t0)) | tee -a "$out/summary.txt"
}
verdict() { # PASS|FAIL TARGET TEXT: the target's verdict line, printed at the end
    printf '%s %s: %s\n' "$1" "$2" "$3" >> "$scratch/verdicts"
}
limit() { # STEP DEFAULT: the step's time limit in seconds
    local v="FB_GPU_CHECK_LIMIT_$1"
    echo "${!v:-$2}"
}
# run LIMIT LOG CMD...: the command within LIMIT seconds, its output appended to LOG; its exit status,
# 124 when it was cut (the LOG then ends with "cut at LIMIT s")
run() {
    local lim=$1 log=$2 rc
    shift 2
    timeout -k 5 "$lim" "$@" >> "$log" 2>&1
    rc=$?
    if [ $rc -eq 124 ] || [ $rc -eq 137 ]; then
        echo "cut at $lim s: $*" >> "$log"
        return 124
    fi
    return $rc
}
finish() {
    echo "total $(($(date +%s) - t0)) s" >> "$out/summary.txt"
    cat "$scratch/verdicts" >> "$out/summary.txt"
    cat "$scratch/verdicts"
    ! grep -q '^FAIL' "$scratch/verdicts"
    exit $?
}

if [ ! -x "$fb" ]; then
    lb=$(limit build 240)
    if run "$lb" "$out/build.txt" cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo &&
        run "$lb" "$out/build.txt" cmake --build "$build" -j"$(nproc)"; then
        line build ok
    else
        r=FAILED
        grep -q '^cut at' "$out/build.txt" && r="cut at $lb s"
        line build "$r (build.txt)"
        verdict FAIL build "$r: no $fb"
        finish
    fi
fi

# ---- correctness ---------------------------------------------------------------------------------

do_devices() { # the layer required, the chosen device a GPU, its subnormals
    local lim rc chosen sub
    lim=$(limit devices 20)
    : > "$out/devices.txt"
    FB_VK_VALIDATION=1 run "$lim" "$out/devices.txt" "$fb" devices
    rc=$?
    chosen=$(sed -n 's/^[0-9]* *\* *\(.*\)$/\1/p' "$out/devices.txt" | head -1 | tr -s ' ')
    sub=$(sed -n 's/^fp32 subnormals on .*, measured: \([a-z ]*\) (.*/\1/p' "$out/devices.txt")
    if [ $rc -eq 124 ]; then
        line devices "cut at $lim s (devices.txt)"
        verdict FAIL devices "cut at $lim s"
    elif [ $rc -ne 0 ]; then
        line devices "FAILED: exit $rc (devices.txt)"
        verdict FAIL devices "exit $rc under FB_VK_VALIDATION=1: $(grep -m1 'fractalbake:' "$out/devices.txt")"
    elif ! grep -qx 'validation layer: on, silent' "$out/devices.txt"; then
        line devices "FAILED: the validation layer is not on (devices.txt)"
        verdict FAIL devices "the validation layer is not on"
    elif [ -z "$chosen" ]; then
        line devices "FAILED: no Vulkan device (devices.txt)"
        verdict FAIL devices "no Vulkan device"
    elif [[ $chosen == *" cpu "* ]] && [ "${FB_GPU_CHECK_ALLOW_CPU:-0}" != 1 ]; then
        line devices "FAILED: the chosen device is a CPU implementation: $chosen"
        verdict FAIL devices "a CPU implementation, not a GPU: $chosen"
    else
        line devices "ok: ${chosen:0:70}; validation layer on, silent; fp32 subnormals $sub"
        verdict PASS devices "${chosen:0:60}, the validation layer on and silent"
    fi
    if [ "$sub" = kept ]; then verdict PASS subnormals "fp32 subnormals kept on the device"; else
        verdict FAIL subnormals "fp32 subnormals ${sub:-not probed} (outputs may differ below 2^-126; the goldens decide)"
    fi
}

do_tests() { # every gpu test but the -staging twins (a discrete GPU's default path already)
    local lim rc n pass skip fail sel=()
    lim=$(limit tests 220)
    [ -n "${FB_GPU_CHECK_TESTS:-}" ] && sel=(-R "$FB_GPU_CHECK_TESTS")
    : > "$out/tests.txt"
    n=$(cd "$build" && ctest -N -L gpu -LE staging "${sel[@]}" | sed -n 's/^Total Tests: //p')
    (cd "$build" && FB_VK_VALIDATION=1 run "$lim" "$out/tests.txt" ctest -L gpu -LE staging "${sel[@]}" -j"$(($(nproc) / 2 + 1))" \
        --output-on-failure)
    rc=$?
    pass=$(grep -cE '^ *[0-9]+/[0-9]+ Test +#[0-9]+: .* Passed ' "$out/tests.txt")
    skip=$(grep -cE '^ *[0-9]+/[0-9]+ Test +#[0-9]+: .*(Skipped|Not Run)' "$out/tests.txt")
    fail=$((${n:-0} - pass - skip))
    local what="$pass of ${n:-?} passed, $skip skipped (a failure here), $fail failed or not finished"
    if [ $rc -eq 124 ]; then
        line tests "cut at $lim s: $what (tests.txt)"
        verdict FAIL tests "cut at $lim s: $what"
    elif [ "${n:-0}" -gt 0 ] && [ "$pass" -eq "$n" ]; then
        line tests "ok: $what"
        verdict PASS tests "$pass of $n gpu tests passed under the validation layer, none skipped"
    else
        line tests "FAILED: $what (tests.txt)"
        verdict FAIL tests "$what"
    fi
}

do_golden() { # every golden scene on the device, exact
    local lim rc n exact
    lim=$(limit golden 60)
    : > "$out/golden.txt"
    FB_GOLDEN_BACKEND=vulkan FB_VK_VALIDATION=1 run "$lim" "$out/golden.txt" bash "$root/scripts/golden.sh" check "$fb" \
        "$scratch/golden"
    rc=$?
    n=$(grep -cv '^#' "$root/tests/golden/thresholds.txt")
    exact=$(grep -c ': ok (exact)' "$out/golden.txt")
    if [ $rc -eq 124 ]; then
        line golden "cut at $lim s: $exact of $n exact (golden.txt)"
        verdict FAIL golden "cut at $lim s: $exact of $n exact"
    elif [ $rc -eq 0 ] && [ "$exact" -eq "$n" ]; then
        line golden "ok: $exact of $n exact on the device"
        verdict PASS golden "$exact of $n golden scenes exact on the device"
    else
        line golden "FAILED: $exact of $n exact (golden.txt)"
        verdict FAIL golden "$exact of $n exact"
    fi
}

# size SCENE MUL: the scene's size times MUL, divided by the scale, as WxH; its own size where a
# layer places things in pixels (a constraint's regions)
scene_size() {
    python3 -c "import json,sys; d = json.load(open(sys.argv[1])); w, h = d['size']; m, s = int(sys.argv[2]), int(sys.argv[3])
m, s = (1, 1) if any('regions' in l for l in d['layers']) else (m, s)
print(f'{max(8, w * m // s)}x{max(8, h * m // s)}')" "$1" "$2" "$scale"
}
# cpu_only SCENE: true when every layer of the scene runs on the CPU on every backend
cpu_only() {
    python3 -c "import json,sys; t = {l['type'] for l in json.load(open(sys.argv[1]))['layers']}
sys.exit(0 if t <= {'terrain', 'constrain', 'rivers', 'op'} else 1)" "$1"
}

do_gallery() { # each scene at a GPU's size: both backends, bit for bit; CPU-only scenes once
    local lim end f name size n=0 ok=0 left mul=1
    lim=$(limit gallery 190)
    end=$(($(date +%s) + lim))
    [ "$scale" -eq 1 ] && mul=2
    : > "$out/gallery.txt"
    for f in "$root"/docs/examples/gallery-*.json; do
        n=$((n + 1))
        name=$(basename "$f" .json)
        left=$((end - $(date +%s)))
        if [ $left -le 0 ]; then
            echo "$name: cut at $lim s (the step's limit), not baked" >> "$out/gallery.txt"
            continue
        fi
        if cpu_only "$f"; then
            size=$(scene_size "$f" 1)
            if run "$left" "$out/gallery.txt" "$fb" render "$f" --set size="$size" --backend vulkan --validation --quiet \
                -o "$scratch/v.exr"; then
                echo "$name $size: CPU layers only, baked once: ok" >> "$out/gallery.txt"
                ok=$((ok + 1))
            else
                echo "$name $size: CPU layers only, baked once: FAILED (or cut at $lim s)" >> "$out/gallery.txt"
            fi
            rm -f "$scratch/v.exr"
            continue
        fi
        size=$(scene_size "$f" $mul)
        local s0 s1 s2 v=""
        s0=$(date +%s%N)
        run "$left" "$out/gallery.txt" "$fb" render "$f" --set size="$size" --backend native --quiet -o "$scratch/n.exr" &&
            s1=$(date +%s%N) &&
            run $((end - $(date +%s) > 0 ? end - $(date +%s) : 1)) "$out/gallery.txt" "$fb" render "$f" --set size="$size" \
                --backend vulkan --validation --quiet -o "$scratch/v.exr" &&
            s2=$(date +%s%N) &&
            v=$(timeout $((end - $(date +%s) > 0 ? end - $(date +%s) : 1)) "$fb" compare "$scratch/n.exr" "$scratch/v.exr" \
                --max-abs 0 2>&1 | tail -1)
        if [[ $v == *PASS* ]]; then
            printf '%-22s %-10s native %6.2fs  vulkan %6.2fs  %s\n' "$name" "$size" "$(((s1 - s0) / 1000000))e-3" \
                "$(((s2 - s1) / 1000000))e-3" "$v" >> "$out/gallery.txt"
            ok=$((ok + 1))
        else
            echo "$name $size: FAILED or cut at $lim s (the step's limit): ${v:-no verdict}" >> "$out/gallery.txt"
        fi
        rm -f "$scratch/n.exr" "$scratch/v.exr"
    done
    local what="$ok of $n scenes (mul $mul, scale 1/$scale)"
    if [ $ok -eq $n ]; then
        line gallery "ok: $what"
        verdict PASS gallery "$what: the same bits on both backends, CPU-only scenes baked"
    elif grep -q 'cut at' "$out/gallery.txt"; then
        line gallery "cut at $lim s: $what (gallery.txt)"
        verdict FAIL gallery "cut at $lim s: $what"
    else
        line gallery "FAILED: $what (gallery.txt)"
        verdict FAIL gallery "$what"
    fi
}

# ---- speed ---------------------------------------------------------------------------------------

# bake LIMIT LOG ARGS...: a whole bake with --json (its summary appended to LOG) within LIMIT seconds,
# its file removed
bake() {
    local lim=$1 log=$2 rc
    shift 2
    run "$lim" "$log" "$fb" render "$@" --quiet --json -o "$scratch/b.exr"
    rc=$?
    rm -f "$scratch/b.exr"
    return $rc
}
# field LOG KEY: the last `"KEY": number` of LOG, to 3 decimals ("" where there is none)
field() {
    local v
    v=$(grep -o "\"$2\": *[0-9.e+-]*" "$1" | tail -1 | sed 's/.*: *//')
    [ -z "$v" ] || printf '%.3f' "$v"
}

do_sky() { # the night sky at 16384 x 8192: the device's whole bake against 3 s and 3x native
    local lim end w=$((16384 / scale)) h=$((8192 / scale)) tv gv tn
    lim=$(limit sky 130)
    end=$(($(date +%s) + lim))
    : > "$out/sky.txt"
    local args=("$root/docs/examples/gallery-night-sky.json" --set "size=${w}x$h")
    echo "== vulkan" >> "$out/sky.txt"
    if ! bake "$lim" "$out/sky.txt" "${args[@]}" --backend vulkan; then
        line sky "FAILED or cut at $lim s: the vulkan bake (sky.txt)"
        verdict FAIL sky-3s "${w}x$h: the vulkan bake failed or was cut at $lim s"
        verdict FAIL sky-3x "${w}x$h: the vulkan bake failed or was cut at $lim s"
        return
    fi
    tv=$(field "$out/sky.txt" seconds) gv=$(field "$out/sky.txt" gpu_seconds)
    echo "== native" >> "$out/sky.txt"
    if ! bake $((end - $(date +%s) > 0 ? end - $(date +%s) : 1)) "$out/sky.txt" "${args[@]}" --backend native; then
        line sky "FAILED or cut at $lim s: the native bake (sky.txt)"
        verdict "$(awk -v t="$tv" -v s="$scale" 'BEGIN {print ((t <= 3 && s == 1) ? "PASS" : "FAIL")}')" sky-3s \
            "${w}x$h whole bake ${tv} s on the device (target 3 s at 16384x8192)"
        verdict FAIL sky-3x "${w}x$h: the native bake failed or was cut at $lim s"
        return
    fi
    tn=$(field "$out/sky.txt" seconds)
    line sky "${w}x$h whole bake: device ${tv} s (its dispatches ${gv:-?} s by timestamps), native ${tn} s"
    verdict "$(awk -v t="$tv" -v s="$scale" 'BEGIN {print ((t <= 3 && s == 1) ? "PASS" : "FAIL")}')" sky-3s \
        "${w}x$h whole bake ${tv} s on the device, dispatches ${gv:-?} s (target: 16384x8192 in 3 s)"
    verdict "$(awk -v a="$tn" -v b="$tv" 'BEGIN {print ((b > 0 && a >= 3 * b) ? "PASS" : "FAIL")}')" sky-3x \
        "native ${tn} s / device ${tv} s = $(awk -v a="$tn" -v b="$tv" 'BEGIN {printf "%.2f", (b > 0 ? a / b : 0)}')x (target 3x)"
}

do_flame() { # gold at 2048 x 2048 quality 1000: points per second of the device's dispatches
    local lim w=$((2048 / scale)) q=$((1000 / scale)) gv tv
    [ $q -ge 1 ] || q=1
    lim=$(limit flame 60)
    : > "$out/flame.txt"
    if ! bake "$lim" "$out/flame.txt" "$root/docs/examples/gallery-flame.json" --set size=${w}x$w \
        --set layers.flame.quality=$q --backend vulkan; then
        line flame "FAILED or cut at $lim s (flame.txt)"
        verdict FAIL flame-10G "${w}x$w q$q: the bake failed or was cut at $lim s"
        return
    fi
    tv=$(field "$out/flame.txt" seconds) gv=$(field "$out/flame.txt" gpu_seconds)
    local rate
    rate=$(awk -v q=$q -v w=$w -v g="${gv:-0}" 'BEGIN {printf "%.4g", (g > 0 ? q * w * w / g * 1e-9 : 0)}')
    line flame "${w}x$w q$q: whole bake ${tv} s, dispatches ${gv:-?} s: $rate G points/s"
    verdict "$(awk -v r="$rate" -v s="$scale" 'BEGIN {print ((r >= 10 && s == 1) ? "PASS" : "FAIL")}')" flame-10G \
        "${w}x$w quality $q: $rate G points/s by the device's timestamps (target 10 at 2048x2048 q1000)"
}

do_bench() { # every kernel beside its minimal peer; whole bakes beside encode-only
    local lim s=$((4096 / scale)) rc
    lim=$(limit bench 280)
    : > "$out/bench.jsonl"
    : > "$out/bench.txt"
    timeout -k 5 "$lim" "$fb" bench --json --quiet --backend vulkan --size ${s}x$s > "$out/bench.jsonl" 2>> "$out/bench.txt"
    rc=$?
    local cut=""
    [ $rc -eq 124 ] || [ $rc -eq 137 ] && cut="cut at $lim s; " && echo "cut at $lim s" >> "$out/bench.txt"
    python3 - "$out/bench.jsonl" "$scratch/verdicts" "$cut" << 'EOF' | tee -a "$out/bench.txt"
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.startswith("{")]
cut = sys.argv[3]
with open(sys.argv[2], "a") as v:
    kernels = [r for r in rows if "vs_peer" in r]
    for r in kernels:
        ok = r["vs_peer"] >= 0.5 and r.get("same_bits", 0) == 1
        v.write(f"{'PASS' if ok else 'FAIL'} kernel {r['generator']} {r['mode']}: vs_peer {r['vs_peer']:.3f} "
                f"(target 0.5), same_bits {r.get('same_bits')}\n")
    for g in ("fbm", "julia", "stars", "ifs", "erode"):
        if not any(r["generator"] == g for r in kernels):
            v.write(f"FAIL kernel {g}: {cut}no kernel row beside its peer\n")
    for r in rows:
        if r["mode"].startswith("end-to-end"):
            enc = [e for e in rows if e["generator"] == r["generator"] and
                   e["mode"] == r["mode"].replace("end-to-end", "encode-only")]
            print(f"{r['generator']:6s} {r['mode']:16s} {r['rate']:10.3f} {r['unit']}"
                  + (f"   encode-only {enc[0]['rate']:10.3f} (bake/encode {enc[0].get('bake_vs_encode')})" if enc else ""))
print(f"{len(rows)} rows, {len(kernels)} kernels beside their peers")
EOF
    if [ -n "$cut" ]; then line bench "cut at $lim s: $(wc -l < "$out/bench.jsonl") rows (bench.jsonl)"; else
        line bench "exit $rc: $(wc -l < "$out/bench.jsonl") rows (bench.jsonl, bench.txt)"
    fi
    [ $rc -eq 0 ] || [ -n "$cut" ] || verdict FAIL bench "exit $rc (bench.txt)"
}

if [ "$call" = correctness ]; then all="devices tests golden gallery" steps=${FB_GPU_CHECK_STEPS:-devices tests golden gallery}; else
    all="sky flame bench" steps=${FB_GPU_CHECK_STEPS:-sky flame bench}
fi
for s in $steps; do
    [[ " $all " == *" $s "* ]] || {
        echo "gpu-check.sh: $call has no step $s ($all)" >&2
        exit 2
    }
done
if [ "$call" = speed ]; then # the device the figures are of
    dev=$(timeout 20 "$fb" devices 2> /dev/null | sed -n 's/^[0-9]* *\* *\(.*\)$/\1/p' | head -1 | tr -s ' ')
    line device "${dev:-no Vulkan device (or cut at 20 s)}"
fi
for s in $steps; do "do_$s"; done
finish
