#!/usr/bin/env bash
# Proves the recipe of docs/architecture.md ("Adding a generator"): copies the source tree, adds the
# example generator of docs/examples/generator/ (one folder, one kernel header, one shader) and its
# name to host/gen/list.c, builds, and bakes it: its flags and help, exact pixels on the native
# backend, the same bits on Vulkan, a scene where an op layer uses it, and its own bad input.
# Usage: scripts/try-generator.sh [SCRATCH_DIR]   (exit 0 on success, 1 on a failed check)
set -euo pipefail
src=$(cd "$(dirname "$0")/.." && pwd)
work=${1:-$(mktemp -d /tmp/fb-recipe.XXXXXX)}
mkdir -p "$work"
trap 'rm -rf "$work/tree"' EXIT
tree=$work/tree
rm -rf "$tree"
mkdir -p "$tree"
tar -C "$src" --exclude=./.git --exclude='./build*' -cf - . | tar -C "$tree" -xf -
cp -r "$src/docs/examples/generator/." "$tree/"
# the one line in the list
python3 - "$tree/host/gen/list.c" << 'PY'
import sys
p = sys.argv[1]
s = open(p).read()
assert "    X(op)\n" in s, "the list's last entry moved; update try-generator.sh"
s = s.replace("    X(op)\n", "    X(op)                \\\n    X(checker)\n")
open(p, "w").write(s)
PY
echo "try-generator: building the tree with the checker generator added" >&2
cmake -S "$tree" -B "$tree/build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DBUILD_TESTING=OFF > "$work/cmake.log"
cmake --build "$tree/build" --target fractalbake -j"$(nproc)" > "$work/build.log" 2>&1 || {
    tail -30 "$work/build.log" >&2
    exit 1
}
fb=$tree/build/fractalbake
cd "$work"
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
fail=0
check() { if ! eval "$2"; then echo "FAIL: $1" >&2; fail=1; else echo "ok: $1"; fi; }

# the help read whole first: grep -q closes the pipe early, and a write to a closed pipe ends
# fractalbake with SIGPIPE, which pipefail would report
"$fb" --help > help.txt
"$fb" checker --help > checker-help.txt
check "the top-level help lists the new command" "grep -q '^  checker \[options\] -o OUT.exr  *a checkerboard' help.txt"
check "its --help lists its keys" "grep -q -- '--cells' checker-help.txt"
$fb checker --size 64x32 --cells 4 --compression none --backend native --quiet -o native.exr
# every pixel from the EXR file itself (uncompressed scanlines), against the formula
cat > read_exr.py << 'PY'
import struct, sys
def channels(path):
    b = open(path, "rb").read()
    assert b[:4] == b"\x76\x2f\x31\x01", "not an EXR file"
    p, attrs = 8, {}
    while b[p] != 0:
        n = b.index(b"\0", p); name = b[p:n].decode(); t = b.index(b"\0", n + 1)
        size, = struct.unpack_from("<i", b, t + 1)
        attrs[name] = b[t + 5:t + 5 + size]; p = t + 5 + size
    p += 1
    chans, q, cl = [], 0, attrs["channels"]
    while cl[q] != 0:
        n = cl.index(b"\0", q); chans.append((cl[q:n].decode(), struct.unpack_from("<i", cl, n + 1)[0])); q = n + 17
    x0, y0, x1, y1 = struct.unpack("<4i", attrs["dataWindow"])
    w, h = x1 - x0 + 1, y1 - y0 + 1
    offsets = struct.unpack_from("<%dQ" % h, b, p)
    out = {c: [[0.0] * w for _ in range(h)] for c, _ in chans}
    for off in offsets:
        y, _ = struct.unpack_from("<ii", b, off); q = off + 8
        for c, t in chans:
            fmt, sz = ("<%df" % w, 4) if t == 2 else ("<%de" % w, 2)
            out[c][y - y0] = list(struct.unpack_from(fmt, b, q)); q += w * sz
    return w, h, out
w, h, ch = channels(sys.argv[1])
want = lambda x, y: float(((x * 4 // w) + (y * 4 // h)) & 1)
bad = [(x, y) for y in range(h) for x in range(w) if ch["checker.Y"][y][x] != want(x, y)]
assert not bad, "checker.Y differs at %d pixels, first %s" % (len(bad), bad[0])
if "inv.Y" in ch:
    bad = [(x, y) for y in range(h) for x in range(w) if ch["inv.Y"][y][x] != 1 - want(x, y)]
    assert not bad, "inv.Y differs at %d pixels" % len(bad)
print("%d x %d pixels exact" % (w, h))
PY
check "native: every pixel is the checker formula" "python3 read_exr.py native.exr"
if $fb devices > /dev/null 2>&1; then
    $fb checker --size 64x32 --cells 4 --compression none --backend vulkan --quiet -o vulkan.exr
    check "vulkan: the same bits as native" "$fb compare native.exr vulkan.exr > /dev/null"
else
    echo "skip: no Vulkan device, the vulkan check is not run"
fi
cat > scene.json << 'JSON'
{"size": [64, 32], "compression": "none",
 "layers": [{"type": "checker", "cells": 4},
            {"type": "op", "name": "inv", "op": "remap", "inputs": ["checker"], "from": [0, 1], "to": [1, 0]}]}
JSON
$fb render scene.json --backend native --quiet -o scene.exr
check "a scene: an op layer reads the new layer's channel" "python3 read_exr.py scene.exr"
set +e
msg=$($fb checker --size 64x32 --cells 100 -o bad.exr 2>&1)
rc=$?
set -e
check "its own check: --cells 100 on 64 x 32 exits 2 naming the flag" "[ $rc -eq 2 ] && grep -q -- '--cells: 100 squares do not fit a 64 x 32 image' <<< \"\$msg\" && [ ! -e bad.exr ]"
# the conformance test of every generator, which now includes the checker with no edit of its own
if python3 "$src/tests/conformance.py" "$fb" > conformance.log 2>&1; then
    echo "ok: the conformance test passes with the checker ($(tail -1 conformance.log))"
else
    grep FAIL conformance.log >&2
    echo "FAIL: the conformance test" >&2
    fail=1
fi
check "the conformance test covered the checker" "python3 -c \"import json,sys; assert any(c['name'] == 'checker' for c in json.load(sys.stdin))\" < <($fb generators --json)"
check "plan splits the checker into bands" "$fb plan <(echo '{\"size\": [2048, 1024], \"layers\": [{\"type\": \"checker\"}]}') --tasks 4 --task-startup 0 --json | python3 -c \"import json,sys; l = json.load(sys.stdin)['layers'][0]; assert l['split'] == 'bands' and l['seconds'] > 0, l\""
if $fb devices > /dev/null 2>&1; then
    if python3 "$src/tests/conformance.py" "$fb" --gpu > conformance-gpu.log 2>&1; then
        echo "ok: the conformance test on Vulkan ($(tail -1 conformance-gpu.log))"
    else
        grep FAIL conformance-gpu.log >&2
        echo "FAIL: the conformance test on Vulkan" >&2
        fail=1
    fi
fi
exit $fail
