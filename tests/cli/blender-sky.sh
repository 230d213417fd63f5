#!/usr/bin/env bash
# Blender as the client of a lat-long sky (docs/sky.md, "Blender"): a julia layer whose only bright
# pixels are a spherical cap at a direction computed from the mapping's formula (zenith angle T0 and
# azimuth PSI0 of p = r (d.x + i d.z) / (1 + d.y)) becomes the World of a Blender scene through the
# recipe docs/examples/blender/sky.py; Cycles renders a probe frame, and tests/blender/test_sky.py finds the
# cap within 2 degrees of where OpenEXR's convention, turned into Blender's frame, puts it, and not
# where a mirrored or upside-down sky would. Not run (77) where blender is not installed.
# Usage: blender-sky.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
require_blender

R=10 T0=60 PSI0=15 FOV=40
# the centre -R tan(T0/2) exp(i PSI0), so that z0 = p + centre is inside |z0| <= 1 around (T0, PSI0)
center=$(awk -v r=$R -v t=$T0 -v p=$PSI0 'BEGIN { d = atan2(0, -1) / 180; k = -r * sin(t * d / 2) / cos(t * d / 2)
  printf "%.9f,%.9f", k * cos(p * d), k * sin(p * d) }')
"$FB" julia --mapping latlong --size 1024x512 --c 0,0 --alpha 0,0 --radius $R --center="$center" --max-iter 64 \
  --stops '0,0,0,0;1,0,0,0' --inside-color 20,20,20 --channels R,G,B --quiet -o sky.exr && ok || bad "the sky does not bake"

blender_test sky "$T/sky.exr" $R $T0 $PSI0 $FOV
cli_finish
