#!/usr/bin/env bash
# Bakes the gallery of docs/gallery.md: each docs/examples/gallery-NAME.json into OUT/gallery-NAME.png
# (its preview; the EXR is not kept). Scene inputs are relative to the repository's root.
#
#   scripts/gallery.sh [--width W] [OUT]    OUT: docs/img (default); --width W: W pixels wide, aspect kept
#
# The CTest entry `gallery` runs it at 320 pixels wide and checks every picture (tests/gallery.py).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
FB=$(realpath "${FB:-$root/build/fractalbake}")
width=0
if [ "${1:-}" = --width ]; then
  width=$2
  shift 2
fi
out=$(realpath -m "${1:-$root/docs/img}")
mkdir -p "$out"
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fb-gallery-XXXXXX")
trap 'rm -rf "$tmp"' EXIT
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-$tmp}
for scene in "$root"/docs/examples/gallery-*.json; do
  name=$(basename "$scene" .json)
  sets=()
  if [ "$width" -gt 0 ]; then
    size=$(cd "$root" && "$FB" scene "$scene" | python3 -c "import json, sys; w, h = json.load(sys.stdin)['size']; print('%dx%d' % ($width, max(1, round(h * $width / w))))")
    sets=(--set "size=$size")
  fi
  (cd "$root" && "$FB" render "$scene" "${sets[@]}" -o "$tmp/$name.exr" --preview "$out/$name.png" --quiet)
  echo "gallery: $out/$name.png"
done
