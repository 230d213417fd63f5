#!/usr/bin/env bash
# Colour is scene-linear Rec. 709 (ITU-R BT.709 primaries, D65 white): a file that holds a colour
# channel says so with OpenEXR's chromaticities attribute, as OpenEXR's exrheader and OpenImageIO read
# it; a file of data channels only (heights, masks, counts) carries none. In a multi-part file the
# attribute is shared (OpenEXR: every part the same value, or the file is not conforming): every part
# has it, and OpenImageIO reads the file.
# Usage: chromaticities.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"

rec709='red   \(0.64 0.33\)|green \(0.3 0.6\)|blue  \(0.15 0.06\)|white \(0.3127 0.329\)'
# one part: the default scene has colour, so its one part says so, with the exact primaries
"$FB" render --set size=64x32 --quiet -o one.exr && ok || bad "the default scene does not bake"
[ "$(exrheader one.exr | grep -cE "^ *($rec709)$")" -eq 4 ] && ok || bad "the single part lacks the Rec. 709 chromaticities"
oiiotool --info -v one.exr | grep -qE 'chromaticities: 0.64, 0.33, 0.3, 0.6, 0.15, 0.06, 0.3127, 0.329' && ok ||
  bad "OpenImageIO does not read the chromaticities: $(oiiotool --info -v one.exr | grep -i chroma)"

# a part per layer: every part carries it (a shared attribute), and the file stays readable
cat > parts.json << 'EOF'
{"size": [64, 32], "parts": "per-layer", "layers": [
  {"type": "fbm", "name": "height", "octaves": 4},
  {"type": "julia", "name": "sky", "channels": ["n", "R", "G", "B"]},
  {"type": "op", "name": "mask", "op": "threshold", "inputs": ["height"], "level": 0, "width": 0.5}]}
EOF
"$FB" render parts.json --quiet -o parts.exr && ok || bad "the per-layer scene does not bake"
[ "$(exrheader parts.exr | grep -cE "^ *($rec709)$")" -eq 12 ] && ok || bad "not every part has the Rec. 709 chromaticities"
oiiotool --info parts.exr 2>&1 | grep -q '(3 subimages)' && ok ||
  bad "OpenImageIO cannot read the three parts: $(oiiotool --info parts.exr 2>&1 | head -2)"

# data only: no chromaticities
"$FB" fbm --size 32x32 --quiet -o data.exr && ! exrheader data.exr | grep -q chromaticities && ok ||
  bad "a file of data channels only has chromaticities"

cli_finish
