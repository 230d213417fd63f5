#!/usr/bin/env bash
# Skies as environment maps against the plane, in one run: the layers of
# docs/examples/gallery-sky-env.json (warped Julia with turbulence, simplex fBm clouds) baked as
# lat-long and as rect at the same size, alternated, REPS times each; the medians of CPU time
# (user + system, steadier than wall time on a shared machine) and wall time, and their ratio.
# With --big, also one 16384 x 8192 lat-long bake under /usr/bin/time -v: its peak resident memory.
#
#   bench/sky.sh PATH/TO/fractalbake [SIZE [REPS [--big]]]     (default 2048x1024, 3)
set -euo pipefail
FB=$(realpath "$1")
size=${2:-2048x1024}
reps=${3:-3}
big=${4:-}
root=$(cd "$(dirname "$0")/.." && pwd)
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fb-bench-sky-XXXXXX")
trap 'rm -rf "$tmp"' EXIT
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-$tmp}
scene=$root/docs/examples/gallery-sky-env.json
one() { # MAPPING: "cpu wall" seconds of one bake
  /usr/bin/time -f '%U %S %e' -o "$tmp/t" "$FB" render "$scene" --set "size=$size" --set "layers.sky.mapping=$1" \
    --set "layers.clouds.mapping=$1" --backend native -o "$tmp/o.exr" --quiet
  awk '{printf "%.3f %.3f\n", $1 + $2, $3}' "$tmp/t"
}
median() { sort -n | awk '{a[NR] = $1} END {print a[int((NR + 1) / 2)]}'; }
: > "$tmp/latlong"
: > "$tmp/rect"
for ((i = 0; i < reps; i++)); do
  one latlong >> "$tmp/latlong"
  one rect >> "$tmp/rect"
done
lc=$(cut -d' ' -f1 "$tmp/latlong" | median) lw=$(cut -d' ' -f2 "$tmp/latlong" | median)
rc=$(cut -d' ' -f1 "$tmp/rect" | median) rw=$(cut -d' ' -f2 "$tmp/rect" | median)
echo "size $size, $reps each, native, $(nproc) cores, $(date -u +%Y-%m-%d)"
printf '| mapping | CPU s (median) | wall s (median) |\n|---|---|---|\n'
printf '| rect | %s | %s |\n| latlong | %s | %s |\n' "$rc" "$rw" "$lc" "$lw"
awk -v a="$lc" -v b="$rc" -v c="$lw" -v d="$rw" 'BEGIN {printf "latlong / rect: %.2fx CPU, %.2fx wall\n", a / b, c / d}'
if [ "$big" = --big ]; then
  /usr/bin/time -v "$FB" render "$scene" --set size=16384x8192 --backend native -o "$tmp/big.exr" --quiet 2> "$tmp/v"
  grep -E 'Maximum resident|Elapsed|User time|System time' "$tmp/v"
fi
