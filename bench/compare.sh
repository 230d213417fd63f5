#!/usr/bin/env bash
# compare's speed: two 20-layer 1024 x 1024 files (fBm, one float Y a layer, 6 octaves against 5),
# every statistic (max, RMSE, PSNR, the share beyond, SSIM, idiff's block) without and with FLIP,
# beside OpenImageIO's idiff on the same pair, one run each, side by side. Prints one line per tool:
# seconds of wall time and of CPU (user + system, both shown) and the 1-minute load average after
# it (on a shared machine the wall time swells with the load; CPU time much less). With BEFORE (an
# earlier build), its every-statistic run too, on two threads and on one.
# Usage: bench/compare.sh PATH/TO/fractalbake [SIZE [BEFORE]]
set -euo pipefail
FB=$(realpath "${1:-build/fractalbake}")
S=${2:-1024}
BEFORE=${3:+$(realpath "$3")}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
cd "$T"
scene() { # scene OCTAVES FIRST: 10 fBm layers of different frequencies (a scene holds at most 16)
  printf '{"size": [%d, %d], "layers": [' "$S" "$S"
  for i in $(seq "$2" $(($2 + 9))); do
    printf '%s{"type": "fbm", "name": "f%02d", "octaves": %d, "frequency": %d}' "$([ "$i" = "$2" ] || echo ,)" "$i" "$1" "$((i + 2))"
  done
  printf ']}\n'
}
for o in 6 5; do
  scene $o 1 > s$o-1.json
  scene $o 11 > s$o-2.json
  "$FB" render s$o-1.json --backend native --quiet -o s$o-1.exr
  "$FB" render s$o-2.json --backend native --quiet -o s$o-2.exr
done
oiiotool s6-1.exr s6-2.exr --chappend -o a.exr # 20 layers in one file
oiiotool s5-1.exr s5-2.exr --chappend -o b.exr
run_inner() {
  local label=$1 t0 t1
  shift
  t0=$(date +%s.%N)
  /usr/bin/time -f "%U %S" -o cpu.txt "$@" > /dev/null 2>&1 || true
  t1=$(date +%s.%N)
  local user sys
  read -r user sys < <(tail -1 cpu.txt)
  printf '%-44s wall %6.2f s  cpu %6.2f s (user %s, sys %s)  load %s\n' "$label" "$(echo "$t1 - $t0" | bc)" \
    "$(echo "$user + $sys" | bc)" "$user" "$sys" "$(cut -d' ' -f1 /proc/loadavg)"
}
echo "# $(date -u +%F), $(lscpu | sed -n 's/^Model name: *//p' | head -1), $(nproc) cores, load $(cut -d' ' -f1 /proc/loadavg); 20 layers of ${S}x${S}"
run_inner "idiff (max, mean, RMS, PSNR, counts)" idiff -fail 0.01 a.exr b.exr
run_inner "compare: max, RMSE, PSNR, share beyond" "$FB" compare a.exr b.exr --fail 0.01
run_inner "compare: + SSIM + idiff's block" "$FB" compare a.exr b.exr --fail 0.01 --ssim 0.5 --idiff-stats
run_inner "compare: + SSIM + idiff's block + FLIP" "$FB" compare a.exr b.exr --fail 0.01 --ssim 0.5 --idiff-stats --flip
run_inner "  the same on one thread (--threads 1)" "$FB" compare a.exr b.exr --fail 0.01 --ssim 0.5 --idiff-stats --flip \
  --threads 1
[ -z "$BEFORE" ] || run_inner "  the same, the build before" "$BEFORE" compare a.exr b.exr --fail 0.01 --ssim 0.5 \
  --idiff-stats --flip
[ -z "$BEFORE" ] || run_inner "  the build before on one thread" "$BEFORE" compare a.exr b.exr --fail 0.01 --ssim 0.5 \
  --idiff-stats --flip --threads 1
echo "# load afterwards $(cut -d' ' -f1-3 /proc/loadavg)"
