#!/usr/bin/env bash
# Regenerates the L-system pictures of docs/plants.md (docs/img/lsys_*.png) from the built binary.
# Usage: scripts/plant-images.sh [PATH/TO/fractalbake]   (default build/fractalbake)
set -euo pipefail
FB=${1:-build/fractalbake}
out=docs/img
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for p in bush tree sticks weed stochastic; do
  "$FB" lsystem --preset "$p" --size 320x320 --width 1 --quiet -o "$tmp/$p.exr" --preview "$out/lsys_$p.png"
done
"$FB" ifs --maps "0.75,0,0,0.75,0.25,0" --condensation lsystem:tree --size 1024x360 \
  --bounds -0.08,1.02,-0.02,0.367 --points 4e7 --quiet -o "$tmp/pop.exr" --preview "$out/lsys_population.png"
