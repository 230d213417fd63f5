#!/bin/bash
# Checks the structure of host/ (docs/architecture.md), naming each breach, exit 1 on any:
# - every include goes down: a folder may include its own headers and those of the folders its
#   library links (CMakeLists.txt), never one above or beside it:
#     base <- geom, io <- core <- gen/NAME <- gen (the list); core <- compare <- cli, lib
#   A generator may use another generator's header, or geom's, only where CMakeLists.txt links the
#   two (listed below; tests/rules.py checks that the lists are the same);
# - no loop of includes: no header includes itself through others;
# - host/cli, the commands, under 4000 lines: the work behind a command lives in a library below.
#   scripts/check-layers.sh [HOST]             check HOST (host/ of this tree by default)
#   scripts/check-layers.sh --allowed [HOST]   print each folder and the folders it may include
set -u
print=0
[ "${1:-}" = --allowed ] && print=1 && shift
host=${1:-$(dirname "$0")/../host}
cd "$host" || exit 2
gens=$(for d in gen/*/; do printf '%s ' "${d%/}"; done)
# the folders each may include, its own first
allowed() {
    case $1 in
    base) echo "base" ;;
    geom) echo "geom base" ;;
    io) echo "io base" ;;
    core) echo "core base io" ;;
    gen/julia) echo "gen/julia base io core gen/fbm" ;;
    gen/ifs) echo "gen/ifs base io core gen/lsystem" ;;
    gen/terrain) echo "gen/terrain base io core geom" ;;
    gen/*) echo "$1 base io core" ;;
    gen) echo "gen base io core geom $gens" ;;
    compare) echo "compare base io core" ;;
    cli) echo "cli base io core compare" ;;
    lib) echo "lib base io core compare" ;;
    *) echo "" ;;
    esac
}
mapfile -t files < <(find . -name '*.[ch]' | sed 's@^\./@@' | sort)
declare -A home ok
for f in "${files[@]}"; do
    dir=${f%/*}
    [ "$dir" = "$f" ] && dir=.
    [[ $f == *.h ]] && home[${f##*/}]=$dir
    [ -n "${ok[$dir]+x}" ] || ok[$dir]=" $(allowed "$dir") "
done
if [ $print -eq 1 ]; then
    for d in $(printf '%s\n' "${!ok[@]}" | sort); do echo "$d:${ok[$d]% }"; done
    exit 0
fi
bad=0
declare -A edges # FILE -> the headers of host/ it includes
# every #include "..." of host/, as FILE:#include "HEADER"
while IFS= read -r line; do
    f=${line%%:*}
    f=${f#./}
    dir=${f%/*}
    h=${line#*\"}
    h=${h%\"*}
    # generated at build time: SPIR-V (NAME_comp.h) and the embedded default scene (core only)
    case $h in kernels/* | *_comp.h) continue ;; esac
    [ "$h" = default_scene.h ] && [ "$dir" = core ] && continue
    # the installed API (include/fractalbake.h), which the library implements
    [ "$h" = fractalbake.h ] && [ "$dir" = lib ] && continue
    where=${home[${h##*/}]:-}
    if [ -z "$where" ] || [ "$h" != "${h##*/}" ]; then
        echo "check-layers: host/$f: #include \"$h\": not a header of host/ by its name" >&2
        bad=1
    elif [[ ${ok[$dir]} != *" $where "* ]]; then
        echo "check-layers: host/$f: #include \"$h\" (host/$where) goes against the order of folders" >&2
        bad=1
    else
        edges[$f]+=" $where/${h##*/}"
    fi
done < <(grep -H '^#include "' "${files[@]}")
# loops: a depth-first walk from every file; a header met again on the current path closes one
declare -A state # 1: on the path, 2: done
path=()
visit() {
    local f=$1 g k loop
    state[$f]=1
    path+=("$f")
    for g in ${edges[$f]:-}; do
        if [ "${state[$g]:-0}" = 1 ]; then
            loop=""
            for ((k = ${#path[@]} - 1; k >= 0; k--)); do
                loop="host/${path[k]} -> $loop"
                [ "${path[k]}" = "$g" ] && break
            done
            echo "check-layers: an include loop: ${loop}host/$g" >&2
            bad=1
        elif [ "${state[$g]:-0}" = 0 ]; then
            visit "$g"
        fi
    done
    unset 'path[${#path[@]}-1]'
    state[$f]=2
}
for f in "${files[@]}"; do [ "${state[$f]:-0}" = 0 ] && visit "$f"; done
cli_max=4000
cli_lines=0
for f in cli/*.[ch]; do
    mapfile -t lines < "$f"
    cli_lines=$((cli_lines + ${#lines[@]}))
done
if [ "$cli_lines" -ge $cli_max ]; then
    echo "check-layers: host/cli holds $cli_lines lines, $cli_max or more: move the work behind a command into" \
        "a library below it" >&2
    bad=1
fi
exit $bad
