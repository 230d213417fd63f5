#!/bin/bash
# Sequences of frames (-o NAME.%04d.exr --frames A-B[:STEP]): a flame's keyframes baked frame by frame,
# each a file of its own with its preview; a frame baked alone is the same file as that frame of the
# whole sequence, on the native backend and on Vulkan; a resumed sequence keeps the frames there from
# the same scene and bakes the missing ones; a frame there from another scene is never replaced; a
# sequence split over 4 tasks (--task K/4) makes the same files as one process; a scene naming its
# frames is a sequence for render, and plan splits it by frames. Then bad selections and patterns
# refused with one line.
# Usage: flame-sequence.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"

# two keyframes of the example genomes 4 apart, few temporal samples (a quick test)
python3 "$HERE/flame-keys.py" k.flame 48 3 0:"$ROOT/docs/examples/flames.flame":0 \
    4:"$ROOT/docs/examples/flames.flame":1 temporal_samples=8 temporal_filter_type=gaussian || bad "flame-keys.py"
seq_bake() { "$FB" flame --file k.flame --size 48x48 --seed 9 "$@"; }

seq_bake --backend native --frames 0-4:2 -o f.%03d.exr --preview p.%03d.png 2> log.txt || bad "the sequence failed: $(cat log.txt)"
[ -s f.000.exr ] && [ -s f.002.exr ] && [ -s f.004.exr ] && [ ! -e f.001.exr ] && ok || bad "frames 0, 2, 4: $(ls)"
[ "$(png_wh p.002.png)" = "48 48" ] && ok || bad "preview of frame 2: $(ls)"
[ "$(grep -c '^fractalbake: frame [024] ([123] of 3): f\.00[024]\.exr$' log.txt)" = 3 ] && ok || bad "progress over frames: $(cat log.txt)"
"$FB" info f.002.exr | grep -q '"time": 2\b' && ok || bad "frame 2's stored scene has not its time"
"$FB" compare f.000.exr f.004.exr --max-abs 0.01 > /dev/null && bad "frames 0 and 4 are the same picture" || ok

# a frame alone is that frame of the sequence, bit for bit; on Vulkan too (and the same pixels as native)
seq_bake --backend native --frames 2 --quiet -o one.%03d.exr && cmp -s one.002.exr f.002.exr && ok ||
    bad "frame 2 alone differs from frame 2 of the sequence"
if have_vulkan; then
    FB_VK_STAGING=1 seq_bake --backend vulkan --frames 0-2:2 --quiet -o v.%03d.exr || bad "the Vulkan sequence failed"
    seq_bake --backend vulkan --frames 2 --quiet -o w.%03d.exr && cmp -s w.002.exr v.002.exr && ok ||
        bad "Vulkan: frame 2 alone differs from frame 2 of the sequence"
    "$FB" compare v.002.exr f.002.exr --max-abs 0 > /dev/null && ok || bad "frame 2: Vulkan's pixels differ from native's"
fi

# resumed: the frames there kept (unchanged), a missing one baked
cp f.002.exr keep.exr
rm f.004.exr
seq_bake --backend native --frames 0-4:2 -o f.%03d.exr 2> log2.txt || bad "the resumed sequence failed: $(cat log2.txt)"
grep -q "2 of 3 frames are there from the same scene: kept" log2.txt && ok || bad "resume: $(cat log2.txt)"
[ "$(grep -c '^fractalbake: frame ' log2.txt)" = 1 ] && grep -q 'frame 4 (1 of 1)' log2.txt && ok || bad "resume baked: $(cat log2.txt)"
cmp -s keep.exr f.002.exr && [ -s f.004.exr ] && ok || bad "resume changed a kept frame or missed frame 4"
# another scene: refused before anything is baked, nothing replaced
expect_fail 2 "f.000.exr: there, baked from another scene: not replaced" "" -- flame --file k.flame --size 48x48 \
    --seed 10 --frames 0-4:2 -o f.%03d.exr
cmp -s keep.exr f.002.exr && ok || bad "a refused sequence replaced a frame"

# 4 tasks of a cluster's array: the same files as one process
for k in 0 1 2 3; do seq_bake --backend native --frames 0-4:2 --task $k/4 --quiet -o t.%03d.exr || bad "task $k/4"; done
for f in 000 002 004; do cmp -s "t.$f.exr" "f.$f.exr" && ok || bad "task-split frame $f differs from one process"; done

# a scene naming its frames: render bakes the sequence; plan lists each task's frames, and render
# --task K/2 bakes just those
printf '{"size": [48, 48], "seed": 9, "frames": "0-4:2", "layers": [{"type": "flame", "file": "k.flame"}]}\n' > s.json
"$FB" render s.json --backend native --quiet -o r.%03d.exr || bad "render of a scene with frames failed"
"$FB" compare r.002.exr f.002.exr --max-abs 0 > /dev/null && ok || bad "render's frame 2 differs from the flame command's"
"$FB" plan s.json --tasks 2 > plan.txt || bad "plan of a sequence failed"
grep -q '^0 *0 to 0 (1 frame)$' plan.txt && grep -q '^1 *2 to 4 (2 frames)$' plan.txt && ok || bad "plan: $(cat plan.txt)"
"$FB" plan s.json --tasks 2 --json | python3 -c 'import json,sys; d=json.load(sys.stdin); assert [t["frames"] for t in d["tasks"]] == [1, 2]' &&
    ok || bad "plan --json of a sequence"
"$FB" render s.json --backend native --quiet --task 1/2 -o u.%03d.exr || bad "render --task 1/2 of a sequence"
[ ! -e u.000.exr ] && cmp -s u.002.exr r.002.exr && cmp -s u.004.exr r.004.exr && ok || bad "task 1/2's frames: $(ls u.*)"

# bad selections and patterns: one line, exit 2, no file
expect_fail 2 "the last frame 1 comes before the first 3" x.003.exr -- flame --file k.flame --frames 3-1 -o x.%03d.exr
expect_fail 2 "expected frames A-B or A-B:STEP" x.000.exr -- flame --file k.flame --frames 0-4:0 -o x.%03d.exr
expect_fail 2 "a frame number is %d or %0Nd" "" -- flame --file k.flame --frames 0-1 -o x.%s.exr
expect_fail 2 "more than one frame number" "" -- flame --file k.flame --frames 0-1 -o x.%d.%d.exr
expect_fail 2 "a sequence needs its frames" "" -- flame --file k.flame -o x.%03d.exr
expect_fail 2 "a sequence writes a file a frame" x.exr -- flame --file k.flame --frames 0-1 -o x.exr
expect_fail 2 "a sequence's previews need a frame number too" "" -- flame --file k.flame --frames 0-1 -o x.%d.exr \
    --preview x.png
no_temp_files && ok || bad "a temporary file left behind"

cli_finish
