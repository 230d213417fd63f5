#!/bin/bash
# Fractal flames against flam3 3.1.1 (flam3-render), on random genomes of flam3-genome with fixed
# seeds that together use every variation we render, and the features each case edits in
# (tests/cli/flame-edit.py): post, xaos, final xform, each palette form, opacity, linear palette,
# supersample, camera, tone map. For every genome our image is no farther from flam3's than 1.5
# times the distance between two flam3 renders with different isaac_seed (RMSE per channel and SSIM
# on the tone-mapped RGB, 8-bit). Then: an unsupported variation refused, the same bits on any
# thread count and strip height.
# Usage: flame.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
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

# case NAME SEED VARIATIONS: flam3-genome's genome for SEED over VARIATIONS, edited for NAME
run_case() {
    local name=$1 seed=$2 vars=$3 ids
    ids=$(python3 -c "import sys; n=sys.argv[1].split(','); print(','.join(str(x) for x in n))" "$vars")
    env seed="$seed" isaac_seed="fb$seed" use_vars="$ids" flam3-genome > "r$seed.flame" 2> /dev/null
    python3 "$HERE/flame-edit.py" "r$seed.flame" "$name.flame" "$name" "$Q" "$(python3 -c "
import sys
names = '''linear sinusoidal spherical swirl horseshoe polar handkerchief heart disc spiral hyperbolic diamond ex julia
bent waves fisheye popcorn exponential power cosine rings fan blob pdj fan2 rings2 eyefish bubble cylinder
perspective noise julian juliascope blur gaussian_blur radial_blur pie ngon curl rectangles arch tangent square
rays blade secant2 twintrian cross disc2 super_shape flower conic parabola bent2'''.split()
print(','.join(names[int(i)] for i in sys.argv[1].split(',')))" "$ids")" || { bad "$name: flame-edit failed"; return; }
    env isaac_seed=a nthreads=1 out="$name-a.png" flam3-render < "$name.flame" > /dev/null 2>&1 &
    env isaac_seed=b nthreads=1 out="$name-b.png" flam3-render < "$name.flame" > /dev/null 2>&1 &
    "$FB" flame --file "$name.flame" --size 512x512 --seed "$seed" --backend native --quiet -o "$name.exr" \
        || bad "$name: fractalbake failed"
    wait
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

# every variation we render (0 to 54), five a genome, each genome with one feature (flame-cases.txt:
# name, flam3-genome's seed, variations)
while read -r name seed vars <&3; do run_case "$name" "$seed" "$vars"; done 3< "$HERE/flame-cases.txt"

# a variation outside flam3 (an Apophysis plugin): exit 2, one line naming it and the xform, no file
sed 's/<xform weight="\([^"]*\)"/<xform weight="\1" hemisphere="0.3"/' post.flame > hemi.flame
expect_fail 2 "xform [0-9]*: unknown variation or attribute .hemisphere" u.exr -- flame --file hemi.flame --size 64x64 -o u.exr
sed 's/<xform weight="\([^"]*\)"/<xform weight="\1" linear3D="0.3"/' post.flame > l3d.flame
expect_fail 2 "xform [0-9]*: unknown variation or attribute .linear3D" u.exr -- flame --file l3d.flame --size 64x64 -o u.exr
expect_fail 2 "no <flame> named" u.exr -- flame --file post.flame --flame nosuch --size 64x64 -o u.exr

# the same bits on any thread count and strip height
"$FB" flame --file xaos.flame --size 128x96 --quality 20 --backend native --threads 1 --strip-rows 7 --quiet -o t1.exr
"$FB" flame --file xaos.flame --size 128x96 --quality 20 --backend native --threads 2 --strip-rows 64 --quiet -o t2.exr
cmp -s t1.exr t2.exr && ok || bad "flame depends on threads or strip rows"
"$FB" flame --file final.flame --size 128x96 --quality 20 --backend native --threads 3 --quiet -o t3.exr
"$FB" flame --file final.flame --size 128x96 --quality 20 --backend native --threads 1 --quiet -o t4.exr
cmp -s t3.exr t4.exr && ok || bad "flame (final xform) depends on threads"
# re-toned from the stored accumulations: unchanged parameters give the same bytes, new ones the
# pixels of a bake made with them
"$FB" tonemap t1.exr -o t1b.exr --quiet && cmp -s t1.exr t1b.exr && ok || bad "tonemap with unchanged parameters changed the flame"
"$FB" flame --file xaos.flame --size 128x96 --quality 20 --backend native --brightness 9 --gamma 2.5 --vibrancy 0.5 \
    --background 0.2,0.1,0 --quiet -o tm.exr
"$FB" tonemap t1.exr -o tm2.exr --brightness 9 --gamma 2.5 --vibrancy 0.5 --background 0.2,0.1,0 --quiet
"$FB" compare tm.exr tm2.exr --max-abs 0 > /dev/null && ok || bad "flame tonemap differs from a bake with the same tone parameters"
"$FB" compare tm.exr t1.exr --max-abs 0.01 > /dev/null && bad "--brightness 9 --gamma 2.5 changed nothing" || ok
# points parts (render --points-part, and a plan's tasks) merged, in any order: the whole bake's
# bytes (parts baked on 1, 3 and 5 threads); a part alone differs from it
"$FB" flame --file xaos.flame --size 128x96 --quality 20 --backend native --threads 2 --quiet -o pw.exr
for k in 1 2 3; do
    "$FB" flame --file xaos.flame --size 128x96 --quality 20 --backend native --threads $((2 * k - 1)) \
        --points-part $k/3 --quiet -o pp$k.exr || bad "flame points part $k/3 failed"
done
"$FB" merge pp3.exr pp1.exr pp2.exr -o ppm.exr --quiet && cmp -s pw.exr ppm.exr && ok || bad "flame points parts do not merge to the whole bake"
cmp -s pw.exr pp2.exr && bad "a flame points part is the whole bake" || ok
"$FB" compare pw.exr pp2.exr --layer flame > /dev/null; [ $? -eq 1 ] && ok || bad "a flame points part holds the whole game"
printf '{"size": [128, 96], "seed": 7, "layers": [{"type": "flame", "file": "final.flame", "quality": 200},
 {"type": "fbm", "name": "clouds", "octaves": 3}]}' > fplan.json
"$FB" plan fplan.json --tasks 4 --task-startup 0 --json > fplan.plan
check "a flame is split by points parts" python3 -c "
import json; p = json.load(open('fplan.plan')); s = {l['name']: l['split'] for l in p['layers']}
assert s['flame'] == 'points parts' and p['points_parts'] >= 2, (s, p['points_parts'])"
"$FB" render fplan.json -o fpw.exr --quiet
rm -rf ft && mkdir ft
for k in 0 1 2 3; do "$FB" render fplan.json --task-startup 0 --task $k/4 -o ft/t$k.exr --quiet || bad "flame task $k/4 failed"; done
"$FB" merge ft/t*.exr -o fpm.exr --quiet && cmp -s fpw.exr fpm.exr && ok || bad "a flame plan's tasks do not merge to the whole bake"

# a flame picked by index or by name: the same pixels
"$FB" flame --file final.flame --flame test-final --size 128x96 --quality 20 --quiet -o t5.exr
"$FB" compare t4.exr t5.exr --max-abs 0 > /dev/null && ok || bad "--flame 0 and --flame test-final differ"
cli_finish
