#!/usr/bin/env bash
# The bake's pieces: the same bits whatever their height, the thread count or the memory path (a
# CPU device's mapped buffers, or FB_VK_STAGING's device buffers copied back through host buffers,
# the discrete GPU's path), for the EXR file, the preview and a heightmap; and the pieces sized for
# the device as --dry-run reports them.
# Usage: pieces-gpu.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
require_vulkan
if [ -n "${FB_VK_STAGING:-}" ]; then # CTest's NAME-staging entry: this script sets it per bake itself
  echo "FB_VK_STAGING is part of this script's own runs: not run again under it"
  exit 77
fi

# A per-pixel layer with a heightmap, a Julia set (seven channels, some half, one uint), an op layer
# reading the first, and a chaos game (prepared before the pieces, its rows from the host).
cat > s.json << 'JSON'
{"size": [200, 120], "layers": [
 {"type": "fbm", "name": "h", "octaves": 4, "heightmap": "h.png"},
 {"type": "julia", "name": "sky", "samples": 2},
 {"type": "op", "name": "snow", "op": "threshold", "inputs": ["h"], "level": 0.2, "width": 0.1},
 {"type": "ifs", "name": "fern", "preset": "fern", "points": 100000}
]}
JSON

# bake NAME ARGS...: NAME.exr, NAME.png (the preview) and NAME.h.png (the heightmap)
bake() {
  local name=$1
  shift
  if "$FB" render s.json -o "$name.exr" --preview "$name.png" --quiet "$@" && mv h.png "$name.h.png"; then
    ok
  else
    bad "$name: the bake failed ($*)"
  fi
}

# same A B WHAT: A's three files are B's, byte for byte
same() {
  local f
  for f in exr png h.png; do
    cmp -s "$1.$f" "$2.$f" && ok || bad "$3: $1.$f and $2.$f differ"
  done
}

V="--backend vulkan"
bake v0 $V
bake v1 $V --strip-rows 1
bake v64 $V --strip-rows 64 --threads 1
FB_VK_STAGING=1 bake s0 $V
FB_VK_STAGING=1 bake s7 $V --strip-rows 7 --threads 3
FB_VK_STAGING=1 bake s64 $V --strip-rows 64
for k in v1 v64 s0 s7 s64; do same v0 $k "vulkan, pieces of other heights or staged"; done

N="--backend native"
bake n0 $N
bake n5 $N --strip-rows 5 --threads 2
bake n64 $N --strip-rows 64 --threads 3
bake n1 $N --strip-rows 1 --threads 1
for k in n5 n64 n1; do same n0 $k "native, pieces of other heights or threads"; done

# The pieces as --dry-run --json reports them, 8192 x 1024: a CPU's strips of at most 2^20 pixels and
# at least 32 pieces (1024 / 32 = 32 rows), on native and on lavapipe; the staged path's dispatches of
# 2^22 invocations (2^22 / 8192 = 512 rows, a multiple of 64).
rows_of() {
  "$FB" fbm --size 8192x1024 -o d.exr --dry-run --json "$@" | sed -n 's/.*"piece_rows": \([0-9]*\).*/\1/p'
}
r=$(rows_of $N)
check "native: $r rows a piece, wanted 32" test "$r" = 32
r=$(rows_of $V)
check "lavapipe: $r rows a piece, wanted 32" test "$r" = 32
r=$(FB_VK_STAGING=1 rows_of $V)
check "staged: $r rows a piece, wanted 512" test "$r" = 512
r=$(FB_VK_STAGING=1 rows_of $V --strip-rows 100)
check "staged, --strip-rows 100: $r rows a piece" test "$r" = 100

# Several staged pieces of the automatic size (512 rows, held in place by the EXR writer's workers)
# against lavapipe's strips of 100 rows (copied by the writer): the same file.
F="fbm --size 8192x1024 --octaves 2 --quiet $V"
FB_VK_STAGING=1 "$FB" $F -o big_s.exr && ok || bad "staged 8192 x 1024 bake failed"
"$FB" $F --strip-rows 100 -o big_v.exr && ok || bad "8192 x 1024 bake in strips of 100 rows failed"
cmp -s big_s.exr big_v.exr && ok || bad "staged pieces of 512 rows and strips of 100 rows differ"

cli_finish
