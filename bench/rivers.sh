#!/usr/bin/env bash
# Stream-power erosion beside its peer, in one run: the rivers layer at its defaults (a flat start
# with noise, uniform uplift, open edges, filled depressions, hillslope diffusion) for STEPS steps on
# a SIZE grid (the whole grid: --coarse its width), and bench/peers/rivers_peer.c (the same model
# written plainly, one thread) on the same grid and steps, alternated, REPS times each. The layer's
# time is its model's (the summary's seconds: no EXR written); both in cell-steps per second of wall
# time, each run on its line, with its relief and largest basin (the two compute the same
# landscape), the process's CPU seconds and the load before each (a shared machine's wall time is
# the load's as much as the code's).
#
#   bench/rivers.sh PATH/TO/fractalbake [SIZE [STEPS [REPS]]]    (default 2048x2048 500 1)
set -euo pipefail
FB=$(realpath "$1")
size=${2:-2048x2048}
steps=${3:-500}
reps=${4:-1}
root=$(cd "$(dirname "$0")/.." && pwd)
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fb-bench-rivers-XXXXXX")
trap 'rm -rf "$tmp"' EXIT
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-$tmp}
gcc -O3 -march=native -o "$tmp/rivers_peer" "$root/bench/peers/rivers_peer.c" -lm
cells=$(echo "$size" | awk -Fx '{print $1 * $2}')
echo "machine: $(lscpu | sed -n 's/^Model name: *//p' | head -1), $(nproc) cores; $(date -u +%Y-%m-%d)"
for ((i = 0; i < reps; i++)); do
  echo "load before: $(cut -d' ' -f1-3 /proc/loadavg)"
  /usr/bin/time -f '%U %S' -o "$tmp/t" "$FB" rivers --size "$size" --coarse "${size%%x*}" --steps "$steps" --backend native -o "$tmp/r.exr" \
    --json > "$tmp/s.json" 2> /dev/null
  python3 -c "
import json
s = [l for l in json.load(open('$tmp/s.json'))['layers'] if l['name'] == 'rivers'][0]['summary']
u, k = map(float, open('$tmp/t').read().split())
print('fractalbake rivers %s, %d steps, $(nproc) threads: %.2f Mcell-steps/s (the model %.1f s; the process %.1f CPU s); '
      'relief %.6g, largest basin %.3g%%' % ('$size', s['steps'], $cells * s['steps'] / s['seconds'] * 1e-6, s['seconds'],
      u + k, s['relief'], 100 * s['largest_basin']))"
  echo "load before: $(cut -d' ' -f1-3 /proc/loadavg)"
  /usr/bin/time -f 'the peer process: %U user + %S system CPU s' "$tmp/rivers_peer" --size "$size" --steps "$steps"
done
