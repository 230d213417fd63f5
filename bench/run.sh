#!/usr/bin/env bash
# Runs every benchmark once and appends the machine-readable lines, with date and machine, to OUT
# (default build/bench-results.jsonl, outside the repository's tracked files; bench/results.jsonl is
# the record of one run that bench/RESULTS.md reads, and changes only by hand).
#
#   bench/run.sh [--out OUT.jsonl] [--size WxH]
#
# It installs nothing: it needs a build (./scripts/setup.sh) and builds the peers with what is
# installed. The Delaunay peer (CGAL's Delaunay_triangulation_2, bench/cgal_delaunay.cpp) runs beside
# fractalbake's own when libcgal-dev is installed, and the chaos-game peer (libflam3 rendering the
# fern, bench/flam3_fern.c) when libflam3-dev is (./scripts/setup.sh installs both); fractalbake never
# links either. The fBm peer (bench/fbm_peer.c, a minimal AVX2 gradient fBm at 4096 x 4096) and the
# erosion peer (bench/erode_peer.c, the virtual-pipe model written plainly, at up to 1024 x 1024), the
# flame's (bench/peers/flame_peer.c, the genome gold's chaos game hard-coded) and the stream-power peer
# (bench/peers/rivers_peer.c, at the rivers rows' 1024 x 1024 and 50 steps; for 2048 x 2048 and 500
# steps, bench/rivers.sh) always run.
set -euo pipefail
cd "$(dirname "$0")/.."
out=build/bench-results.jsonl
if [ "${1:-}" = --out ]; then
  [ $# -ge 2 ] || { echo "bench/run.sh: --out: missing file name" >&2; exit 2; }
  out=$2
  shift 2
fi
case $out in
bench/results.jsonl | ./bench/results.jsonl)
  echo "bench/run.sh: --out $out: a tracked file; write elsewhere and copy what you keep" >&2
  exit 2
  ;;
esac
if [ ! -x build/fractalbake ]; then
  echo "bench/run.sh: no build/fractalbake: build it first (./scripts/setup.sh)" >&2
  exit 2
fi
mkdir -p "$(dirname "$out")"
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
installed() { dpkg-query -W -f='${Status}' "$1" 2> /dev/null | grep -q "install ok installed"; }
machine="$(lscpu | sed -n 's/^Model name: *//p' | head -1), $(nproc) cores"
peer=""
if installed libcgal-dev; then
  g++ -O3 -march=native -DNDEBUG -o build/cgal_delaunay bench/cgal_delaunay.cpp -lgmp -lmpfr && peer=build/cgal_delaunay
else
  echo "bench/run.sh: libcgal-dev is not installed: no CGAL peer (./scripts/setup.sh installs it)" >&2
fi
flam3=""
if installed libflam3-dev; then
  gcc -O3 -march=native -o build/flam3_fern bench/flam3_fern.c $(pkg-config --cflags --libs flam3) && flam3=build/flam3_fern
else
  echo "bench/run.sh: libflam3-dev is not installed: no libflam3 peer (./scripts/setup.sh installs it)" >&2
fi
# the fBm peer (bench/fbm_peer.c): plain C and pthreads, always built
gcc -O3 -mavx2 -o build/fbm_peer bench/fbm_peer.c -lpthread -lm
# the erosion peer (bench/erode_peer.c): the same pipe model written plainly, always built
gcc -O3 -march=native -o build/erode_peer bench/erode_peer.c -lpthread -lm
# the flame's peer and ceiling (bench/peers/flame_peer.c: the genome gold, as the flame rows), always
# built, run on every core at the flame rows' quality 20
gcc -O2 -march=native -ffp-contract=off -Ikernels -o build/flame_peer bench/peers/flame_peer.c -lpthread -lm
gcc -O3 -march=native -o build/rivers_peer bench/peers/rivers_peer.c -lm
{
  ./build/fractalbake bench --json "$@"
  ./build/fbm_peer --json "$@"
  ./build/erode_peer --json "$@"
  ./build/flame_peer --json "$(nproc)" 20
  ./build/rivers_peer --json --size 1024x1024 --steps 50
  if [ -n "$peer" ]; then "$peer" --json; fi
  if [ -n "$flam3" ]; then "$flam3" --json "$@"; fi
} | while read -r line; do
  echo "{\"date\": \"$(date -u +%Y-%m-%d)\", \"machine\": \"$machine\", \"result\": $line}"
done | tee -a "$out"
