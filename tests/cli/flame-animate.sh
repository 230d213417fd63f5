#!/bin/bash
# Flame animations against flam3 3.1.1 (flam3-animate): keyframes made by flam3-genome (sequence,
# inter, rotate) and by hand from the test genomes (tests/cli/flame-edit.py) and flam3's shipped
# test.flam3, with every interpolation (linear, smooth), interpolation_type (log, linear, old,
# older), palette_interpolation (hsv_circular, hsv, rgb, sweep) and temporal filter (box, gaussian,
# exp); xforms padded where keyframes differ (a final xform in one alone, more xforms in one). Each
# frame, motion blur included, is no farther from flam3-animate's than 1.5 times the distance
# between two flam3-animate renders with another isaac_seed (tests/cli/flame-measure.bash). Then bad
# keyframes refused with one line.
# Usage: flame-animate.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
. "$HERE/flame-measure.bash"
S=128

# genome NAME: the test genome of flame-cases.txt named NAME, as flame.sh makes it
genome() {
    local seed vars
    read -r seed vars < <(awk -v n="$1" '$1 == n { print $2, $3 }' "$HERE/flame-cases.txt")
    env seed="$seed" isaac_seed="fb$seed" use_vars="$vars" flam3-genome > "r$1.flame" 2> /dev/null
    python3 "$HERE/flame-edit.py" "r$1.flame" "$1.flame" "${1%_*}" "$Q" "$vars" "$S" || bad "$1: flame-edit failed"
}

# frame NAME FILE TIME: flam3-animate's frame TIME of FILE (isaac_seed a and b) and ours, judged
frame() {
    local name=$1 file=$2 t=$3 rc=0
    env begin="$t" end="$t" isaac_seed=a nthreads=1 out="$name-a.png" flam3-animate < "$file" > /dev/null 2>&1 &
    env begin="$t" end="$t" isaac_seed=b nthreads=1 out="$name-b.png" flam3-animate < "$file" > /dev/null 2>&1 &
    "$FB" flame --file "$file" --time "$t" --size ${S}x$S --seed 3 --backend native --quiet -o "$name.exr" \
        2> "$name.err" || rc=$?
    wait
    [ $rc -eq 0 ] || { bad "$name: fractalbake failed: $(head -1 "$name.err")"; return 1; }
    judge "$name"
}

keys() { python3 "$HERE/flame-keys.py" "$@" || bad "flame-keys.py $*"; }

for g in post xaos final palette-rgb colors library opacity linear camera tone supersample; do genome "$g"; done

# two keyframes 4 apart, frame 2 between them, and each way of interpolating
keys pair-log.flame $S "$Q" 0:post.flame 4:xaos.flame
frame pair-log pair-log.flame 2
keys pair-linear.flame $S "$Q" 0:final.flame 4:palette-rgb.flame interpolation_type=linear palette_interpolation=rgb
frame pair-linear pair-linear.flame 2
keys pair-old.flame $S "$Q" 0:colors.flame 4:library.flame interpolation_type=old palette_interpolation=hsv
frame pair-old pair-old.flame 1
keys pair-older.flame $S "$Q" 0:opacity.flame 4:final.flame interpolation_type=older palette_interpolation=sweep
frame pair-older pair-older.flame 3
# the final xform in the second alone, the first with more xforms: padding by flam3_align's rules
keys pair-pad.flame $S "$Q" 0:camera.flame 4:final.flame
frame pair-pad pair-pad.flame 2
# motion blur: a wide gaussian, and exp both ways, over keyframes one apart
keys blur-gauss.flame $S "$Q" 0:post.flame 1:xaos.flame 2:tone.flame temporal_filter_type=gaussian temporal_filter_width=2
frame blur-gauss blur-gauss.flame 1
keys blur-exp.flame $S "$Q" 0:linear.flame 1:post.flame 2:xaos.flame temporal_filter_type=exp temporal_filter_exp=2
frame blur-exp blur-exp.flame 1
keys blur-exp2.flame $S "$Q" 0:xaos.flame 1:supersample.flame 2:post.flame temporal_filter_type=exp temporal_filter_exp=-1.5
frame blur-exp2 blur-exp2.flame 1
# smooth (Catmull-Rom) on the inner segment of four keyframes
keys smooth.flame $S "$Q" 0:post.flame 3:xaos.flame 6:colors.flame 9:linear.flame interpolation=smooth
frame smooth smooth.flame 4

# flam3-genome's own keyframes: a sequence (rotations, then the blend), inter and rotate
keys two.flame $S "$Q" 0:xaos.flame 1:library.flame
env sequence=two.flame nframes=8 flam3-genome > seq.flame 2> /dev/null
frame seq-rotate seq.flame 3
frame seq-blend seq.flame 12
env inter=two.flame frame=2 nframes=6 flam3-genome > inter.flame 2> /dev/null
frame inter inter.flame 2
# rotate takes one genome: camera's, whose <symmetry> xforms stay still (animate 0)
env rotate=camera.flame frame=2 nframes=6 flam3-genome > rotate.flame 2> /dev/null
frame rotate rotate.flame 2
# flam3's shipped animation (library palettes, time 0 to 100)
keys shipped.flame $S "$Q" /usr/share/flam3/test.flam3
frame shipped shipped.flame 40

# bad keyframes: one line, exit 2, no file
keys order.flame $S 4 3:post.flame 1:xaos.flame
expect_fail 2 "keyframes must be in increasing time: time 1 follows 3" u.exr -- flame --file order.flame --time 2 -o u.exr
keys same.flame $S 4 1:post.flame 1:xaos.flame
expect_fail 2 "keyframes must be in increasing time" u.exr -- flame --file same.flame --time 1 -o u.exr
keys badtype.flame $S 4 0:post.flame 1:xaos.flame interpolation_type=cubic
expect_fail 2 "attribute interpolation_type: expected log, linear, old, older, found 'cubic'" u.exr -- \
    flame --file badtype.flame --time 0.5 -o u.exr
keys badtime.flame $S 4 0:post.flame x:xaos.flame
expect_fail 2 "attribute time: expected a number, found 'x'" u.exr -- flame --file badtime.flame --time 0.5 -o u.exr
keys badfilter.flame $S 4 0:post.flame 1:xaos.flame temporal_filter_type=tent
expect_fail 2 "attribute temporal_filter_type: expected box, gaussian, exp, found 'tent'" u.exr -- \
    flame --file badfilter.flame --time 0.5 -o u.exr
expect_fail 2 "no flame picks one" u.exr -- flame --file pair-log.flame --time 1 --flame 0 -o u.exr

cli_finish
