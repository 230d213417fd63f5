#!/bin/bash
# The flame's chaos game on Vulkan against the native path, bit for bit (issue 31): the random
# genomes of tests/cli/flame.sh (flame-cases.txt: flam3-genome with fixed seeds, five variations
# each, together all 99 of flam3 3.1.1, each with its feature edited in: post, xaos, final xform,
# palettes, opacity, linear palette, supersample, camera, tone map), baked as a points part 1/1 so that the
# file carries the whole integer histogram (NAME.hist*), on both backends: every channel equal, the
# histogram included. Then the device's 32-bit atomics (FB_VK_NO_INT64=1) on an opaque, a
# translucent and a linear-palette genome, and a points part on Vulkan merged with one baked
# natively. Under the validation layer (FB_VK_VALIDATION=1: any message fails the bake). Not run
# (77) without a Vulkan device or flam3-utils.
# Usage: flame-gpu.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
require_vulkan
if ! command -v flam3-genome > /dev/null; then
    echo "flam3-utils is not installed: not run"
    exit 77
fi
SIZE=${FB_FLAME_GPU_SIZE:-96x96}
Q=${FB_FLAME_GPU_QUALITY:-12}

# genome NAME SEED VARIATIONS: flam3-genome's genome for SEED over VARIATIONS, edited for NAME (its
# feature: the name before any "_")
genome() {
    local name=$1 seed=$2 ids=$3
    env seed="$seed" isaac_seed="fb$seed" use_vars="$ids" flam3-genome > "r$seed.flame" 2> /dev/null
    python3 "$HERE/flame-edit.py" "r$seed.flame" "$name.flame" "${name%_*}" "$Q" "$ids" || bad "$name: flame-edit failed"
}

# same NAME [ENV...]: the genome on both backends, every channel (the histogram's too) the same;
# supersample 2's histogram is too large for a points part's channels: the image's (its count,
# and the accumulations computed from every cell) only
same() {
    local name=$1 part="--points-part 1/1"
    shift
    [ "${name%_*}" = supersample ] && part=
    "$FB" flame --file "$name.flame" --size "$SIZE" --seed 5 --backend native $part --quiet \
        -o "$name-n.exr" || { bad "$name: native failed"; return; }
    env "$@" "$FB" flame --file "$name.flame" --size "$SIZE" --seed 5 --backend vulkan --validation $part \
        --quiet -o "$name-v.exr" || { bad "$name: vulkan failed"; return; }
    [ -z "$part" ] || "$FB" info "$name-v.exr" | grep -q 'flame.hist0_lo' || { bad "$name: no histogram channels"; return; }
    if "$FB" compare "$name-n.exr" "$name-v.exr" --max-abs 0 > "$name.cmp"; then ok; else
        bad "$name ($*): Vulkan differs from native: $(grep -v ' ok$' "$name.cmp" | head -3)"
    fi
}

while read -r name seed vars <&3; do genome "$name" "$seed" "$vars" && same "$name"; done 3< "$HERE/flame-cases.txt"
# the 32-bit atomics: opaque (4 fields a cell), translucent (6) and the linear palette
for g in post opacity linear; do same $g FB_VK_NO_INT64=1; done
# the 64-bit histogram's folds (kernels/flame.h: a cell's words are exact for 2^26 - 1 points between
# folds): two xforms that map every point to (0.01, 0.01), one cell, 71.7M points in it, opaque (3
# words a cell) and translucent (5); without the folds its hits wrap past 2^26
for op in 1 0.5; do
    cat > "one$op.flame" << EOF
<flame size="16 16" center="0 0" scale="4" rotate="0" supersample="1" filter="0.5" quality="280000" palette="7"
 background="0 0 0" brightness="4" gamma="4" vibrancy="1" estimator_radius="0" estimator_minimum="0">
  <xform weight="0.5" color="0.2" color_speed="0.5" linear="1" coefs="0 0 0 0 0.01 0.01" opacity="1"/>
  <xform weight="0.5" color="0.9" color_speed="0.5" linear="1" coefs="0 0 0 0 0.01 0.01" opacity="$op"/>
</flame>
EOF
    SIZE=16x16 same "one$op"
done
# the histogram is not trivially equal: another seed gives another one
"$FB" flame --file post.flame --size "$SIZE" --seed 6 --backend vulkan --points-part 1/1 --quiet -o post-s6.exr
"$FB" compare post-v.exr post-s6.exr --max-abs 0 > /dev/null
[ $? -eq 1 ] && ok || bad "another seed gave the same histogram"

# points parts from both backends merge to the one-backend bake
"$FB" flame --file xaos.flame --size "$SIZE" --seed 5 --backend native --quiet -o xw.exr
"$FB" flame --file xaos.flame --size "$SIZE" --seed 5 --backend vulkan --points-part 1/2 --quiet -o xp1.exr
"$FB" flame --file xaos.flame --size "$SIZE" --seed 5 --backend native --points-part 2/2 --quiet -o xp2.exr
"$FB" merge xp1.exr xp2.exr -o xm.exr --quiet && "$FB" compare xw.exr xm.exr --max-abs 0 > /dev/null && ok ||
    bad "a Vulkan points part and a native one do not merge to the native bake"
cli_finish
