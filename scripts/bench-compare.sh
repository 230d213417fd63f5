#!/usr/bin/env bash
# A change's speed against an earlier commit: BASE is built beside the working tree (a detached git
# worktree and its build folder under a temporary folder, compiled through ccache where the
# environment sets it up, as scripts/setup.sh does), then `fractalbake bench --json` of BASE and of
# the working tree's build run alternately, ROUNDS rounds (BASE first in odd rounds, the working
# tree first in even ones, so that a load that drifts weighs on both alike). It prints, as a
# Markdown table to paste into bench/RESULTS.md: each row's median rate in both builds, their ratio
# (working tree / BASE, above 1 faster) and its spread (the two builds' own ranges, max - min over
# the median, added), flagging SLOWER a row whose ratio is below 1 by more than its spread (FASTER
# above); then each build's whole runs, median wall and CPU seconds (user + system) and their
# ratio, the load (uptime) before and after, and the machine.
#
# Usage: scripts/bench-compare.sh BASE [GENERATORS]
#   BASE        a commit (hash, tag, branch, HEAD~1)
#   GENERATORS  a comma list (julia,stars): one bench per generator; default every generator
# Environment:
#   FB_COMPARE_ROUNDS  rounds (default 3, at least 3)
#   FB_COMPARE_ARGS    more arguments of every bench (default none): "--backend native --size 1024x1024"
#   FB_BUILD_DIR       the working tree's build folder (default build), rebuilt first
#   FB_CMAKE_ARGS      configure arguments for BASE's build (default: the working tree build's
#                      compiler launcher, ccache where it has one)
#   TMPDIR             where BASE's worktree and build go (removed at the end)
# Exit status: 0, also when rows are flagged (the table says so); 2 on bad usage; 1 on a failure.
set -euo pipefail
usage() {
  echo "usage: scripts/bench-compare.sh BASE [GENERATORS] (see the script's head)" >&2
  exit 2
}
[ $# -ge 1 ] && [ $# -le 2 ] || usage
ROOT=$(cd "$(dirname "$0")/.." && pwd)
ROUNDS=${FB_COMPARE_ROUNDS:-3}
case $ROUNDS in '' | *[!0-9]*) echo "bench-compare: FB_COMPARE_ROUNDS must be a number, not \"$ROUNDS\"" >&2 && exit 2 ;; esac
[ "$ROUNDS" -ge 3 ] || { echo "bench-compare: FB_COMPARE_ROUNDS must be at least 3 (a spread needs rounds)" >&2 && exit 2; }
BASE=$(git -C "$ROOT" rev-parse --verify --quiet "$1^{commit}") || {
  echo "bench-compare: $1 is not a commit of $ROOT" >&2
  exit 2
}
GENS=${2:-}
if [ -n "$GENS" ]; then
  case $GENS in *[!a-z0-9,]* | ,* | *, | *,,*) echo "bench-compare: GENERATORS is a comma list of names, not \"$GENS\"" >&2 && exit 2 ;; esac
fi
BUILD=$(cd "$ROOT" && realpath -m "${FB_BUILD_DIR:-build}")
[ -f "$BUILD/CMakeCache.txt" ] || { echo "bench-compare: no build in $BUILD (run scripts/setup.sh)" >&2 && exit 1; }

T=$(mktemp -d "${TMPDIR:-/tmp}/fb-compare-XXXXXX")
cleanup() {
  git -C "$ROOT" worktree remove --force "$T/base" > /dev/null 2>&1 || true
  rm -rf "$T"
}
trap cleanup EXIT

echo "bench-compare: building the working tree ($BUILD) and ${BASE:0:10} ($T/base)" >&2
cmake --build "$BUILD" -j"$(nproc)" --target fractalbake > "$T/build-head.log" 2>&1 || {
  tail -20 "$T/build-head.log" >&2
  exit 1
}
git -C "$ROOT" worktree add --detach --quiet "$T/base" "$BASE"
# without FB_CMAKE_ARGS, the working tree build's compiler launcher (ccache) builds BASE too
if [ -z "${FB_CMAKE_ARGS+set}" ]; then
  L=$(sed -n 's/^CMAKE_C_COMPILER_LAUNCHER:[A-Z]*=//p' "$BUILD/CMakeCache.txt")
  [ -n "$L" ] && FB_CMAKE_ARGS="-DCMAKE_C_COMPILER_LAUNCHER=$L -DCMAKE_CXX_COMPILER_LAUNCHER=$L"
fi
# shellcheck disable=SC2086 # FB_CMAKE_ARGS is a list of arguments
{ cmake -S "$T/base" -B "$T/base-build" -DCMAKE_BUILD_TYPE=RelWithDebInfo ${FB_CMAKE_ARGS:-} &&
  cmake --build "$T/base-build" -j"$(nproc)" --target fractalbake; } > "$T/build-base.log" 2>&1 || {
  tail -20 "$T/build-base.log" >&2
  exit 1
}

# run SIDE ROUND: every generator's bench of one build, its JSON lines and its times
run() {
  local side=$1 round=$2 fb
  fb=$([ "$side" = base ] && echo "$T/base-build/fractalbake" || echo "$BUILD/fractalbake")
  local gens=() g
  if [ -n "$GENS" ]; then IFS=, read -r -a gens <<< "$GENS"; else gens=(""); fi
  for g in "${gens[@]}"; do
    # shellcheck disable=SC2086 # FB_COMPARE_ARGS is a list of arguments
    /usr/bin/time -f "%e %U %S" -o "$T/time" "$fb" bench --json --quiet ${g:+--generator "$g"} ${FB_COMPARE_ARGS:-} \
      >> "$T/$side-$round.json" 2> "$T/err" || {
      cat "$T/err" >&2
      exit 1
    }
    echo "$side $round $(cat "$T/time")" >> "$T/times"
  done
}

LOAD0=$(uptime)
for r in $(seq 1 "$ROUNDS"); do
  echo "bench-compare: round $r of $ROUNDS" >&2
  if [ $((r % 2)) = 1 ]; then run base "$r" && run head "$r"; else run head "$r" && run base "$r"; fi
done
LOAD1=$(uptime)

python3 - "$T" "$ROUNDS" "$BASE" "$(git -C "$ROOT" rev-parse HEAD)" "$(git -C "$ROOT" status --porcelain --untracked-files=no | wc -l)" \
  "$GENS" "${FB_COMPARE_ARGS:-}" "$LOAD0" "$LOAD1" << 'EOF'
import json, os, statistics, subprocess, sys
T, rounds, base, head, dirty, gens, args, load0, load1 = sys.argv[1:]
rounds = int(rounds)

def rows(side, r):
    out = {}
    for line in open(os.path.join(T, f"{side}-{r}.json")):
        o = json.loads(line)
        key = (o["generator"], o["backend"], o.get("device", ""), o["mode"], o.get("threads", 0), o["unit"])
        n = 2
        while key in out:  # a repeated row (the same mode twice): numbered
            key = key[:3] + (f'{o["mode"]} #{n}',) + key[4:]
            n += 1
        out[key] = o["rate"]
    return out

runs = {s: [rows(s, r) for r in range(1, rounds + 1)] for s in ("base", "head")}
order = list(runs["base"][0])
for k in runs["head"][0]:
    if k not in order:
        order.append(k)

def spread(v):
    m = statistics.median(v)
    return (max(v) - min(v)) / m if m > 0 else 0.0

cpu = subprocess.run(["sh", "-c", "grep -m1 'model name' /proc/cpuinfo | cut -d: -f2"], capture_output=True, text=True).stdout.strip()
print(f"bench-compare: {base[:10]} (base) against {head[:10]}{' + uncommitted changes' if int(dirty) else ''} (head), "
      f"{rounds} alternating rounds; generators: {gens or 'all'}; arguments: {args or 'none'}")
print(f"machine: {cpu}, {os.cpu_count()} cores; load before: {load0.split('load average:')[-1].strip()}, "
      f"after: {load1.split('load average:')[-1].strip()}")
print()
print("| generator | backend | mode | threads | unit | base | head | head/base | spread | |")
print("|---|---|---|---|---|---|---|---|---|---|")
flagged = 0
for k in order:
    b = [x[k] for x in runs["base"] if k in x]
    h = [x[k] for x in runs["head"] if k in x]
    gen, backend, device, mode, threads, unit = k
    if len(b) < rounds or len(h) < rounds or min(b + h) <= 0:
        side = "head only" if not b else "base only" if not h else "missing in a round"
        print(f"| {gen} | {backend} | {mode} | {threads} | {unit} | {statistics.median(b) if b else '-'} | "
              f"{statistics.median(h) if h else '-'} | - | - | {side} |")
        continue
    mb, mh = statistics.median(b), statistics.median(h)
    ratio, s = mh / mb, spread(b) + spread(h)
    flag = "SLOWER" if ratio < 1 - s else "FASTER" if ratio > 1 + s else ""
    flagged += flag == "SLOWER"
    print(f"| {gen} | {backend} | {mode} | {threads} | {unit} | {mb:.4g} | {mh:.4g} | {ratio:.3f} | {s:.3f} | {flag} |")
print()
t = {"base": [], "head": []}
for line in open(os.path.join(T, "times")):
    side, r, wall, user, sys_ = line.split()
    t[side].append((float(wall), float(user) + float(sys_)))
nb = len(t["base"]) // rounds
def per_round(side):  # a round's seconds, all its generators' benches together
    v = t[side]
    return [tuple(sum(x[i] for x in v[j * nb:(j + 1) * nb]) for i in (0, 1)) for j in range(rounds)]
pb, ph = per_round("base"), per_round("head")
print("| whole runs (seconds: head/base above 1 is slower) | base | head | head/base | spread |")
print("|---|---|---|---|---|")
for i, what in ((0, "wall seconds"), (1, "CPU seconds (user + system)")):
    b, h = [x[i] for x in pb], [x[i] for x in ph]
    print(f"| {what} | {statistics.median(b):.2f} | {statistics.median(h):.2f} | "
          f"{statistics.median(h) / statistics.median(b):.3f} | {spread(b) + spread(h):.3f} |")
print()
print(f"{flagged} row{'s' if flagged != 1 else ''} slower beyond the spread")
EOF
