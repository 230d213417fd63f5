#!/bin/bash
# The native path under flush-to-zero and denormals-are-zero: every golden scene (scripts/golden.sh's
# list) baked natively with MXCSR's FTZ and DAZ bits set in every thread (an LD_PRELOAD shim built
# here: a process's threads inherit its MXCSR) must give the reference's bits, and so must a 32-octave
# fBm, a deep Julia set's orbits and a flame at quality 200 against their own bakes without the shim.
# A device whose driver flushes fp32 subnormals (NVIDIA's has been seen to declare
# shaderDenormPreserveFloat32 = false: `fractalbake devices` measures it) then gives the same bits
# too. First the shim is shown to work: a product with a subnormal result and one with a subnormal
# operand, in a second thread, are 0 with it and kept without it. Each comparison runs without the
# shim (a difference below 2^-126 would itself be flushed). Not run (77) on a CPU other than x86-64.
# Usage: ftz.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
if [ "$(uname -m)" != x86_64 ]; then
    echo "not x86-64 (no MXCSR): not run"
    exit 77
fi
cat > ftz.c << 'EOF'
#include <xmmintrin.h>
/* FTZ (bit 15) and DAZ (bit 6) before main: every thread made afterwards inherits them */
__attribute__((constructor)) static void fb_ftz_daz(void) { _mm_setcsr(_mm_getcsr() | 0x8040u); }
EOF
cat > probe.c << 'EOF'
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
static float in[4];
static unsigned out[2];
static void *work(void *arg) {
    (void)arg;
    volatile float a = in[0] * in[1], b = in[2] * in[3];
    float fa = a, fb = b;
    memcpy(&out[0], &fa, 4), memcpy(&out[1], &fb, 4);
    return NULL;
}
int main(int argc, char **argv) {
    for (int i = 0; i < 4 && i + 1 < argc; i++) in[i] = strtof(argv[i + 1], NULL);
    pthread_t t;
    if (pthread_create(&t, NULL, work, NULL)) return 1;
    pthread_join(t, NULL);
    printf("%08x %08x\n", out[0], out[1]);
    return 0;
}
EOF
${CC:-cc} -O2 -shared -fPIC -o ftz.so ftz.c || { bad "cannot build the FTZ/DAZ shim"; cli_finish; exit 1; }
${CC:-cc} -O2 -pthread -o probe probe.c || { bad "cannot build the probe"; cli_finish; exit 1; }
export ASAN_OPTIONS=${ASAN_OPTIONS:+$ASAN_OPTIONS:}verify_asan_link_order=0
# 2^-126 * 0.5 (a subnormal result) and 2^-140 * 2^20 (a subnormal operand)
args="0x1p-126 0.5 0x1p-140 0x1p20"
check "without the shim subnormals are kept: $(./probe $args)" test "$(./probe $args)" = "00400000 03800000"
check "with it both are flushed in a thread: $(LD_PRELOAD=$T/ftz.so ./probe $args)" \
    test "$(LD_PRELOAD=$T/ftz.so ./probe $args)" = "00000000 00000000"

ftz() { LD_PRELOAD=$T/ftz.so "$FB" "$@"; }
gold=$ROOT/tests/golden
cd "$ROOT" || exit 1 # scenes name their inputs from the repository's root
n=0
while read -r name args; do
    [ -n "$name" ] || continue
    n=$((n + 1))
    if [ "$name" = default ]; then src=(--set size=256x128); else src=("$gold/scenes/$name.json"); fi
    if ! ftz render "${src[@]}" --backend native --quiet -o "$T/$name.exr"; then
        bad "$name: the native bake under FTZ/DAZ failed"
        continue
    fi
    if "$FB" compare "$gold/$name.exr" "$T/$name.exr" --max-abs 0 > "$T/$name.cmp"; then ok; else
        bad "$name under FTZ/DAZ: not the golden bits: $(grep FAIL "$T/$name.cmp" | head -3)"
    fi
done < <(grep -v '^#' "$gold/thresholds.txt")
check "every golden scene baked ($n)" test "$n" -ge 13

# same NAME ARGS...: a bake with and without the shim, the same bits
same() {
    local name=$1
    shift
    "$FB" "$@" --backend native --quiet -o "$T/$name-plain.exr" || { bad "$name: bake failed"; return; }
    ftz "$@" --backend native --quiet -o "$T/$name-ftz.exr" || { bad "$name: bake under FTZ/DAZ failed"; return; }
    if "$FB" compare "$T/$name-plain.exr" "$T/$name-ftz.exr" --max-abs 0 > "$T/$name.cmp"; then ok; else
        bad "$name under FTZ/DAZ differs: $(grep FAIL "$T/$name.cmp" | head -3)"
    fi
}
same fbm32 fbm --octaves 32 --size 128x128 --noise simplex --warp 1
same fbm32-ridged fbm --octaves 32 --size 96x96 --ridged --lacunarity 3
same julia-deep julia --size 128x64 --max-iter 20000 --samples 2
same flame-q200 render docs/examples/gallery-flame.json --set size=128x128 --set layers.flame.quality=200
cli_finish
