#!/usr/bin/env bash
# What `cmake --install` gives a user, used as the docs use it (docs/library.md): installed into a
# fresh prefix, docs/examples/library.c compiled with `pkg-config --cflags --libs fractalbake`
# against the installed header and library alone, run, and its channels' hashes equal those of the
# installed `fractalbake render`'s file (read by the installed Python module, which finds the
# installed library by itself); then docs/examples/library.py through the installed module.
#   install.sh BUILD_DIR SOURCE_DIR
# Not run (77) where no python3 has numpy (python3-numpy) or the build has the sanitizers.
set -euo pipefail
build=$(cd "$1" && pwd) src=$(cd "$2" && pwd)
if ldd "$build/libfractalbake.so" | grep -q libasan; then echo "SKIP: a sanitizer build"; exit 77; fi
py=
for p in /usr/bin/python3 python3; do
  if "$p" -c "import numpy" 2>/dev/null; then py=$p; break; fi
done
[ -n "$py" ] || { echo "SKIP: no python3 with numpy"; exit 77; }
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
prefix=$T/prefix
cmake --install "$build" --prefix "$prefix" >/dev/null
pc=$(dirname "$(find "$prefix" -name fractalbake.pc)")
moddir=$(dirname "$(find "$prefix" -path '*fractalbake/__init__.py')")
test -f "$prefix/include/fractalbake.h" && test -x "$prefix/bin/fractalbake"
export PKG_CONFIG_PATH=$pc
libdir=$(cd "$(pkg-config --variable=libdir fractalbake)" && pwd -P)
# shellcheck disable=SC2046
cc -std=c11 -Wall -Wextra -Werror -o "$T/example" "$src/docs/examples/library.c" \
  $(pkg-config --cflags --libs fractalbake) -Wl,-rpath,"$libdir"
# linked against the installed library, not the build's
ldd "$T/example" | grep -q "$libdir/libfractalbake.so.0" || { echo "FAIL: the example is not linked to $libdir"; exit 1; }
"$T/example" size=96x48 seed=11 >"$T/example.txt"
"$prefix/bin/fractalbake" render -q --backend native --set size=96x48 --set seed=11 -o "$T/cli.exr"
cd "$T"
unset FRACTALBAKE_LIBRARY
PYTHONPATH=$(dirname "$moddir") "$py" - "$T/cli.exr" "$T/example.txt" "$libdir" <<'PY'
import sys
import numpy as np
import fractalbake
planes = fractalbake.read(sys.argv[1])
assert fractalbake._library_path().startswith(sys.argv[3]), fractalbake._library_path()
def fnv(b):
    h = 14695981039346656037
    for x in b:
        h = ((h ^ x) * 1099511628211) & 0xFFFFFFFFFFFFFFFF
    return h
want = [f"{k} {fnv((v.astype(np.float32) if v.dtype == np.float16 else v).tobytes()):016x}" for k, v in planes.items()]
got = open(sys.argv[2]).read().split("\n")[:-1]
assert len(want) == 24 and got == want, "\n".join(a + "  |  " + b for a, b in zip(got, want))
print(f"the installed example's {len(got)} channels equal the installed fractalbake render's")
PY
PYTHONPATH=$(dirname "$moddir") "$py" "$src/docs/examples/library.py" "$prefix/bin/fractalbake"
echo "PASS"
