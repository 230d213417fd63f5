#!/usr/bin/env bash
# Fractal flames beside libflam3 (flam3-render of Debian's flam3-utils), the same genome, the same
# size, quality and thread count, side by side in one run: points per second of the whole render
# (chaos game, density estimation, filter, tone map and writing the file), the median of 3 runs each,
# alternated, in wall seconds and in CPU seconds (user + system: less sensitive to a loaded machine).
# fractalbake runs twice: natively and on Vulkan (lavapipe on a machine without a GPU; its CPU
# seconds are the driver's threads, its pipeline's compilation included).
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
# run: "WALL CPU" seconds of one render (CPU: user + system, every thread's), the command after it
run() { /usr/bin/time -f '%e %U %S' -o "$tmp/t" "$@" > /dev/null 2>&1; awk '{print $1, $2 + $3}' "$tmp/t"; }
fb() { run "$FB" flame --file "$tmp/g.flame" --size 1024x1024 --threads "$threads" --backend native --quiet -o "$tmp/o.exr"; }
# lavapipe's threads: LP_NUM_THREADS
fv() { run env LP_NUM_THREADS="$threads" "$FB" flame --file "$tmp/g.flame" --size 1024x1024 --threads "$threads" \
    --backend vulkan --quiet -o "$tmp/v.exr"; }
fb0() { run "$FB_BEFORE" flame --file "$tmp/g.flame" --size 1024x1024 --threads "$threads" --backend native --quiet -o "$tmp/b.exr"; }
pe() { run "$FLAME_PEER" "$threads" "$q"; }
f3() { run env nthreads="$threads" isaac_seed=bench out="$tmp/o.png" flam3-render < "$tmp/g.flame"; }
# alternated, so that both see the same load; the medians of wall and of CPU seconds
vk=${FB_VULKAN:-1}
for i in 1 2 3; do
    fb >> "$tmp/fb"
    [ "$vk" = 0 ] || fv >> "$tmp/fv"
    [ -z "${FB_BEFORE:-}" ] || fb0 >> "$tmp/fb0"
    [ -z "${FLAME_PEER:-}" ] || pe >> "$tmp/pe"
    f3 >> "$tmp/f3"
done
[ "$vk" = 0 ] || "$FB" compare "$tmp/o.exr" "$tmp/v.exr" --max-abs 0 --quiet > /dev/null ||
    echo "bench/flame.sh: the Vulkan file differs from the native one" >&2
[ -z "${FB_BEFORE:-}" ] || "$FB" compare "$tmp/o.exr" "$tmp/b.exr" --max-abs 0 --quiet > /dev/null ||
    echo "bench/flame.sh: the file of FB_BEFORE differs from this one" >&2
[ "$vk" = 0 ] || { t_fv=$(cut -d' ' -f1 "$tmp/fv" | median) c_fv=$(cut -d' ' -f2 "$tmp/fv" | median); }
t_fb=$(cut -d' ' -f1 "$tmp/fb" | median) c_fb=$(cut -d' ' -f2 "$tmp/fb" | median)
t_f3=$(cut -d' ' -f1 "$tmp/f3" | median) c_f3=$(cut -d' ' -f2 "$tmp/f3" | median)
printf 'flame 1024x1024 quality %s (%d points), %d threads, %s, load %s\n' "$q" "$points" "$threads" "$(date -u +%F)" \
    "$(cut -d' ' -f1 /proc/loadavg)"
printf '  %-20s %7s %9s %8s %12s\n' renderer "wall s" "Mpts/s" "CPU s" "Mpts/CPU-s"
line() { printf '  %-20s %7.2f %9.1f %8.2f %12.1f\n' "$1" "$2" "$(echo "$points / $2 / 1000000" | bc -l)" "$3" \
    "$(echo "$points / $3 / 1000000" | bc -l)"; }
line "fractalbake native" "$t_fb" "$c_fb"
[ "$vk" = 0 ] || line "fractalbake vulkan" "$t_fv" "$c_fv"
if [ -n "${FB_BEFORE:-}" ]; then
    t_fb0=$(cut -d' ' -f1 "$tmp/fb0" | median) c_fb0=$(cut -d' ' -f2 "$tmp/fb0" | median)
    line "native, FB_BEFORE" "$t_fb0" "$c_fb0"
fi
if [ -n "${FLAME_PEER:-}" ]; then
    t_pe=$(cut -d' ' -f1 "$tmp/pe" | median) c_pe=$(cut -d' ' -f2 "$tmp/pe" | median)
    line "flame_peer (ceiling)" "$t_pe" "$c_pe"
fi
line "flam3-render 3.1.1" "$t_f3" "$c_f3"
ratio() { printf '  ratio %-22s %6.2fx            %6.2fx\n' "$1 (flam3 / it)" "$(echo "$t_f3 / $2" | bc -l)" "$(echo "$c_f3 / $3" | bc -l)"; }
ratio native "$t_fb" "$c_fb"
[ "$vk" = 0 ] || ratio vulkan "$t_fv" "$c_fv"
[ -z "${FB_BEFORE:-}" ] || ratio "native before" "$t_fb0" "$c_fb0"
[ -z "${FLAME_PEER:-}" ] || ratio flame_peer "$t_pe" "$c_pe"
