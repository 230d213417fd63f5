#!/bin/bash
# Checks that host/ includes only downwards: every folder may include its own headers and those of
# the folders below it, never above or beside (docs/architecture.md):
#   base <- geom, io <- core <- gen/NAME <- gen (the list) <- cli
# A generator may use another generator's header only where CMakeLists.txt links the two (listed
# below). Exit 1 naming each include that breaks the order.
set -u
host=${1:-$(dirname "$0")/../host}
cd "$host" || exit 2
# rank of a folder, and the folders each may include
allowed() {
    case $1 in
    base) echo "base" ;;
    geom) echo "base geom" ;;
    io) echo "base io" ;;
    core) echo "base io core" ;;
    gen/julia) echo "base io geom core gen/julia gen/fbm" ;;
    gen/ifs) echo "base io geom core gen/ifs gen/lsystem" ;;
    gen/terrain) echo "base io geom core gen/terrain" ;;
    gen/*) echo "base io geom core $1" ;;
    gen) echo "base io geom core gen" ;;
    cli) echo "base io geom core gen $(cd gen && ls -d */ | sed 's@/$@@; s@^@gen/@' | tr '\n' ' ') cli" ;;
    *) echo "" ;;
    esac
}
# where each header lives
declare -A home
while read -r f; do
    home[$(basename "$f")]=$(dirname "$f")
done < <(find . -name '*.h' | sed 's@^\./@@')
bad=0
while read -r f; do
    dir=$(dirname "$f")
    ok=" $(allowed "$dir") "
    while IFS= read -r inc; do
        h=${inc#*\"}
        h=${h%\"*}
        # generated at build time: SPIR-V (NAME_comp.h) and the embedded default scene (core only)
        case $h in kernels/* | *_comp.h) continue ;; esac
        [ "$h" = default_scene.h ] && [ "$dir" = core ] && continue
        where=${home[$(basename "$h")]:-}
        if [ -z "$where" ] || [ "$h" != "$(basename "$h")" ]; then
            echo "check-layers: host/$f: #include \"$h\": not a header of host/ by its name" >&2
            bad=1
        elif [[ $ok != *" $where "* ]]; then
            echo "check-layers: host/$f: #include \"$h\" (host/$where) goes against the order of folders" >&2
            bad=1
        fi
    done < <(grep -h '^#include "' "$f")
done < <(find . -name '*.[ch]' | sed 's@^\./@@')
exit $bad
