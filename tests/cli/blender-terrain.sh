#!/usr/bin/env bash
# Blender as the client of a heightmap (docs/terrain.md, "Blender"): a terrain of survey points with
# two plateaus at known heights and places writes its 16-bit PNG heightmap; the recipe
# docs/examples/blender/terrain.py displaces a plane by it, and tests/blender/test_terrain.py reads the
# heights back from Blender's mesh: every vertex against the PNG decoded by the test (its first row
# north), the plateaus at their heights where the survey put them and not at their mirror images.
# Not run (77) where blender is not installed.
# Usage: blender-terrain.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
require_blender

cat > survey.txt << 'EOF2'
# corners at 0; a plateau at 40 in the north-east, one at 10 in the south-west
0 0 0
200 0 0
0 100 0
200 100 0
140 60 40
170 60 40
140 90 40
170 90 40
20 10 10
60 10 10
20 40 10
60 40 10
EOF2
"$FB" terrain --points survey.txt --insert 0 --size 256x128 --quiet -o t.exr --heightmap t.png && ok ||
  bad "the terrain does not bake"

blender_test terrain "$T/t.png" 0,200,0,100
cli_finish
