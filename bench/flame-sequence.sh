#!/usr/bin/env bash
# A flame sequence beside flam3-animate (Debian's flam3-utils), the same keyframes, size, quality,
# temporal samples and thread count, in one run: 48 frames at 1280 x 720 of the three genomes of
# docs/examples/flames.flame as keyframes at times 0, 24 and 48 (flam3-animate's default frames,
# 0 to 47), flam3's default 1000 temporal samples (motion blur) a frame. Frames per second of the
# whole sequence (chaos games, density estimation, filter, tone map, writing each file), in wall
# seconds and in CPU seconds (user + system: steadier on a loaded machine); the two renderers
# alternate, ROUNDS times each.
#
#   bench/flame-sequence.sh [FRACTALBAKE] [THREADS] [QUALITY] [FRAMES] [ROUNDS]
#                           defaults: build/fractalbake, 2, 10, 48, 1
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
FB=$(realpath "${1:-$root/build/fractalbake}")
read -r threads q frames rounds <<< "${2:-2} ${3:-10} ${4:-48} ${5:-1}"
for tool in flam3-animate /usr/bin/time; do
    command -v "$tool" > /dev/null || { echo "bench/flame-sequence.sh: $tool is not installed" >&2; exit 2; }
done
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fb-flame-seq-XXXXXX") && trap 'rm -rf "$tmp"' EXIT
python3 - "$root/docs/examples/flames.flame" "$tmp/k.flame" "$q" << 'PY'
import sys, xml.etree.ElementTree as ET
src = ET.parse(sys.argv[1]).getroot().findall('flame')
root = ET.Element('flames')
for t, f in zip((0, 24, 48), src):
    w = int(f.get('size').split()[0])
    f.set('scale', '%.9g' % (float(f.get('scale')) * 1280 / w)); f.set('size', '1280 720')
    f.set('quality', sys.argv[3]); f.set('time', str(t))
    root.append(f)
ET.ElementTree(root).write(sys.argv[2])
PY
cd "$tmp"
last=$((frames - 1))
# run NAME: "WALL CPU" seconds of the command after it
run() {
    local name=$1
    shift
    /usr/bin/time -f "%e %U %S" -o "$name.time" "$@" > /dev/null 2> "$name.err" || { cat "$name.err" >&2; exit 3; }
    awk '{ printf "%.2f %.2f\n", $1, $2 + $3 }' "$name.time"
}
for r in $(seq "$rounds"); do
    rm -f f.*.exr a*.png
    fb=$(run fb "$FB" flame --file k.flame --size 1280x720 --frames "0-$last" --threads "$threads" --backend native \
        --quiet -o f.%04d.exr)
    fl=$(run fl env begin=0 end="$last" nthreads="$threads" prefix=a flam3-animate < k.flame)
    [ "$(ls f.*.exr | wc -l)" = "$frames" ] && [ "$(ls a*.png | wc -l)" = "$frames" ] || { echo "frames missing" >&2; exit 3; }
    read -r fw fc <<< "$fb"
    read -r lw lc <<< "$fl"
    awk -v n="$frames" -v fw="$fw" -v fc="$fc" -v lw="$lw" -v lc="$lc" -v q="$q" -v t="$threads" 'BEGIN {
        printf "round %d: %d frames 1280x720 q%s, %s threads | fractalbake %.1f s wall (%.3f fps), %.1f CPU s (%.2f CPU s a frame) | flam3-animate %.1f s wall (%.3f fps), %.1f CPU s (%.2f CPU s a frame) | ratio wall %.2fx, CPU %.2fx\n",
            '"$r"', n, q, t, fw, n / fw, fc, fc / n, lw, n / lw, lc, lc / n, lw / fw, lc / fc }'
done
