#!/usr/bin/env bash
# Runs every benchmark once and appends the machine-readable lines, with date and machine, to
# bench/results.jsonl. Usage: bench/run.sh [--size WxH]
# The Delaunay peer (CGAL's Delaunay_triangulation_2, bench/cgal_delaunay.cpp) is built and run
# beside fractalbake's own when libcgal-dev can be installed, and the chaos-game peer (libflam3 rendering
# the fern, bench/flam3_fern.c) when libflam3-dev can; fractalbake never links either. The fBm peer
# (bench/fbm_peer.c, a minimal AVX2 gradient fBm at 4096 x 4096) and the erosion peer
# (bench/erode_peer.c, the virtual-pipe model written plainly, at up to 1024 x 1024), the flame's
# (bench/peers/flame_peer.c, the genome gold's chaos game hard-coded) and the stream-power peer
# (bench/peers/rivers_peer.c, at the rivers rows' 1024 x 1024 and 50 steps; for 2048 x 2048 and 500
# steps, bench/rivers.sh) always run.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
machine="$(lscpu | sed -n 's/^Model name: *//p' | head -1), $(nproc) cores"
peer=""
if dpkg-query -W -f='${Status}' libcgal-dev 2>/dev/null | grep -q "install ok installed" ||
  { [ "$(id -u)" -eq 0 ] && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends libcgal-dev g++ > /dev/null 2>&1; }; then
  g++ -O3 -march=native -DNDEBUG -o build/cgal_delaunay bench/cgal_delaunay.cpp -lgmp -lmpfr && peer=build/cgal_delaunay
fi
flam3=""
if dpkg-query -W -f='${Status}' libflam3-dev 2>/dev/null | grep -q "install ok installed" ||
  { [ "$(id -u)" -eq 0 ] && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends libflam3-dev pkg-config > /dev/null 2>&1; }; then
  gcc -O3 -march=native -o build/flam3_fern bench/flam3_fern.c $(pkg-config --cflags --libs flam3) && flam3=build/flam3_fern
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
done | tee -a bench/results.jsonl
