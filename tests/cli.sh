#!/usr/bin/env bash
# End-to-end tests of the fractalbake command line: bad input, compare, determinism, the files
# themselves (strict header check by OpenEXRCore's exrinfo, full decode by the C++ library), and
# atomic replacement. Usage: cli.sh PATH/TO/fractalbake
set -u
FB=$(realpath "$1")
HERE=$(cd "$(dirname "$0")" && pwd)
T=$(mktemp -d /tmp/fb-test-cli-XXXXXX)
trap 'rm -rf "$T"' EXIT
cd "$T" || exit 1
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-$T}
pass=0
fail=0
ok() { pass=$((pass + 1)); }
bad() { fail=$((fail + 1)); echo "FAIL: $*" >&2; }

# expect_fail CODE PATTERN OUTFILE -- ARGS: exit CODE, exactly one stderr line matching PATTERN, no OUTFILE
expect_fail() {
  local code=$1 pat=$2 out=$3
  shift 4
  "$FB" "$@" > "$T/stdout" 2> "$T/stderr"
  local rc=$? lines
  lines=$(wc -l < "$T/stderr")
  if [ $rc -ne "$code" ]; then bad "$* : exit $rc, wanted $code ($(cat "$T/stderr"))"; return; fi
  if [ "$lines" -ne 1 ]; then bad "$* : $lines stderr lines, wanted 1: $(cat "$T/stderr")"; return; fi
  if ! grep -q -- "$pat" "$T/stderr"; then bad "$* : stderr lacks '$pat': $(cat "$T/stderr")"; return; fi
  if [ -n "$out" ] && [ -e "$out" ]; then bad "$* : left $out behind"; return; fi
  if ls -A "$T" | grep -q '\.tmp$'; then bad "$* : left a temporary file"; return; fi
  ok
}

# valid_exr FILE: strict header check and a full decode through the OpenEXR C++ library
valid_exr() {
  if exrinfo --strict "$1" > /dev/null 2>&1 && exrmaketiled "$1" "$T/tiled.exr" > /dev/null 2>&1; then ok; else bad "$1 is not a valid EXR"; fi
  rm -f "$T/tiled.exr"
}

S="--size 96x64 --quiet"

# ---- bad input: flags ----
expect_fail 2 "nodir/o.exr: cannot create the output: folder" "$T/nodir/o.exr" -- fbm $S -o "$T/nodir/o.exr"

# ---- bad input: julia ----
FB_VK_NO_FLOAT64=1 expect_fail 2 "needs a Vulkan device with shaderFloat64" o.exr -- julia $S --precision double --backend vulkan -o o.exr
printf '{"size": [64, 32], "layers": [{"type": "julia", "channels": []}]}' > chan.json
# a subset of channels: exactly those in the file, equal to the full layer's; iter alone previews
if "$FB" julia $S --channels iter,de -o sub.exr --preview sub.png && "$FB" julia $S -o full.exr &&
  [ "$("$FB" info sub.exr | sed -n 's/^channels: *//p')" = 2 ] && "$FB" compare sub.exr full.exr --ignore-missing > /dev/null &&
  "$FB" julia $S --channels iter -o it.exr --preview it.png && [ -s it.png ] && [ -s sub.png ]; then ok; else bad "julia --channels"; fi
"$FB" julia $S --stops "0,0,0,0;0.5,1,0,0;1,1,1,1" --density 0 --brightness 2 -o js.exr && ok || bad "julia with stops failed"
if "$FB" julia $S --alpha 0.5,0.25 -o j.exr --preview j.png 2> err.txt; then ok; else bad "julia bake failed: $(cat err.txt)"; fi
[ "$(od -An -tu1 -j25 -N1 j.png | tr -d ' ')" = "2" ] && ok || bad "the julia preview is not an RGB PNG"
"$FB" info j.exr | grep -q "R (half)" && ok || bad "julia colour is not half by default"
"$FB" julia $S --float -o jf.exr && "$FB" info jf.exr | grep -q "R (float)" && ok || bad "--float does not store float colour"
valid_exr j.exr
"$FB" info j.exr | grep -q "layer sky .*iter (uint)" && ok || bad "julia layer lacks sky.iter as uint"

# ---- bad input: ifs ----
I="ifs --size 96x64 --quiet --points 200000"
printf '{"size": [64, 32], "layers": [{"type": "ifs",\n "maps": []}]}' > empty.json
printf '{"size": [64, 32], "layers": [{"type": "ifs", "maps": [[0.5, 0, 0, 0.5, 0, 0],\n [0.5, 0, 0, 0.5, 1, NaN]]}]}' > nanmap.json
"$FB" ifs --size 64x48 --quiet --points 1e5 -o e5.exr && "$FB" info e5.exr | grep -q '"points": 100000' && ok || bad "--points 1e5 is not the integer 100000"
printf 'leaf {\n  .5 0 0 .5 0 0 .5\n  .5 0 0 .5 1 0 zz\n}\n' > broken.ifs
printf 'halves { .5 0 0 .5 0 0 .5 .5 0 0 .5 1 0 .5 }\nthirds {\n .33 0 0 .33 0 0 .3 .33 0 0 .33 .66 0 .3 .33 0 0 .33 .33 .5 .4\n}\n' > two.ifs
if "$FB" $I --file two.ifs --name thirds -o t.exr 2> err.txt; then ok; else bad "ifs from a file failed: $(cat err.txt)"; fi
"$FB" info t.exr | grep -q '0.66' && ok || bad "the file's maps are not stored in the scene"
"$FB" info t.exr | grep -q '"file"' && bad "the stored scene still names the file" || ok
"$FB" $I --maps ".33,0,0,.33,0,0,.3;.33,0,0,.33,.66,0,.3;.33,0,0,.33,.33,.5,.4" -o t2.exr --quiet
"$FB" compare t.exr t2.exr > /dev/null && ok || bad "the same maps from a file and from --maps differ"
if "$FB" ifs --size 96x64 --points 300000 --preset population -o pop.exr --preview pop.png --quiet 2> err.txt; then ok; else bad "population failed: $(cat err.txt)"; fi
[ -s err.txt ] && bad "a clean ifs bake wrote to stderr: $(cat err.txt)" || ok
valid_exr pop.exr
"$FB" info pop.exr > info3.txt
grep -q "layer plants .*count (uint)" info3.txt && grep -q "A (half)" info3.txt && grep -q "density (float)" info3.txt && ok || bad "ifs layer channels: $(cat info3.txt)"
[ "$(od -An -tu1 -j25 -N1 pop.png | tr -d ' ')" = "2" ] && ok || bad "the ifs preview is not an RGB PNG"
# the same bits on every thread count, strip height and backend
"$FB" $I --preset maple --oversample 2 --backend native --threads 1 --strip-rows 7 -o in1.exr
"$FB" $I --preset maple --oversample 2 --backend native --threads 3 --strip-rows 64 -o in2.exr
"$FB" $I --preset maple --oversample 2 -o iv1.exr
cmp -s in1.exr in2.exr && ok || bad "ifs (native) depends on threads or strip rows"
"$FB" compare in1.exr iv1.exr --max-abs 0 > /dev/null && ok || bad "ifs differs between lavapipe and native"
# tone mapping re-run from the stored channels: the same parameters give the same bytes, new ones
# the same pixels as a bake made with them
"$FB" $I -o tm1.exr
"$FB" tonemap tm1.exr -o tm1b.exr --quiet && cmp -s tm1.exr tm1b.exr && ok || bad "tonemap with unchanged parameters changed the file"
"$FB" $I --brightness 2.5 --gamma 3 --vibrancy 0.5 --highlight-power -1 --palette blossom -o tm2.exr
"$FB" tonemap tm1.exr -o tm2b.exr --brightness 2.5 --gamma 3 --vibrancy 0.5 --highlight-power -1 --palette blossom
"$FB" compare tm2.exr tm2b.exr --max-abs 0 > /dev/null && ok || bad "tonemap differs from a bake with the same tone parameters"
"$FB" info tm2b.exr | grep -q '"brightness": 2.5' && ok || bad "tonemap did not store the new parameters"
"$FB" compare tm1.exr tm2b.exr --layer plants > /dev/null; [ $? -eq 1 ] && ok || bad "new tone parameters changed nothing"
expect_fail 2 "not a tone-mapping flag" x.exr -- tonemap tm1.exr -o x.exr --points 5
expect_fail 2 "brightness" x.exr -- tonemap tm1.exr -o x.exr --brightness -1
"$FB" fbm $S -o f0.exr
expect_fail 2 "no ifs layer" x.exr -- tonemap f0.exr -o x.exr

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

# ---- bad input: scene files ----
printf '{"size": [64, 32],\n "layers": [\n  {"type": "fbm", "octaves": 3,\n   "octavez": 2}\n ]\n}\n' > unknown.json
printf '{"size": [64, 32], "layers": [{"type": "fbm",\n "octaves": "3"}]}' > wrongtype.json
printf '{"size": [64, 32], "layers": [{"type": "fbm", "octaves": 3,]}' > malformed.json
printf '{"size": [64, 32], "layers": [{"type": "fbm", "hurst": NaN}]}' > nan.json
printf '{"size": [64, 32], "layers": [{"type": "fbm", "octaves": 0}]}' > range.json
printf '{"size": [64, 32], "layers": [{"type": "sky"}]}' > gen.json
printf '{"size": [64, 32], "layers": [{"type": "fbm"}, {"type": "fbm"}]}' > dup.json
printf '{"size": [64, 32]}' > nolayers.json
mkdir -p unreadable.json

# ---- a bake, the file, info ----
if "$FB" fbm $S --seed 5 --octaves 6 -o a.exr --preview a.png 2> err.txt; then ok; else bad "fbm bake failed: $(cat err.txt)"; fi
[ -s err.txt ] && bad "a clean bake wrote to stderr: $(cat err.txt)" || ok
valid_exr a.exr
if head -c 8 a.png | od -An -c | grep -q 'P   N   G'; then ok; else bad "preview is not a PNG"; fi
"$FB" info a.exr > info.txt
grep -q 'layer fbm .*Y (float)' info.txt && ok || bad "info lacks the fbm layer: $(cat info.txt)"
grep -q '"octaves": 6' info.txt && ok || bad "info lacks the stored scene"
grep -q '"seed": 5' info.txt && ok || bad "stored scene lacks the seed"

# the default scene, with every format
for c in zip piz none; do
  printf '{"size": [80, 48], "seed": 3, "compression": "%s", "layers": [{"type": "fbm", "warp": 0.5}, {"type": "fbm", "name": "h", "half": true, "noise": "cellular"}]}' $c > s_$c.json
  if "$FB" render s_$c.json -o s_$c.exr --quiet; then ok; else bad "render $c failed"; fi
  valid_exr s_$c.exr
done
"$FB" compare s_zip.exr s_piz.exr > /dev/null && ok || bad "zip and piz files differ"
"$FB" compare s_zip.exr s_none.exr > /dev/null && ok || bad "zip and none files differ"

# a scene with both generators: one file, every layer's channels, each with its own type
printf '{"size": [120, 60], "seed": 4, "layers": [{"type": "julia", "name": "sky", "mapping": "polar", "alpha": [-0.3, 0]}, {"type": "fbm", "name": "height", "octaves": 5}]}' > mixed.json
if "$FB" render mixed.json -o mixed.exr --preview mixed.png --quiet; then ok; else bad "mixed scene failed"; fi
valid_exr mixed.exr
"$FB" info mixed.exr > info2.txt
grep -q "layer height .*Y (float)" info2.txt && grep -q "layer sky .*iter (uint)" info2.txt && grep -q "R (half)" info2.txt && ok || bad "mixed scene lacks a layer: $(cat info2.txt)"
"$FB" render mixed.json -o mixed_n.exr --backend native --quiet
"$FB" compare mixed.exr mixed_n.exr --layer height --max-abs 1e-5 > /dev/null && ok || bad "mixed scene: fbm layer differs between backends"
"$FB" compare mixed.exr mixed_n.exr --layer sky --max-abs 0.5 --fail-percent 1 > /dev/null && ok || bad "mixed scene: sky layer differs between backends beyond 1% of pixels"

# ---- determinism ----
"$FB" fbm $S --seed 9 --warp 1 --backend native --threads 1 --strip-rows 64 -o n1.exr
"$FB" fbm $S --seed 9 --warp 1 --backend native --threads 2 --strip-rows 5 -o n2.exr
"$FB" fbm $S --seed 9 --warp 1 --backend native --threads 7 --strip-rows 17 -o n3.exr
cmp -s n1.exr n2.exr && cmp -s n1.exr n3.exr && ok || bad "native result depends on threads or strip rows"
"$FB" fbm $S --seed 9 --warp 1 -o v1.exr
"$FB" fbm $S --seed 9 --warp 1 --strip-rows 3 -o v2.exr
cmp -s v1.exr v2.exr && ok || bad "the same command twice (other strip rows) gave different bytes"

J="julia --size 96x64 --quiet --mapping polar --alpha -0.3,0 --turbulence 0.2 --samples 3"
"$FB" $J --backend native --threads 1 --strip-rows 64 -o jn1.exr
"$FB" $J --backend native --threads 3 --strip-rows 7 -o jn2.exr
cmp -s jn1.exr jn2.exr && ok || bad "julia (native) depends on threads or strip rows"
"$FB" $J --strip-rows 5 -o jv1.exr
"$FB" $J --strip-rows 64 -o jv2.exr
cmp -s jv1.exr jv2.exr && ok || bad "julia (vulkan) depends on strip rows"

# ---- atomic replacement ----
cp a.exr keep.exr
before=$(md5sum < keep.exr)
expect_fail 2 "octaves" "" -- fbm $S --octaves 99 -o keep.exr
[ "$(md5sum < keep.exr)" = "$before" ] && ok || bad "a failed bake damaged the existing output"
"$FB" fbm $S --seed 6 -o keep.exr --quiet
[ "$(md5sum < keep.exr)" != "$before" ] && ok || bad "a successful bake did not replace the output"
valid_exr keep.exr

# ---- compare ----
"$FB" compare a.exr a.exr > cmp.txt && ok || bad "identical files do not compare equal"
grep -q "max_abs 0" cmp.txt && ok || bad "identical: max_abs not 0"
"$FB" fbm $S --seed 5 --octaves 6 --offset 0.001,0 -o b.exr --quiet
"$FB" compare a.exr b.exr > cmp.txt; [ $? -eq 1 ] && ok || bad "different files compare equal"
grep -q "at pixel (" cmp.txt && ok || bad "compare does not name the pixel"
"$FB" compare a.exr b.exr --max-abs 1 > /dev/null && ok || bad "--max-abs 1 should pass a tiny offset"
"$FB" compare a.exr b.exr --fail-percent 100 --max-abs 0 > /dev/null && ok || bad "--fail-percent 100 should pass"
"$FB" compare a.exr b.exr --psnr 1000 > /dev/null; [ $? -eq 1 ] && ok || bad "--psnr 1000 should fail"
"$FB" compare a.exr b.exr --diff d.exr > /dev/null; valid_exr d.exr
"$FB" fbm $S --seed 5 --octaves 6 --layer other -o c.exr --quiet
"$FB" compare a.exr c.exr > cmp.txt; [ $? -eq 1 ] && ok || bad "missing channels should fail"
grep -q "fbm.Y: only in a.exr" cmp.txt && grep -q "other.Y: only in c.exr" cmp.txt && ok || bad "missing channels not reported"
"$FB" compare a.exr c.exr --ignore-missing > /dev/null && ok || bad "--ignore-missing should pass"
"$FB" compare a.exr missing.exr > /dev/null 2>&1; [ $? -eq 2 ] && ok || bad "a missing file should exit 2"
"$FB" compare a.exr > /dev/null 2>&1; [ $? -eq 2 ] && ok || bad "one file should exit 2"
"$FB" compare a.exr b.exr --max-abs nan > /dev/null 2>&1; [ $? -eq 2 ] && ok || bad "--max-abs nan should exit 2"
"$FB" fbm --size 97x64 --quiet -o w.exr
"$FB" compare a.exr w.exr > cmp.txt; [ $? -eq 1 ] && grep -q "size differs" cmp.txt && ok || bad "size mismatch not reported"

# a perturbed pixel, written by the test itself through a scene with a different seed in one spot
# is not possible, so perturb the file: flip one float in an uncompressed file and find it by name
"$FB" fbm --size 40x30 --compression none --quiet -o p0.exr
cp p0.exr p1.exr
size=$(stat -c %s p1.exr)
# the last 4 bytes are the last pixel of the last row (uncompressed, one channel)
printf '\x00\x00\x80\x7f' | dd of=p1.exr bs=1 seek=$((size - 4)) conv=notrunc status=none # +Inf
"$FB" compare p0.exr p1.exr --max-abs 0.5 > cmp.txt; [ $? -eq 1 ] && ok || bad "a perturbed pixel passed"
grep -q "non-finite pixels: 1 differ" cmp.txt && ok || bad "the non-finite pixel is not reported: $(cat cmp.txt)"
printf '\x00\x00\x20\x41' | dd of=p1.exr bs=1 seek=$((size - 4)) conv=notrunc status=none # 10.0
"$FB" compare p0.exr p1.exr --max-abs 0.5 > cmp.txt; [ $? -eq 1 ] && ok || bad "a perturbed pixel passed"
grep -q "at pixel (39, 29)" cmp.txt && ok || bad "the perturbed pixel is not named: $(cat cmp.txt)"

# all-zero images: the diff of a file with itself
"$FB" compare a.exr a.exr --diff z.exr > /dev/null && ok || bad "self-compare with --diff failed"
"$FB" compare z.exr z.exr > cmp.txt && ok || bad "all-zero images do not compare equal"
grep -q "all-zero" cmp.txt && ok || bad "all-zero image not reported: $(cat cmp.txt)"

# ---- no Vulkan device: fall back with one line, unless vulkan was asked for ----
VK_ICD_FILENAMES=/nonexistent.json "$FB" fbm --size 32x32 -o nv.exr 2> nv.txt && [ -s nv.exr ] && ok || bad "no fallback to native"
[ "$(grep -c 'no Vulkan device available: using the native backend' nv.txt)" -eq 1 ] && ok || bad "fallback not announced: $(cat nv.txt)"
FB_VK_VALIDATION=0 VK_ICD_FILENAMES=/nonexistent.json expect_fail 3 "vulkan" nv2.exr -- fbm --size 32x32 --backend vulkan -o nv2.exr
"$FB" compare nv.exr nv.exr > /dev/null && ok || bad "fallback file unreadable"

# ---- bounded memory: resident size does not grow with the image (streamed in strips) ----
# (under AddressSanitizer its quarantine keeps freed buffers resident; measure without it)
rss() { ASAN_OPTIONS="${ASAN_OPTIONS:-}:quarantine_size_mb=0" /usr/bin/time -f %M "$FB" fbm --size "$1" --compression none --quiet -o m.exr 2>&1 >/dev/null | tail -1; }
if [ -x /usr/bin/time ]; then
  small=$(rss 4096x256)
  large=$(rss 4096x8192) # 32 times the pixels (128 MiB of floats)
  # kilobytes; allow 64 MiB of growth for driver caches and the writer's queue, far below 128 MiB
  [ "$large" -lt $((small + 65536)) ] && ok || bad "resident memory grows with the image: $small KiB -> $large KiB"
  rm -f m.exr
fi

# ---- terrain ----
Tr="terrain --size 64x64 --quiet"
awk 'BEGIN { srand(4); print "# survey"; print "x,y,z"; for (i = 0; i < 300; i++) { x = rand() * 100; y = rand() * 100; printf "%.4f,%.4f,%.4f\n", x, y, 10 * sin(x / 9) + y / 10 } }' > pts.csv
printf '0 0 1\n1 0 2\n2 0 nan\n' > nanpts.xyz
printf '0 0 1\n1 0 2\n2 0\n' > short.xyz
printf '0 0 1\n1 1 2\n2 2 3\n3 3 4\n' > line.xyz
printf '# nothing here\n' > empty.xyz
printf '1,1,3.4,1\n' > badcenters.csv
printf '1 1 1\n1 1 1\n1 1 1\n' > same.xyz
expect_fail 2 "nanpts.xyz:3: coordinate is not a finite number" o.exr -- $Tr --points nanpts.xyz -o o.exr
expect_fail 2 "short.xyz:3: expected three numbers" o.exr -- $Tr --points short.xyz -o o.exr
expect_fail 2 "empty.xyz: no points" o.exr -- $Tr --points empty.xyz -o o.exr
expect_fail 2 "all points are collinear" o.exr -- $Tr --points line.xyz -o o.exr
expect_fail 2 "fewer than three distinct points" o.exr -- $Tr --points same.xyz -o o.exr
expect_fail 2 "nofile.xyz: cannot open points" o.exr -- $Tr --points nofile.xyz -o o.exr
expect_fail 2 "badcenters.csv:1: fractal dimension D = 3.4 is outside (2, 3)" o.exr -- $Tr --points pts.csv --centers badcenters.csv -o o.exr
expect_fail 2 "dimension" o.exr -- $Tr --points pts.csv --dimension 3 -o o.exr
expect_fail 2 "hurst" o.exr -- $Tr --points pts.csv --hurst 1 -o o.exr
expect_fail 2 "not both" o.exr -- $Tr --points pts.csv --hurst 0.5 --dimension 2.5 -o o.exr
expect_fail 2 "give the survey points" o.exr -- $Tr -o o.exr
expect_fail 2 "sample is the step of from-heightfield" o.exr -- $Tr --points pts.csv --sample 4 -o o.exr
expect_fail 2 "insert" o.exr -- $Tr --points pts.csv --insert 1000000000 -o o.exr
expect_fail 2 "mesh format comes from the extension" o.exr -- $Tr --points pts.csv --mesh m.stl -o o.exr
expect_fail 2 "drop hurst" o.exr -- $Tr --points pts.csv --centers badcenters.csv --hurst 0.7 -o o.exr
printf '0 0 5\n1 0 5\n0 1 5\n' > flat.xyz
expect_fail 2 "give sigma" o.exr -- $Tr --points flat.xyz -o o.exr
expect_fail 2 "nodir/m.ply: cannot create the mesh" o.exr -- $Tr --points pts.csv --mesh nodir/m.ply -o o.exr
[ ! -e nodir/m.ply ] && ok || bad "a mesh was left behind"
expect_fail 2 "nodir/o.exr: cannot create the output" tm.ply -- $Tr --points pts.csv --mesh tm.ply -o nodir/o.exr
if "$FB" terrain --size 64x64 --points pts.csv --insert 5000 --mesh tm.ply -o tr.exr --preview tr.png --json > tr.json 2> err.txt; then ok; else bad "terrain failed: $(cat err.txt)"; fi
valid_exr tr.exr
grep -q '"input_points": 300, "duplicates": 0, "inserted": 5000' tr.json && ok || bad "terrain --json summary: $(cat tr.json)"
"$FB" info tr.exr | grep -q "layer terrain .*Y (float)" && ok || bad "terrain layer channels"
# the PLY: header counts match the summary, and the size is exact (24 bytes a vertex, 13 a face)
nv=$(grep -a -m1 "element vertex" tm.ply | awk '{print $3}')
nf=$(grep -a -m1 "element face" tm.ply | awk '{print $3}')
hdr=$(grep -a -b -m1 "end_header" tm.ply | cut -d: -f1)
[ "$nv" = 5300 ] && ok || bad "PLY vertices $nv, wanted 5300"
[ "$(stat -c %s tm.ply)" = $((hdr + 11 + 24 * nv + 13 * nf)) ] && ok || bad "PLY size does not match its header"
grep -q "\"triangles\": $nf" tr.json && ok || bad "PLY faces $nf differ from the summary"
# determinism: threads, strip rows, backend; the seed changes the terrain
"$FB" $Tr --points pts.csv --insert 5000 --backend native --threads 1 --strip-rows 3 -o tn1.exr
"$FB" $Tr --points pts.csv --insert 5000 --backend native --threads 2 --strip-rows 64 -o tn2.exr
"$FB" $Tr --points pts.csv --insert 5000 -o tv1.exr
cmp -s tn1.exr tn2.exr && ok || bad "terrain depends on threads or strip rows"
"$FB" compare tn1.exr tv1.exr --max-abs 0 > /dev/null && ok || bad "terrain differs between backends"
"$FB" $Tr --points pts.csv --insert 5000 --seed 2 -o ts2.exr
"$FB" compare tn1.exr ts2.exr > /dev/null; [ $? -eq 1 ] && ok || bad "terrain ignores the seed"
# every refinement flag changes the terrain
for f in "--order sweep" "--variance local" "--hurst 0.5" "--dimension 2.5" "--sigma 3" "--insert 4000" "--bounds 10,90,10,90"; do
  "$FB" $Tr --points pts.csv --insert 5000 $f -o tf.exr
  "$FB" compare tn1.exr tf.exr > /dev/null; [ $? -eq 1 ] && ok || bad "terrain $f changed nothing"
done
# a height field sampled back: the refined terrain of a sampled fbm
"$FB" fbm --size 65x65 --quiet --float -o hf.exr
if "$FB" $Tr --from-heightfield hf.exr --sample 8 --insert 2000 --sigma 0.01 --mesh hf.obj -o th.exr; then ok; else bad "from-heightfield failed"; fi
[ "$(grep -c '^v ' hf.obj)" = $((81 + 2000)) ] && ok || bad "height field sampled at step 8 of 65 should give 81 points"
expect_fail 2 "no channel fbm.X" o.exr -- $Tr --from-heightfield hf.exr:fbm.X -o o.exr
# centres: regions of their own D
printf 'x,y,D,sigma\n25,50,2.1,\n75,50,2.7,0.5\n' > centers.csv
"$FB" $Tr --points pts.csv --centers centers.csv --insert 3000 -o tc.exr && ok || bad "terrain with centres failed"
"$FB" terrain --help | grep -q -- "--from-heightfield" && ok || bad "terrain --help lists no --from-heightfield"

# ---- scenes: the default showcase, previews, --set, --from, --region and merge ----
png_wh() { printf '%d %d' "0x$(od -An -tx1 -j16 -N4 "$1" | tr -d ' ')" "0x$(od -An -tx1 -j20 -N4 "$1" | tr -d ' ')"; }
if "$FB" render -o def.exr --preview def.png --quiet 2> err.txt; then ok; else bad "the default scene failed: $(cat err.txt)"; fi
"$FB" info def.exr > def.txt
grep -q "size: *1024 x 512" def.txt && ok || bad "the default scene is not 1024 x 512"
grep -q "layer sky .*B (half), G (half), R (half)" def.txt && ok || bad "default scene: no sky colour: $(cat def.txt)"
grep -q "layer terrain .*Y (float)" def.txt && ok || bad "default scene: no terrain.Y"
grep -q "layer plants .*A (half)" def.txt && ok || bad "default scene: no plants.A"
[ "$(png_wh def.png)" = "1024 512" ] && [ "$(od -An -tu1 -j25 -N1 def.png | tr -d ' ')" = "2" ] && ok || bad "the default preview is not a 1024 x 512 RGB PNG"
# the over composite differs from the sky alone; a layer by name; an unknown layer is refused
S3="--set size=128x64 --set layers.plants.points=200000 --set layers.terrain.insert=2000 --quiet"
"$FB" render $S3 -o c.exr --preview over.png && "$FB" render $S3 -o c2.exr --preview sky.png --preview-layer sky && ok || bad "previews failed"
cmp -s over.png sky.png && bad "the over composite equals the sky alone" || ok
"$FB" render $S3 -o c3.exr --preview ter.png --preview-layer terrain && [ "$(od -An -tu1 -j25 -N1 ter.png | tr -d ' ')" = "0" ] && ok || bad "the terrain preview is not a grey hillshade"
expect_fail 2 'no layer named "moon" (layers: sky, terrain, plants' o.exr -- render $S3 -o o.exr --preview o.png --preview-layer moon
[ -e o.png ] && bad "a failed preview left o.png" || ok
# --set: overrides reach the stored scene and the pixels; bad overrides name the --set
"$FB" render $S3 --set seed=9 --set layers.sky.c=-0.7,0.27 -o set.exr && ok || bad "--set failed"
"$FB" info set.exr | tr -d ' \n' | grep -q '"c":\[-0.69999999999999996,0.27000000000000002\]' && ok || bad "--set c not stored"
"$FB" info set.exr | grep -q '"seed": 9' && ok || bad "--set seed not stored"
"$FB" compare c.exr set.exr --layer sky > /dev/null; [ $? -eq 1 ] && ok || bad "--set c changed no pixel"
expect_fail 2 "\-\-set layers.sky.foo=1: unknown key for a julia layer" o.exr -- render $S3 --set layers.sky.foo=1 -o o.exr
expect_fail 2 '\-\-set layers.moon.c=1: no element named "moon"' o.exr -- render $S3 --set layers.moon.c=1 -o o.exr
expect_fail 2 "\-\-set layers.sky.c=1: expected \[x, y\]" o.exr -- render $S3 --set layers.sky.c=1 -o o.exr
expect_fail 2 "\-\-set layers.7.c=1: index 7 is out of range" o.exr -- render $S3 --set layers.7.c=1 -o o.exr
expect_fail 2 "\-\-set seed: expected KEY.PATH=VALUE" o.exr -- render $S3 --set seed -o o.exr
# --from: the same file, byte for byte (same backend); with an override, another
if "$FB" render --from set.exr -o from.exr --quiet; then ok; else bad "--from failed"; fi
cmp -s set.exr from.exr && ok || bad "--from did not reproduce the file byte for byte"
"$FB" render --from set.exr --set layers.sky.max-iter=50 -o from2.exr --quiet && ! cmp -s set.exr from2.exr && ok || bad "--from with --set changed nothing"
printf 'not an exr' > junk.exr
expect_fail 2 "not a readable OpenEXR" o.exr -- render --from junk.exr -o o.exr
expect_fail 2 "either a scene file or --from" o.exr -- render mixed.json --from set.exr -o o.exr
# --region and merge: the parts, merged, are the whole bake byte for byte, whatever the strips and backend
for be in vulkan native; do
  "$FB" render $S3 --backend $be -o whole_$be.exr --strip-rows 7 || bad "whole bake ($be) failed"
  "$FB" render $S3 --backend $be -o pa_$be.exr --region 0,0,128,21 --strip-rows 5 &&
    "$FB" render $S3 --backend $be -o pb_$be.exr --region 0,21,50,43 &&
    "$FB" render $S3 --backend $be -o pc_$be.exr --region 50,21,78,43 --strip-rows 64 && ok || bad "region bakes ($be) failed"
  "$FB" merge pc_$be.exr pa_$be.exr pb_$be.exr -o merged_$be.exr --quiet && ok || bad "merge ($be) failed"
  cmp -s whole_$be.exr merged_$be.exr && ok || bad "merged regions ($be) differ from the whole bake"
  valid_exr pb_$be.exr
done
"$FB" info pb_vulkan.exr | grep -q "the region 0,21,50,43 of a 128 x 64 image" && ok || bad "info does not show the region"
"$FB" merge pc_vulkan.exr pa_vulkan.exr pb_vulkan.exr -o merged_t1.exr --threads 1 --quiet && cmp -s merged_vulkan.exr merged_t1.exr && ok || bad "merge --threads 1 differs"
"$FB" compare c.exr set.exr --max-abs 0.01 --diff-png cd.png > /dev/null; [ $? -eq 1 ] && [ "$(od -An -tu1 -j25 -N1 cd.png | tr -d ' ')" = "2" ] && [ "$(png_wh cd.png)" = "128 64" ] && ok || bad "compare --diff-png wrote no RGB picture"
"$FB" compare pb_vulkan.exr pc_vulkan.exr > /dev/null; [ $? -eq 1 ] && ok || bad "compare of two regions passed"
"$FB" render --from pb_vulkan.exr -o pb2.exr --quiet && cmp -s pb_vulkan.exr pb2.exr && ok || bad "--from a region file did not reproduce it"
expect_fail 2 "a region is missing" o.exr -- merge pa_vulkan.exr pb_vulkan.exr -o o.exr
expect_fail 2 "overlap" o.exr -- merge pa_vulkan.exr pb_vulkan.exr pc_vulkan.exr pb_vulkan.exr -o o.exr
expect_fail 2 "another scene" o.exr -- merge pa_vulkan.exr pb_vulkan.exr set.exr -o o.exr
expect_fail 2 "not inside the 128 x 64 image" o.exr -- render $S3 --region 100,0,29,64 -o o.exr
expect_fail 2 "region: expected X,Y,W,H" o.exr -- render $S3 --region 1,2,3 -o o.exr

# one EXR part per layer, each with its own compression: the same pixels as one part; regions merge
MP="--set parts=per-layer --set layers.sky.compression=piz --set layers.terrain.compression=none"
"$FB" render $S3 $MP -o mp.exr && ok || bad "multi-part bake failed"
"$FB" info mp.exr > mp.txt
grep -q "parts: *3" mp.txt && grep -q "part 0  sky *compression piz" mp.txt && grep -q "part 1  terrain *compression none" mp.txt && grep -q "part 2  plants *compression zip" mp.txt && ok || bad "multi-part structure: $(cat mp.txt)"
exrinfo --strict mp.exr > /dev/null 2>&1 && ok || bad "the multi-part file fails exrinfo --strict"
rm -rf sep && mkdir sep && exrmultipart -separate -i mp.exr -o sep/p > /dev/null 2>&1 && [ -e sep/p.3.exr ] && ok || bad "exrmultipart cannot separate the parts"
"$FB" compare c.exr mp.exr > /dev/null && ok || bad "multi-part pixels differ from the single-part bake"
"$FB" render $S3 $MP --region 0,0,128,30 -o mpa.exr && "$FB" render $S3 $MP --region 0,30,128,34 -o mpb.exr && "$FB" merge mpa.exr mpb.exr -o mpm.exr --quiet && cmp -s mp.exr mpm.exr && ok || bad "multi-part regions do not merge to the whole file"
"$FB" render --from mp.exr -o mp2.exr --quiet && cmp -s mp.exr mp2.exr && ok || bad "--from a multi-part file did not reproduce it"
expect_fail 2 "its EXR parts differ" o.exr -- merge mpa.exr pb_vulkan.exr -o o.exr
expect_fail 2 'set layers.sky.compression=piz: a compression per layer needs "parts": "per-layer"' o.exr -- render $S3 --set layers.sky.compression=piz -o o.exr
"$FB" fbm $S --compression piz -o fpiz.exr && "$FB" info fpiz.exr | grep -q "compression: piz" && ok || bad "fbm --compression piz"

# a bake split by chaos-game points: three parts' hits add up to the whole game, byte for byte
printf '{"size": [120, 72], "seed": 4, "layers": [{"type": "fbm", "name": "ground", "octaves": 5, "warp": 0.5},
 {"type": "ifs", "name": "fern", "preset": "fern", "points": 2000000, "oversample": 2},
 {"type": "ifs", "name": "pop", "preset": "population", "points": 600000, "half": false}]}' > pp.json
for be in vulkan native; do
  "$FB" render pp.json --backend $be -o ppw_$be.exr --quiet
  for k in 1 2 3; do "$FB" render pp.json --backend $be --points-part $k/3 -o pp${k}_$be.exr --quiet || bad "points part $k ($be) failed"; done
  "$FB" merge pp2_$be.exr pp3_$be.exr pp1_$be.exr -o ppm_$be.exr --quiet && cmp -s ppw_$be.exr ppm_$be.exr && ok || bad "points parts ($be) do not merge to the whole bake"
  "$FB" compare ppw_$be.exr pp2_$be.exr --layer fern > /dev/null; [ $? -eq 1 ] && ok || bad "a points part ($be) holds the whole game"
done
# the backends give the same bits here, so parts from both merge to the same file
"$FB" merge pp1_vulkan.exr pp2_native.exr pp3_vulkan.exr -o ppx.exr --quiet && "$FB" compare ppw_vulkan.exr ppx.exr > /dev/null && ok || bad "parts from two backends do not merge"
"$FB" info pp1_vulkan.exr | grep -q "fractalbake/points-part string *1/3" && ok || bad "the part is not recorded"
"$FB" render --from pp2_vulkan.exr -o pp2b.exr --quiet && cmp -s pp2_vulkan.exr pp2b.exr && ok || bad "--from a points part did not reproduce it"
expect_fail 2 "points part 2/3 is missing" o.exr -- merge pp1_vulkan.exr pp3_vulkan.exr -o o.exr
expect_fail 2 "points part 1/3 is given twice" o.exr -- merge pp1_vulkan.exr pp1_vulkan.exr pp3_vulkan.exr -o o.exr
expect_fail 2 "merge one kind at a time" o.exr -- merge pp1_vulkan.exr pa_vulkan.exr -o o.exr
expect_fail 2 "no chaos-game (ifs) layer" o.exr -- render mixed.json --points-part 1/2 -o o.exr
expect_fail 2 "not with --region" o.exr -- render pp.json --points-part 1/2 --region 0,0,10,10 -o o.exr
expect_fail 2 "points-part: expected K/N" o.exr -- render pp.json --points-part 3/2 -o o.exr

# op layers: fBm detail on a refined terrain, plants masked by height; a cycle names both layers
printf '{"size": [96, 48], "layers": [{"type": "op", "name": "ground", "op": "add", "inputs": ["terrain.Y", "detail"], "weights": [1, 4]},
 {"type": "terrain", "points": [[0,0,0],[10,0,1],[0,5,2],[10,5,4],[5,2.5,9]], "insert": 500},
 {"type": "fbm", "name": "detail", "octaves": 4},
 {"type": "op", "name": "high", "op": "threshold", "inputs": ["ground"], "level": 3, "width": 1},
 {"type": "ifs", "points": 100000},
 {"type": "op", "name": "lowplants", "op": "mix", "inputs": ["plants.A", 0], "mask": "high"}]}' > ops.json
"$FB" render ops.json -o ops.exr --preview ops.png --quiet && ok || bad "op scene failed"
"$FB" info ops.exr | grep -q "layer lowplants *Y (float)" && ok || bad "op layer missing from the file"
"$FB" render ops.json -o ops_n.exr --backend native --quiet && "$FB" compare ops.exr ops_n.exr --layer lowplants > /dev/null && ok || bad "op layer differs between backends"
printf '{"layers": [{"type": "fbm"}, {"type": "op", "name": "a", "op": "add", "inputs": ["fbm", "b"]},\n {"type": "op", "name": "b", "op": "add", "inputs": ["a", 1]}]}' > cyc.json
expect_fail 2 'cyc.json:2: layers\[2\]: layer "b" uses layer "a", which depends on "b": a cycle' o.exr -- render cyc.json -o o.exr
printf '{"layers": [{"type": "fbm"}, {"type": "op", "op": "add", "inputs": ["fbm", "sky.R"]}]}' > miss.json
expect_fail 2 'no layer is named "sky"' o.exr -- render miss.json -o o.exr

# the Slurm job-array example of docs/scenes.md, run as three array tasks, merges to the whole bake
slurm=$HERE/../docs/examples/slurm-bake.sh
for t in 0 1 2; do
  PATH=$(dirname "$FB"):$PATH SLURM_ARRAY_TASK_ID=$t SLURM_ARRAY_TASK_COUNT=3 bash "$slurm" ops.json 96x48 bands/ops || bad "slurm task $t failed"
done
"$FB" render ops.json -o ops_w.exr --set size=96x48 --quiet
"$FB" merge bands/ops.part*.exr -o ops_m.exr --quiet && cmp -s ops_w.exr ops_m.exr && ok || bad "the Slurm example's bands do not merge to the whole bake"

# mismatched sizes: region files of two different images do not merge
"$FB" render $S3 --set size=128x32 --region 0,0,128,32 -o small.exr && ok || bad "small region failed"
expect_fail 2 "a region of a 128 x 32 image, but pa_vulkan.exr is of a 128 x 64 image" o.exr -- merge pa_vulkan.exr small.exr -o o.exr

# bounded memory: the bake streams strips to the file, so peak RSS does not grow with the image.
# 16384^2 has 4x the pixels of 8192^2 (384 MiB more half data): RSS may grow by < 64 MiB (the
# writer's queue grows with the width), and stays under 512 MiB, the size of the image held whole
# (an AddressSanitizer build adds ~300 MiB of its own, the same at both sizes).
for n in 8192 16384; do # /usr/bin/time: Debian's `time` package (scripts/setup.sh)
  /usr/bin/time -f "%M" -o rss_$n.txt "$FB" fbm --size ${n}x${n} --octaves 2 --half --compression none --backend native -o big.exr --quiet || bad "the ${n}^2 bake failed"
  rm -f big.exr
done
k1=$(tail -1 rss_8192.txt) k2=$(tail -1 rss_16384.txt)
[ "$k2" -lt 524288 ] && [ $((k2 - k1)) -lt 65536 ] && ok || bad "peak RSS $k1 KiB at 8192^2, $k2 KiB at 16384^2: not bounded"

# ---- constrain: the FBM constraint model ----
C="constrain --size 120x80 --quiet"
printf '10,10\n60,40\n119,79\n' > cpts.csv
printf 'x,y,kind,value\n30,30,H,0.95\n90,50,T,0.05\n' > cregs.csv
if "$FB" $C --points cpts.csv --regions cregs.csv --water 5 -o con.exr --preview con.png 2> err.txt; then ok; else bad "constrain failed: $(cat err.txt)"; fi
"$FB" info con.exr | grep -q "layer terrain .*A (half), H (float), T (float), Y (float), detail (float), macro (float)" && ok || bad "constrain channels: $("$FB" info con.exr | grep layer)"
"$FB" $C --points cpts.csv --regions cregs.csv --water 5 --backend native -o con_n.exr && "$FB" compare con.exr con_n.exr > /dev/null && ok || bad "constrain differs between backends"
"$FB" $C --points cpts.csv --regions cregs.csv --water 5 --threads 1 --backend native -o con_1.exr && "$FB" compare con.exr con_1.exr > /dev/null && ok || bad "constrain depends on the thread count"
"$FB" $C --T 0.05 -o con_t.exr && "$FB" compare con.exr con_t.exr --layer terrain > /dev/null; [ $? -eq 1 ] && ok || bad "--T changed nothing"
# every model key reaches the computation: each one changes the result
"$FB" $C --points cpts.csv --regions cregs.csv -o cbase.exr
for f in "--macro cone" "--macro-height 5" "--hurst 0.6" "--sigma 2" "--delta 0.5" "--buffering naive" "--domain 2" "--falloff 0.5" "--seed 9"; do
  "$FB" $C --points cpts.csv --regions cregs.csv $f -o cf.exr
  "$FB" compare cbase.exr cf.exr > /dev/null; [ $? -eq 1 ] && ok || bad "constrain $f changed nothing"
done
# 1D: a CSV profile in, x,d,D out; the constraint rows have D == d
printf 'x,d\n0,0\n50,10\n100,0\n' > prof.csv
"$FB" constrain --size 256x1 --profile prof.csv --points <(printf '128,0\n40,0\n') --csv out1d.csv -o p1d.exr --quiet && ok || bad "1D constrain failed"
[ "$(wc -l < out1d.csv)" = 257 ] && head -1 out1d.csv | grep -q "^x,d,D$" && ok || bad "1D CSV: $(head -2 out1d.csv)"
awk -F, '$1 == 128 || $1 == 40 {if ($2 != $3) bad = 1} END {exit bad}' out1d.csv && ok || bad "1D constraints not exact in the CSV"
"$FB" constrain --size 256x1 --profile prof.csv --points <(printf '128,0\n') --plot p1d.png -o p1d2.exr --quiet &&
  [ "$(od -An -tu1 -j25 -N1 p1d.png | tr -d ' ')" = "2" ] && [ "$(png_wh p1d.png)" = "256 240" ] && ok || bad "1D plot is not a 256 x 240 RGB PNG"
# a macro shape from an EXR channel, and its size must match
"$FB" fbm --size 120x80 --quiet --octaves 3 -o macro.exr
"$FB" $C --macro macro.exr:fbm.Y -o cm.exr && ok || bad "macro from an EXR failed"
expect_fail 2 "macro.exr: 120 x 80, but the scene is 64 x 64" o.exr -- constrain --size 64x64 --macro macro.exr -o o.exr
expect_fail 2 "cpts.csv:3: the pixel is outside the image" o.exr -- constrain --size 100x50 --points cpts.csv -o o.exr
expect_fail 2 "H must be in (0, 1)" o.exr -- constrain --size 120x80 --regions <(printf '1,1,H,1.5\n') -o o.exr
printf '1,2\n3\n' > bad.csv
printf '{"size": [64, 64], "layers": [{"type": "constrain", "points": [[3, 4], [64, 2]]}]}' > cbad.json
expect_fail 2 'cbad.json:1: layers\[0\].points\[1\]: pixel (64, 2) is outside the 64 x 64 image' o.exr -- render cbad.json -o o.exr
"$FB" constrain --help | grep -c -- "--compression" | grep -q "^1$" && ok || bad "constrain --help lists --compression twice"
# the macro shape from another layer of the scene (listed after it) equals the same layer baked to an EXR first
printf '{"size": [96, 64], "seed": 2, "layers": [{"type": "constrain", "name": "shaped", "macro": "terrain", "T": 0.5, "points": [[10, 10], [50, 30]]},
 {"type": "terrain", "points": [[0,0,0],[10,0,3],[0,5,6],[10,5,2],[5,2.5,9]], "insert": 800}]}' > mac.json
"$FB" render mac.json -o mac.exr --quiet && ok || bad "macro from a layer failed"
printf '0 0 0\n10 0 3\n0 5 6\n10 5 2\n5 2.5 9\n' > mac.xyz
"$FB" terrain --size 96x64 --seed 2 --points mac.xyz --insert 800 -o mact.exr --quiet
"$FB" constrain --size 96x64 --seed 2 --layer shaped --macro mact.exr:terrain.Y --T 0.5 --points <(printf '10,10\n50,30\n') -o macc.exr --quiet
"$FB" compare macc.exr mac.exr --layer shaped > /dev/null && ok || bad "a macro from a layer differs from the same layer's EXR"
printf '{"layers": [{"type": "constrain", "macro": "m"}, {"type": "op", "name": "m", "op": "add", "inputs": ["terrain", 1]}]}' > mcyc.json
expect_fail 2 'layer "m" uses layer "terrain", which depends on "m": a cycle' o.exr -- render mcyc.json -o o.exr
printf '{"layers": [{"type": "constrain", "macro": "hill.Y"}]}' > mmiss.json
expect_fail 2 'layers\[0\].macro: "hill.Y" is not cone' o.exr -- render mmiss.json -o o.exr
printf '{"size": [32, 32], "layers": [{"type": "constrain", "macro": "sky.iter"}, {"type": "julia"}]}' > mint.json
expect_fail 2 'a channel of integers' o.exr -- render mint.json -o o.exr

# ---- device selection (where a Vulkan device exists) ----
if "$FB" devices | grep -q '^0 '; then
  "$FB" fbm $S --backend vulkan --device 0 -o d0.exr && ok || bad "--device 0 failed"
  first=$("$FB" devices | awk 'NR == 2 {print $3}')
  "$FB" fbm $S --backend vulkan --device "$first" -o d1.exr && ok || bad "--device $first (a name) failed"
  "$FB" info d1.exr | grep -q "fractalbake/device .*$first" && ok || bad "device not stored in the file"
  expect_fail 2 "out of range" d2.exr -- fbm $S --backend vulkan --device 99 -o d2.exr
fi

# ---- the other commands ----
"$FB" devices > dev.txt && ok || bad "devices failed"
grep -q -E "\*|no Vulkan device" dev.txt && ok || bad "devices marks no chosen device"
"$FB" --version | grep -q "fractalbake 0" && ok || bad "--version"
"$FB" fbm --help | grep -q -- "--octaves" && ok || bad "fbm --help lists no --octaves"
# the terrain benchmark's JSON lines (rates are measured, not asserted: only their form and sign)
"$FB" bench --generator terrain --json > bt.json && ok || bad "bench --generator terrain failed"
grep -q '"generator": "delaunay", "backend": "native".*"unit": "Minserts/s", "rate": [0-9]*\.[0-9]*[1-9]' bt.json && ok || bad "bench: no delaunay line: $(cat bt.json)"
grep -q '"generator": "refine", "backend": "native".*"unit": "Minserts/s", "rate": [0-9]*\.[0-9]*[1-9]' bt.json && ok || bad "bench: no refine line: $(cat bt.json)"
"$FB" bench --generator constrain --size 256x256 --json > bc.json && grep -q '"generator": "constrain", "backend": "native".*"unit": "Mpix/s", "rate": [0-9]*\.[0-9]*[1-9]' bc.json && ok || bad "bench: no constrain line: $(cat bc.json)"

echo "$pass passed, $fail failed"
[ $fail -eq 0 ]
