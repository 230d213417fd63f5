#!/usr/bin/env bash
# The pictures of docs/terrain.md's rivers section and the gallery's range: bakes
# docs/examples/gallery-rivers.json (2048 x 2048, some minutes) and writes, with oiiotool,
#   docs/img/gallery-rivers.png   its preview shrunk to 1024 x 1024
#   docs/img/rivers-vs-pipes.png  the pipe model's eroded survey (docs/img/gallery-eroded.png) beside it,
#                                 both shrunk to 360 pixels tall
# Usage: scripts/rivers-images.sh [FRACTALBAKE]   (default build/fractalbake)
set -euo pipefail
cd "$(dirname "$0")/.."
fb=${1:-build/fractalbake}
img=docs/img tmp=$(mktemp -d "${TMPDIR:-/tmp}/fb-rivers-images-XXXXXX")
trap 'rm -rf "$tmp"' EXIT
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-$tmp}
"$fb" render docs/examples/gallery-rivers.json -o "$tmp/rivers.exr" --preview "$tmp/rivers.png" --quiet
oiiotool "$tmp/rivers.png" --resize 1024x1024 -o $img/gallery-rivers.png
# the pipe model's picture (1024 x 820) shrunk to 450 x 360 at the left of a white 818 x 360, the range's at x 458
oiiotool "$tmp/rivers.png" --resize 360x360 $img/gallery-eroded.png --resize 0x360 --create 818x360 3 \
  --fill:color=1,1,1 818x360 --paste +0+0 --paste +458+0 -o $img/rivers-vs-pipes.png
echo "wrote $img/gallery-rivers.png and $img/rivers-vs-pipes.png"
