# Sourced by tests/cli/flame.sh and flame-genomes.sh: a flam3-genome genome rendered by flam3-render
# (twice, isaac_seed a and b) and by fractalbake, and our distance from flam3 held to 1.5 times
# flam3's own from itself (RMSE per channel and SSIM on the tone-mapped RGB, 8-bit).
# FB_FLAME_QUALITY: samples per pixel (30). Exits 77 (not run) without flam3-utils.
if ! command -v flam3-render > /dev/null || ! command -v flam3-genome > /dev/null; then
    echo "flam3-utils is not installed: not run"
    exit 77
fi
Q=${FB_FLAME_QUALITY:-30}

# compare A B: "rmseR rmseG rmseB ssimR ssimG ssimB" of two 8-bit PNGs (their RGB)
metrics() {
    "$FB" compare "$1" "$2" --ignore-missing --ssim 0 --json 2> /dev/null |
        python3 -c 'import json,sys; d=json.load(sys.stdin); c=[x for x in d["channels"] if x["name"] in "RGB"]; print(" ".join(str(x["rmse"]) for x in c), " ".join(str(x["ssim"]) for x in c))'
}

# case NAME SEED VARIATIONS [SIZE]: flam3-genome's genome for SEED over VARIATIONS (flam3's numbers;
# "-": flam3-genome's default choice), edited for NAME, SIZE x SIZE (384)
run_case() {
    local name=$1 seed=$2 vars=$3 size=${4:-384}
    [ "$vars" = - ] && vars=
    env seed="$seed" isaac_seed="fb$seed" ${vars:+use_vars="$vars"} flam3-genome > "r$seed.flame" 2> /dev/null
    python3 "$HERE/flame-edit.py" "r$seed.flame" "$name.flame" "${name%_*}" "$Q" "$vars" "$size" ||
        { bad "$name: flame-edit failed"; return 1; }
    env isaac_seed=a nthreads=1 out="$name-a.png" flam3-render < "$name.flame" > /dev/null 2>&1 &
    env isaac_seed=b nthreads=1 out="$name-b.png" flam3-render < "$name.flame" > /dev/null 2>&1 &
    local rc=0
    "$FB" flame --file "$name.flame" --size "${size}x$size" --seed "$seed" --backend native --quiet -o "$name.exr" \
        2> "$name.err" || rc=$?
    wait
    # a default genome refused (exit 2, one line): counted by the caller
    if [ $rc -eq 2 ] && [ "${name%_*}" = plain ]; then
        echo "$name refused: $(cat "$name.err")"
        return 2
    fi
    [ $rc -eq 0 ] || { bad "$name: fractalbake failed: $(head -1 "$name.err")"; return 1; }
    judge "$name"
}

# judge NAME: our NAME.exr against flam3's NAME-a.png, held to 1.5 times flam3's NAME-a.png from
# NAME-b.png (another isaac_seed)
judge() {
    local name=$1
    # flam3 truncates to 8 bits where our preview rounds: our linear R, G, B to sRGB, less half a
    # level, rounded (OpenImageIO), is flam3's quantisation of our image
    oiiotool "$name.exr" --ch flame.R,flame.G,flame.B --chnames R,G,B --colorconvert linear sRGB \
        --subc 0.0019607843 -d uint8 -o "$name-8.png" || bad "$name: oiiotool failed"
    [ -s "$name-a.png" ] && [ -s "$name-b.png" ] && [ -s "$name-8.png" ] || { bad "$name: a render is missing"; return; }
    local ref ours
    ref=$(metrics "$name-a.png" "$name-b.png")
    ours=$(metrics "$name-8.png" "$name-a.png")
    if python3 -c "
import sys
r = [float(x) for x in sys.argv[1].split()]
o = [float(x) for x in sys.argv[2].split()]
ok = all(o[k] <= 1.5 * r[k] for k in range(3)) and all(1 - o[k] <= 1.5 * (1 - r[k]) for k in range(3, 6))
print('%-12s flam3 a-b rmse %s ssim %s | ours-a rmse %s ssim %s %s' % (sys.argv[3],
      ' '.join('%.4f' % x for x in r[:3]), ' '.join('%.4f' % x for x in r[3:]),
      ' '.join('%.4f' % x for x in o[:3]), ' '.join('%.4f' % x for x in o[3:]), 'ok' if ok else 'BEYOND 1.5x'))
sys.exit(0 if ok else 1)" "$ref" "$ours" "$name"; then ok; else bad "$name: farther from flam3 than 1.5x flam3's own noise"; fi
}

