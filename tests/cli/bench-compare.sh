#!/usr/bin/env bash
# scripts/bench-compare.sh on a tiny bench: HEAD built beside this build (the same commit: the two
# builds agree within the spread, no row flagged either way), five alternating rounds of the fBm
# bench on the native backend, a table row for every bench row with its ratio and spread, and the
# whole runs' wall and CPU seconds. Bad usage fails with one line. Not run (77) outside a git
# checkout, or where the sources differ from HEAD (the two builds would not be of one commit).
source "$(dirname "$0")/lib.sh"
cli_init "$@"
S=$ROOT/scripts/bench-compare.sh

if ! git -C "$ROOT" rev-parse --verify --quiet HEAD > /dev/null; then
  echo "not a git checkout: not run"
  exit 77
fi
if ! git -C "$ROOT" diff --quiet HEAD -- host kernels shaders bench/peers cmake include CMakeLists.txt; then
  echo "the sources differ from HEAD: not run"
  exit 77
fi

expect_usage() { # expect_usage PATTERN ARGS...: exit 2, one stderr line matching PATTERN
  local pat=$1
  shift
  "$S" "$@" > out.txt 2> err.txt
  local rc=$?
  check "bench-compare $* exits 2 ($rc)" test $rc -eq 2
  check "bench-compare $*: one line naming the problem ($(cat err.txt))" \
    sh -c "[ \$(wc -l < err.txt) -eq 1 ] && grep -q -- '$pat' err.txt"
}
expect_usage "usage: scripts/bench-compare.sh BASE"
expect_usage "no-such-commit is not a commit" no-such-commit
expect_usage "GENERATORS is a comma list" HEAD "fbm,,julia"
FB_COMPARE_ROUNDS=2 expect_usage "at least 3" HEAD fbm

export FB_BUILD_DIR
FB_BUILD_DIR=$(dirname "$FB")
FB_COMPARE_ROUNDS=5 FB_COMPARE_ARGS="--backend native --size 256x256" "$S" HEAD fbm > table.md 2> err.txt
check "bench-compare HEAD fbm runs ($(tail -3 err.txt))" test -s table.md
# the fBm bench's own rows, each once in the table
"$FB" bench --json --quiet --size 64x64 --generator fbm --backend native > rows.json 2> /dev/null
check "every bench row has its ratio and spread; the same commit: none flagged" python3 -c "
import json, re, sys
want = [(r['generator'], r['backend'], r['mode'], str(r['threads']), r['unit']) for r in map(json.loads, open('rows.json'))]
table = open('table.md').read()
got = {}
for line in table.splitlines():
    c = [x.strip() for x in line.strip('|').split('|')]
    if len(c) == 10 and re.fullmatch(r'[0-9.]+', c[7]):
        got[tuple(c[:5])] = (float(c[7]), float(c[8]), c[9])
assert sorted(got) == sorted(want), (sorted(got), sorted(want))
for k, (ratio, spread, flag) in got.items():
    assert ratio > 0 and spread >= 0, (k, ratio, spread)
    assert flag == '' and abs(ratio - 1) <= spread, ('the same commit flagged', k, ratio, spread, flag)
assert '5 alternating rounds' in table and '0 rows slower beyond the spread' in table, table
assert re.search(r'\| CPU seconds \(user \+ system\) \| [0-9.]+ \| [0-9.]+ \|', table), table
assert re.search(r'\| wall seconds \| [0-9.]+ \| [0-9.]+ \|', table), table
"
check "BASE's worktree is gone" sh -c "! git -C '$ROOT' worktree list | grep -q fb-compare-"
cli_finish
