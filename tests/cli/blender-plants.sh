#!/usr/bin/env bash
# Blender as the client of plant instances (docs/plants.md, "Loading them"): a population of an ifs
# layer stands on a terrain layer; its instances (PLY, Z up) and the terrain's heightmap go into
# Blender through the recipes docs/examples/blender/plants.py and terrain.py, and
# tests/blender/test_plants.py checks the count and places of the points and of their Geometry Nodes
# instances against the population it enumerates itself, and that each plant stands on the terrain
# as Blender displaced it. Not run (77) where blender is not installed.
# Usage: blender-plants.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
require_blender

cat > scene.json << 'EOF2'
{"size": [128, 64], "seed": 5, "layers": [
  {"type": "terrain", "name": "ground", "half": false, "insert": 800, "bounds": [0, 100, 0, 50],
   "points": [[0, 0, 0], [100, 0, 10], [0, 50, 20], [100, 50, 40], [50, 25, 80], [20, 40, 5], [80, 10, 60]],
   "heightmap": "ground.png"},
  {"type": "ifs", "name": "plants", "points": 100000, "bounds": [-0.05, 1.05, -0.05, 1.0],
   "maps": [[0.5, 0, 0, 0.5, 0, 0, 1], [0.5, 0, 0, 0.5, 0.5, 0, 1], [0.5, 0, 0, 0.5, 0.25, 0.45, 1]],
   "condensation": {"preset": "bush", "height": 0.1}, "instances": "plants.ply", "instances-up": "z",
   "instances-surface": "ground", "instances-min-size": 0.5}]}
EOF2
"$FB" render scene.json --quiet -o scene.exr && ok || bad "the scene does not bake"

blender_test plants "$T/plants.ply" "$T/ground.png" "$T/scene.json"
cli_finish
