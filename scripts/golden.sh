#!/usr/bin/env bash
# Golden images: small reference EXRs for every generator, rendered on lavapipe.
#
#   scripts/golden.sh check  [FRACTALBAKE] [OUTDIR]   render each scene, compare with its reference at
#                                                     the thresholds of tests/golden/thresholds.txt;
#                                                     for each failure OUTDIR holds NAME.exr (this
#                                                     render), NAME.diff.exr (|A - B| per channel) and
#                                                     NAME.diff.png (red: pixels beyond the threshold);
#                                                     the reference's attributes and stored scene must
#                                                     also be what update writes (NAME.header.txt)
#   scripts/golden.sh update [FRACTALBAKE] [NAME...]  re-render the references (the named ones, else
#                                                     all) on the Vulkan backend (lavapipe where there
#                                                     is no GPU), then review `git diff --stat
#                                                     tests/golden` and the PNGs
#
# A scene names its input files (a flame genome) relative to its own folder, as every scene does.
#
# FRACTALBAKE defaults to build/fractalbake; OUTDIR to build/golden. FB_GOLDEN_BACKEND=native or
# vulkan checks that backend (default: auto); every backend must give the reference's bits.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
mode=${1:-check}
fb=$(realpath "${2:-$root/build/fractalbake}")
out=$root/build/golden
[ "$mode" = check ] && out=${3:-$out}
gold=$root/tests/golden
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
# lavapipe's settings, pinned: LP_NATIVE_VECTOR_WIDTH sets its SIMD width and so its subgroup size
# (256: 8 lanes, 128: 4), which may change a shader's results; LP_NUM_THREADS its rasteriser
# threads, which change its speed only. The references were rendered with these (docs/ci.md).
export LP_NATIVE_VECTOR_WIDTH=${LP_NATIVE_VECTOR_WIDTH:-256} LP_NUM_THREADS=${LP_NUM_THREADS:-2}
mkdir -p "$out"
out=$(cd "$out" && pwd)
cd "$root"

render() { # NAME OUT.exr [extra args]
  local name=$1 dst=$2
  shift 2
  if [ "$name" = default ]; then
    "$fb" render --set size=256x128 -o "$dst" --quiet "$@"
  else
    "$fb" render "tests/golden/scenes/$name.json" -o "$dst" --quiet "$@"
  fi
}

# What `info` shows of a file but the name, the backend and device that made it and the version: the
# attributes and the stored scene, which a reference must hold as `update` writes them today.
header() {
  "$fb" info "$1" | grep -v -e '^file:' -e 'fractalbake/backend ' -e 'fractalbake/device ' \
    -e 'fractalbake/layer-backends ' -e 'fractalbake/version '
}

case $mode in
update)
  shift $(($# < 2 ? $# : 2))
  grep -v '^#' "$gold/thresholds.txt" | while read -r name _; do
    [ -n "$name" ] || continue
    [ $# -eq 0 ] || [[ " $* " == *" $name "* ]] || continue
    render "$name" "$gold/$name.exr" --backend vulkan --preview "$out/$name.png"
    echo "updated tests/golden/$name.exr (preview $out/$name.png)"
  done
  ;;
check)
  if [ "${FB_GOLDEN_BACKEND:-auto}" = vulkan ] && "$fb" devices 2> /dev/null | grep -q '^no Vulkan device'; then
    echo "golden: no Vulkan device: not run"
    exit 77
  fi
  failed=0 n=0
  while read -r name args; do
    [ -n "$name" ] || continue
    args=${args%%#*}
    args=$(echo $args)
    [ "$args" = "-" ] && args=""
    n=$((n + 1))
    if ! render "$name" "$out/$name.exr" --backend "${FB_GOLDEN_BACKEND:-auto}"; then
      echo "golden $name: render failed"
      failed=$((failed + 1))
      continue
    fi
    if ! diff <(header "$gold/$name.exr") <(header "$out/$name.exr") > "$out/$name.header.txt"; then
      echo "golden $name: the reference's header is not what \`scripts/golden.sh update $name\` writes today" \
        "(see $out/$name.header.txt)"
      head -4 "$out/$name.header.txt"
      failed=$((failed + 1))
      continue
    fi
    # shellcheck disable=SC2086
    if "$fb" compare "$gold/$name.exr" "$out/$name.exr" $args > "$out/$name.txt"; then
      echo "golden $name: ok (${args:-exact})"
    else
      "$fb" compare "$gold/$name.exr" "$out/$name.exr" $args --diff "$out/$name.diff.exr" --diff-png "$out/$name.diff.png" > /dev/null || true
      echo "golden $name: BEYOND thresholds (${args:-exact}); see $out/$name.txt and $out/$name.diff.png"
      grep FAIL "$out/$name.txt" | head -5
      failed=$((failed + 1))
    fi
  done < <(grep -v '^#' "$gold/thresholds.txt")
  echo "$((n - failed)) of $n golden scenes within thresholds"
  [ "$failed" -eq 0 ]
  ;;
*)
  echo "usage: scripts/golden.sh check|update [FRACTALBAKE] [OUTDIR]" >&2
  exit 2
  ;;
esac
