#!/bin/bash
# Fractal flames against flam3 3.1.1 (flam3-render), on random genomes of flam3-genome with fixed
# seeds that together use all 99 of flam3's variations, and the features each case edits in
# (tests/cli/flame-edit.py): post, xaos, final xform, each palette form, opacity, linear palette,
# supersample, camera, tone map. For every genome our image is no farther from flam3's than 1.5
# times the distance between two flam3 renders with different isaac_seed (RMSE per channel and SSIM
# on the tone-mapped RGB, 8-bit: tests/cli/flame-measure.bash). Then: a variation outside flam3
# refused, the same bits on any thread count and strip height.
# Usage: flame.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
. "$HERE/flame-measure.bash"

# every variation (0 to 98), five a genome, each genome with one feature (flame-cases.txt: name, its
# feature before any "_", flam3-genome's seed, variations)
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
