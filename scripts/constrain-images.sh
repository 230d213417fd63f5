#!/usr/bin/env bash
# Renders the FBM constraint model's examples (docs/examples/constrain-*.json, the paper's) into the
# pictures of docs/constrain.md. Usage: scripts/constrain-images.sh [FRACTALBAKE]
set -euo pipefail
cd "$(dirname "$0")/.."
fb=${1:-build/fractalbake}
ex=docs/examples img=docs/img tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
"$fb" render $ex/constrain-1d.json -o "$tmp/a.exr" --quiet --set layers.0.plot=$img/constrain-1d-h050.png \
  --set layers.0.csv=$ex/constrain-1d.csv
"$fb" render $ex/constrain-1d.json -o "$tmp/b.exr" --quiet --set layers.0.hurst=0.65 \
  --set layers.0.plot=$img/constrain-1d-h065.png
"$fb" render $ex/constrain-2d.json -o "$tmp/c.exr" --quiet --preview $img/constrain-2d.png
"$fb" render $ex/constrain-2d.json -o "$tmp/c2.exr" --quiet --set layers.0.points=[[1,1]] --preview $img/constrain-2d-free.png
"$fb" render $ex/constrain-lake.json -o "$tmp/d.exr" --quiet --preview $img/constrain-lake.png --preview-layer over
"$fb" render $ex/constrain-region.json -o "$tmp/e.exr" --quiet --preview $img/constrain-region.png
"$fb" render $ex/constrain-region.json -o "$tmp/e2.exr" --quiet --set layers.0.soften=0.3 --preview $img/constrain-region-soft.png
"$fb" render $ex/constrain-region.json -o "$tmp/e3.exr" --quiet --set layers.0.interpolation=linear --preview $img/constrain-region-linear.png
"$fb" render $ex/constrain-eroded-boss.json -o "$tmp/f.exr" --quiet --preview $img/constrain-eroded-boss.png
echo "wrote $img/constrain-*.png and $ex/constrain-1d.csv"
