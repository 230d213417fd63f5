#!/usr/bin/env bash
# Every C file of host/, kernels/, tests/, bench/ and the recipe's example generator (docs/examples/)
# is formatted as .clang-format says (`clang-format --dry-run -Werror`), so that `clang-format -i`
# on a file one edits changes only what one edited. A misformatted file planted in a scratch tree
# fails, naming the file. 77 (not run) without clang-format.
#   tests/format.sh [ROOT]      ROOT: the source tree (this one by default)
set -u
src=$(cd "$(dirname "$0")/.." && pwd)
command -v clang-format > /dev/null || {
    echo "clang-format not installed: not run"
    exit 77
}
# the files of ROOT to check, one a line
files() {
    (cd "$1" && find host kernels tests bench docs/examples -type f \( -name '*.[ch]' -o -name '*.cpp' \) 2> /dev/null |
        sort)
}
# formats ROOT's files: 0 when all are as .clang-format says, else 1 with clang-format's lines
check() {
    local root=$1
    mapfile -t list < <(files "$root")
    [ ${#list[@]} -gt 0 ] || {
        echo "format: no C files under $root" >&2
        return 2
    }
    (cd "$root" && clang-format --dry-run -Werror "${list[@]}")
}
if [ $# -gt 0 ]; then
    check "$1"
    exit
fi
pass=0 fail=0
ok() { pass=$((pass + 1)); }
ko() {
    fail=$((fail + 1))
    echo "FAIL: $1" >&2
}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
if check "$src" 2> "$tmp/tree"; then ok; else
    ko "the tree is not as .clang-format says (clang-format -i FILE):"
    head -40 "$tmp/tree" >&2
fi
n=$(files "$src" | wc -l)
[ "$n" -ge 200 ] && ok || ko "only $n C files found"
# the check itself: a planted misformatted line fails and names its file
mkdir -p "$tmp/host/base"
cp "$src/.clang-format" "$tmp/"
cp "$src/host/base/pool.c" "$tmp/host/base/"
if check "$tmp" > /dev/null 2>&1; then ok; else ko "a copy of host/base/pool.c fails"; fi
printf 'int   planted (int x){return x ;}\n' >> "$tmp/host/base/pool.c"
check "$tmp" > /dev/null 2> "$tmp/err"
rc=$?
[ $rc -ne 0 ] && grep -q 'host/base/pool.c' "$tmp/err" && ok || ko "a planted misformatted line passes (rc $rc)"
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
