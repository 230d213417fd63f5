#!/usr/bin/env bash
# A bake and its file: previews, info, compressions, mixed scenes, determinism, atomic replacement,
# compare, the native fallback, bounded memory.
# Needs a Vulkan device (lavapipe at least): it compares backends. Usage: bake.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
require_vulkan
S="--size 96x64 --quiet"

# ---- bad input: flags ----
expect_fail 2 "nodir/o.exr: cannot create the output: folder" "$T/nodir/o.exr" -- fbm $S -o "$T/nodir/o.exr"

# ---- a bake, the file, info ----
if "$FB" fbm $S --seed 5 --octaves 6 -o a.exr --preview a.png 2> err.txt; then ok; else bad "fbm bake failed: $(cat err.txt)"; fi
[ -s err.txt ] && bad "a clean bake wrote to stderr: $(cat err.txt)" || ok
valid_exr a.exr
if head -c 8 a.png | od -An -c | grep -q 'P   N   G'; then ok; else bad "preview is not a PNG"; fi
"$FB" info a.exr > info.txt
grep -q 'layer fbm .*Y (float)' info.txt && ok || bad "info lacks the fbm layer: $(cat info.txt)"
grep -q '"octaves": 6' info.txt && ok || bad "info lacks the stored scene"
grep -q '"seed": 5' info.txt && ok || bad "stored scene lacks the seed"
grep -q '^  dataWindow  *box2i  *0,0,' info.txt && ok || bad "info does not print attribute values: $(grep dataWindow info.txt)"
grep -q '^  fractalbake/seed  *string  *5$' info.txt && ok || bad "info does not print the seed attribute's value"
"$FB" info a.exr --json > info.json
python3 -c "
import json; r = json.load(open('info.json'))
assert r['layers'][0]['layer'] == 'fbm' and r['layers'][0]['channels'][0]['type'] == 'float', r['layers']
assert r['attributes']['fractalbake/seed']['value'] == '5' and r['scene']['layers'][0]['octaves'] == 6
assert r['attributes']['compression']['value'] == 'zip'" && ok || bad "info --json: $(cat info.json)"
# the stored scene: compact, numbers in their shortest form that reads back the same
exrheader a.exr | grep -q 'fractalbake/scene (type string): "{"compression":"zip","layers":\[{"billow":false,"frequency":4.0,' && ok ||
  bad "the stored scene is not compact: $(exrheader a.exr | grep -A2 fractalbake/scene | head -3)"
# a foreign multi-part file: each part's channels under its part's full name
if command -v oiiotool > /dev/null; then
  oiiotool --create 16x8 3 -o p1.exr && oiiotool --create 16x8 4 --ch R,G,B,A -o p2.exr &&
    oiiotool p1.exr p2.exr --siappend -o mp.exr
  "$FB" info mp.exr > mp.txt
  grep -q "^  layer subimage00 B (float), G (float), R (float)$" mp.txt && grep -q "^  layer subimage01 A (float)" mp.txt && ok ||
    bad "info of a foreign multi-part file: $(cat mp.txt)"
fi

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
"$FB" compare a.exr c.exr --ignore-missing > cmp.txt; [ $? -eq 1 ] && grep -q "result: FAIL: no channel in common" cmp.txt && ok || bad "--ignore-missing with nothing in common should fail, saying why"
"$FB" compare a.exr missing.exr > /dev/null 2>&1; [ $? -eq 2 ] && ok || bad "a missing file should exit 2"
"$FB" compare a.exr > /dev/null 2>&1; [ $? -eq 2 ] && ok || bad "one file should exit 2"
"$FB" compare a.exr b.exr --max-abs nan > /dev/null 2>&1; [ $? -eq 2 ] && ok || bad "--max-abs nan should exit 2"
"$FB" fbm --size 97x64 --quiet -o w.exr
"$FB" compare a.exr w.exr > cmp.txt; [ $? -eq 1 ] && grep -q "result: FAIL: the sizes differ" cmp.txt && ok || bad "size mismatch not reported"

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

cli_finish
