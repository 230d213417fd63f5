#!/usr/bin/env bash
# Fractal flames beside libflam3 (flam3-render of Debian's flam3-utils), the same genome, the same
# size, quality and thread count, side by side in one run: points per second of the whole render
# (chaos game, density estimation, filter, tone map and writing the file), the median of 3 runs each.
#
#   bench/flame.sh [FRACTALBAKE] [THREADS] [QUALITY]    defaults: build/fractalbake, 2, 50
#
# The genome is `gold` of docs/examples/flames.flame at 1024 x 1024. Prints one line per renderer.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
FB=$(realpath "${1:-$root/build/fractalbake}")
threads=${2:-2}
q=${3:-50}
command -v flam3-render > /dev/null || { echo "bench/flame.sh: flam3-render (flam3-utils) is not installed" >&2; exit 2; }
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fb-flame-bench-XXXXXX")
trap 'rm -rf "$tmp"' EXIT
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-$tmp}
python3 - "$root/docs/examples/flames.flame" "$tmp/g.flame" "$q" <<'EOF'
import sys, xml.etree.ElementTree as ET
f = [x for x in ET.parse(sys.argv[1]).getroot() if x.get('name') == 'gold'][0]
w = int(f.get('size').split()[0])
f.set('scale', '%.9g' % (float(f.get('scale')) * 1024 / w)); f.set('size', '1024 1024'); f.set('quality', sys.argv[3])
ET.ElementTree(f).write(sys.argv[2])
EOF
points=$((1024 * 1024 * q))
median() { sort -g | sed -n 2p; }
t_fb=$(for i in 1 2 3; do
    s=$(date +%s.%N)
    "$FB" flame --file "$tmp/g.flame" --size 1024x1024 --threads "$threads" --backend native --quiet -o "$tmp/o.exr"
    echo "$(date +%s.%N) - $s" | bc
done | median)
t_f3=$(for i in 1 2 3; do
    s=$(date +%s.%N)
    env nthreads="$threads" isaac_seed=bench out="$tmp/o.png" flam3-render < "$tmp/g.flame" > /dev/null 2>&1
    echo "$(date +%s.%N) - $s" | bc
done | median)
printf 'flame 1024x1024 quality %s (%d points), %d threads, %s\n' "$q" "$points" "$threads" "$(date -u +%F)"
printf '  fractalbake native  %6.2f s  %7.1f Mpts/s\n' "$t_fb" "$(echo "$points / $t_fb / 1000000" | bc -l)"
printf '  flam3-render 3.1.1  %6.2f s  %7.1f Mpts/s\n' "$t_f3" "$(echo "$points / $t_f3 / 1000000" | bc -l)"
printf '  ratio               %6.2fx\n' "$(echo "$t_f3 / $t_fb" | bc -l)"
