#!/usr/bin/env bash
# Skies as environment maps against the plane, in one run: the layers of
# docs/examples/gallery-sky-env.json (warped Julia with turbulence, simplex fBm clouds) baked as
# lat-long and as rect at the same size, alternated, REPS times each; the medians of CPU time
# (user + system, steadier than wall time on a shared machine) and wall time, and their ratio.
# --layer NAME bakes that layer of the scene alone (clouds: the fBm, sky: the Julia with turbulence).
# --against OTHER also bakes everything with a second binary (a build before a change), alternated
# with the first within each repetition, and gives each binary's figures and their ratios.
# With --big, also one 16384 x 8192 lat-long bake under /usr/bin/time -v: its peak resident memory.
#
#   bench/sky.sh PATH/TO/fractalbake [SIZE [REPS [--big]]] [--layer NAME] [--against PATH/TO/fractalbake]
#   (default 2048x1024, 3)
set -euo pipefail
pos=()
big= layer= against=
while [ $# -gt 0 ]; do
  case $1 in
  --big) big=--big ;;
  --layer) layer=$2; shift ;;
  --against) against=$(realpath "$2"); shift ;;
  *) pos+=("$1") ;;
  esac
  shift
done
FB=$(realpath "${pos[0]}")
size=${pos[1]:-2048x1024}
reps=${pos[2]:-3}
root=$(cd "$(dirname "$0")/.." && pwd)
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fb-bench-sky-XXXXXX")
trap 'rm -rf "$tmp"' EXIT
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-$tmp}
scene=$root/docs/examples/gallery-sky-env.json
sets=(--set "layers.sky.mapping=MAP" --set "layers.clouds.mapping=MAP")
if [ -n "$layer" ]; then # the scene with that one layer
  python3 - "$scene" "$layer" "$tmp/scene.json" <<'EOF'
import json, sys
s = json.load(open(sys.argv[1]))
s["layers"] = [l for l in s["layers"] if l["name"] == sys.argv[2]]
if not s["layers"]:
    sys.exit("sky.sh: the scene has no layer " + sys.argv[2])
json.dump(s, open(sys.argv[3], "w"))
EOF
  scene=$tmp/scene.json
  sets=(--set "layers.$layer.mapping=MAP")
fi
one() { # BINARY MAPPING: "cpu wall" seconds of one bake
  /usr/bin/time -f '%U %S %e' -o "$tmp/t" "$1" render "$scene" --set "size=$size" "${sets[@]//MAP/$2}" \
    --backend native -o "$tmp/o.exr" --quiet
  awk '{printf "%.3f %.3f\n", $1 + $2, $3}' "$tmp/t"
}
median() { sort -n | awk '{a[NR] = $1} END {print a[int((NR + 1) / 2)]}'; }
bins=("$FB")
[ -n "$against" ] && bins=("$against" "$FB")
for ((b = 0; b < ${#bins[@]}; b++)); do : > "$tmp/latlong$b"; : > "$tmp/rect$b"; done
for ((i = 0; i < reps; i++)); do
  for ((b = 0; b < ${#bins[@]}; b++)); do
    one "${bins[$b]}" latlong >> "$tmp/latlong$b"
    one "${bins[$b]}" rect >> "$tmp/rect$b"
  done
done
echo "size $size, ${layer:-every layer}, $reps each, native, $(nproc) cores, $(date -u +%Y-%m-%d)"
printf '| binary | mapping | CPU s (median) | wall s (median) |\n|---|---|---|---|\n'
for ((b = 0; b < ${#bins[@]}; b++)); do
  lc[b]=$(cut -d' ' -f1 "$tmp/latlong$b" | median) lw[b]=$(cut -d' ' -f2 "$tmp/latlong$b" | median)
  rc[b]=$(cut -d' ' -f1 "$tmp/rect$b" | median) rw[b]=$(cut -d' ' -f2 "$tmp/rect$b" | median)
  printf '| %s | rect | %s | %s |\n| %s | latlong | %s | %s |\n' "${bins[$b]}" "${rc[b]}" "${rw[b]}" "${bins[$b]}" \
    "${lc[b]}" "${lw[b]}"
done
for ((b = 0; b < ${#bins[@]}; b++)); do
  awk -v n="${bins[$b]}" -v a="${lc[b]}" -v b="${rc[b]}" -v c="${lw[b]}" -v d="${rw[b]}" \
    'BEGIN {printf "%s: latlong / rect: %.2fx CPU, %.2fx wall\n", n, a / b, c / d}'
done
if [ -n "$against" ]; then
  awk -v n="$FB" -v m="$against" -v a="${lc[1]}" -v b="${lc[0]}" -v c="${rc[1]}" -v d="${rc[0]}" \
    'BEGIN {printf "CPU of %s / %s: latlong %.2fx, rect %.2fx\n", n, m, a / b, c / d}'
fi
if [ "$big" = --big ]; then
  /usr/bin/time -v "$FB" render "$scene" --set size=16384x8192 --backend native -o "$tmp/big.exr" --quiet 2> "$tmp/v"
  grep -E 'Maximum resident|Elapsed|User time|System time' "$tmp/v"
fi
