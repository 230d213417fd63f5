#!/usr/bin/env bash
# L-systems: presets, rules by hand, flags, stochastic seeds, determinism, condensation sets.
# Needs a Vulkan device (lavapipe at least): it compares backends. Usage: lsystem.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
require_vulkan
S="--size 96x64 --quiet"

# ---- lsystem ----
L="lsystem --size 96x64 --quiet"
printf '{"size": [64, 32], "layers": [{"type": "lsystem", "axiom": "F",\n "rules": ["F=F[+F]", 3]}]}' > lrule.json
if "$FB" lsystem --size 96x64 --preset tree -o lt.exr --preview lt.png 2> err.txt; then ok; else bad "lsystem failed: $(cat err.txt)"; fi
grep -q "wrote lt.exr" err.txt && ok || bad "lsystem: no summary line"
valid_exr lt.exr
"$FB" info lt.exr > info4.txt
grep -q "layer plants .*A (half)" info4.txt && grep -q "R (half)" info4.txt && ok || bad "lsystem layer channels: $(cat info4.txt)"
grep -q '"X=X\[-FFF\]F\[+FFF\]FX"' info4.txt && ok || bad "the preset's rules are not spelled out in the stored scene"
[ "$(od -An -tu1 -j25 -N1 lt.png | tr -d ' ')" = "2" ] && ok || bad "the lsystem preview is not an RGB PNG"
# the preset equals its rules given by hand (repeatable --rule)
"$FB" $L --axiom Y --rule 'Y=YFX[+Y][-Y]' --rule 'X=X[-FFF]F[+FFF]FX' --iterations 6 --angle 25.7 -o lh.exr
"$FB" $L --preset tree -o lp.exr
"$FB" compare lh.exr lp.exr > /dev/null && ok || bad "--rule (repeated) differs from the tree preset"
# flags change the picture: width, taper, angle, iterations, heading, palette, seed (stochastic)
for f in "--width 2" "--taper 0.3" "--angle 30" "--iterations 5" "--heading 60" "--palette blossom"; do
  "$FB" $L --preset tree $f -o lf.exr
  "$FB" compare lp.exr lf.exr > /dev/null; [ $? -eq 1 ] && ok || bad "lsystem $f changed nothing"
done
"$FB" $L --preset stochastic --seed 1 -o ls1.exr
"$FB" $L --preset stochastic --seed 2 -o ls2.exr
"$FB" compare ls1.exr ls2.exr > /dev/null; [ $? -eq 1 ] && ok || bad "the stochastic preset ignores the seed"
# the same bits on every thread count, strip height and backend
"$FB" $L --preset stochastic --float --backend native --threads 1 --strip-rows 5 -o ln1.exr
"$FB" $L --preset stochastic --float --backend native --threads 3 --strip-rows 64 -o ln2.exr
"$FB" $L --preset stochastic --float -o lv1.exr
cmp -s ln1.exr ln2.exr && ok || bad "lsystem (native) depends on threads or strip rows"
"$FB" compare ln1.exr lv1.exr --max-abs 0 > /dev/null && ok || bad "lsystem differs between lavapipe and native"
"$FB" lsystem --help | grep -q -- "--rule " && ok || bad "lsystem --help lists no --rule"
# an L-system as the condensation set of an IFS
if "$FB" ifs --size 96x48 --quiet --points 300000 --maps "0.75,0,0,0.75,0.25,0" --condensation lsystem:tree -o lc.exr 2> err.txt; then ok; else bad "ifs with an L-system condensation set failed: $(cat err.txt)"; fi
"$FB" info lc.exr | grep -q '"Y=YFX\[+Y\]\[-Y\]"' && ok || bad "the condensation L-system is not spelled out in the stored scene"
"$FB" ifs --size 96x48 --quiet --points 300000 --maps "0.75,0,0,0.75,0.25,0" --condensation '{"preset": "tree", "height": 0.1}' -o lc2.exr
"$FB" compare lc.exr lc2.exr > /dev/null; [ $? -eq 1 ] && ok || bad "the condensation height changed nothing"
"$FB" ifs --size 96x48 --quiet --points 300000 --maps "0.75,0,0,0.75,0.25,0" --condensation '{"preset": "tree", "heading": 80}' -o lc3.exr
"$FB" compare lc.exr lc3.exr > /dev/null; [ $? -eq 1 ] && ok || bad "the condensation heading changed nothing"

cli_finish
