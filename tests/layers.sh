#!/usr/bin/env bash
# scripts/check-layers.sh: passes on the tree, and fails, naming the file, on each kind of include
# against the order of folders (planted in a scratch copy of host/).
set -u
src=$(cd "$(dirname "$0")/.." && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
pass=0 fail=0
check() { if eval "$2"; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL: $1" >&2; fi; }
check "the tree keeps the order" "bash '$src/scripts/check-layers.sh' '$src/host' 2> '$tmp/err'"
# plant: FILE, the include, the words the message must have
plant() {
    rm -rf "$tmp/host"
    cp -r "$src/host" "$tmp/host"
    printf '#include "%s"\n' "$2" >> "$tmp/host/$1"
    bash "$src/scripts/check-layers.sh" "$tmp/host" 2> "$tmp/err"
    local rc=$?
    check "$1 including $2 fails" "[ $rc -eq 1 ] && grep -q 'host/$1: #include \"$2\"' '$tmp/err' && grep -q '$3' '$tmp/err'"
}
plant io/exrio_read.c scene.h "host/core) goes against"         # io may not include core (a cycle with bake.c)
plant base/log.c exrio.h "host/io) goes against"           # base includes nothing above it
plant core/bake.c gen_ifs.h "host/gen/ifs) goes against"   # core knows no generator
plant gen/fbm/layer.c gen_ifs.h "host/gen/ifs) goes against" # a generator another it does not link
plant gen/fbm/layer.c delaunay.h "host/geom) goes against"   # geom only where linked (terrain)
plant cli/main.c gen_fbm.h "host/gen/fbm) goes against"      # the commands name no generator
plant geom/delaunay.c vkc.h "host/io) goes against"        # geom and io are side by side
plant core/scene.c ../io/exrio.h "not a header of host/ by its name" # no paths around the rule
plant gen/julia/layer.c cli.h "not a header of host/ by its name"    # no header of that name
# a loop of includes: scene.h -> gen.h -> scene.h
rm -rf "$tmp/host"
cp -r "$src/host" "$tmp/host"
printf '#include "gen.h"\n' >> "$tmp/host/core/scene.h"
bash "$src/scripts/check-layers.sh" "$tmp/host" 2> "$tmp/err"
rc=$?
check "a loop of includes fails" "[ $rc -eq 1 ] && grep -q 'an include loop: host/core/scene.h -> host/core/gen.h -> host/core/scene.h' '$tmp/err'"
# host/cli at 4000 lines
rm -rf "$tmp/host"
cp -r "$src/host" "$tmp/host"
n=$(cat "$tmp"/host/cli/*.[ch] | wc -l)
yes '/* planted */' | head -n $((4000 - n)) > "$tmp/host/cli/planted.c"
bash "$src/scripts/check-layers.sh" "$tmp/host" 2> "$tmp/err"
rc=$?
check "host/cli at 4000 lines fails" "[ $rc -eq 1 ] && grep -q 'host/cli holds 4000 lines' '$tmp/err'"
sed -i 1d "$tmp/host/cli/planted.c"
check "host/cli at 3999 lines passes" "bash '$src/scripts/check-layers.sh' '$tmp/host'"
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
