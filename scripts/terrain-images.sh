#!/usr/bin/env bash
# Regenerates the pictures of docs/terrain.md: a synthetic survey of 1000 points (a broad hill on
# rolling ground) refined by 200,000 inserted points, with the stage and the local variance and with
# additions.
set -euo pipefail
cd "$(dirname "$0")/.."
FB=${FB:-build/fractalbake}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
awk 'BEGIN { srand(5); print "x,y,z"; for (i = 0; i < 1000; i++) { x = rand() * 1000; y = rand() * 1000;
  printf "%.3f,%.3f,%.3f\n", x, y, 300 * exp(-((x - 500)^2 + (y - 500)^2) / 80000) + 20 * sin(x / 60) } }' > "$T/survey.csv"
"$FB" terrain --points "$T/survey.csv" --insert 200000 --size 512x512 --quiet -o "$T/s.exr" --preview docs/img/terrain_stage.png
"$FB" terrain --points "$T/survey.csv" --insert 200000 --size 512x512 --quiet --variance local -o "$T/l.exr" --preview docs/img/terrain_local.png
"$FB" terrain --points "$T/survey.csv" --insert 200000 --size 512x512 --quiet --variance additions -o "$T/a.exr" --preview docs/img/terrain_additions.png
# linear against smooth: the survey's 200 points unrefined, a 512 x 410 hillshade, triangles tens of
# pixels across
"$FB" terrain --points docs/examples/survey.csv --insert 0 --size 512x410 --quiet -o "$T/lin.exr" --preview docs/img/terrain_linear.png
"$FB" terrain --points docs/examples/survey.csv --insert 0 --size 512x410 --quiet --interpolation smooth -o "$T/smo.exr" --preview docs/img/terrain_smooth.png
