#!/usr/bin/env bash
# Splitting a bake over N tasks: fractalbake plan, render --task K/N and merge. Every kind of split
# (bands, points parts, whole layers, and their mixes) merges to the one-command bake byte for byte,
# on both backends and in single- and multi-part files; the plan's shares tile the work exactly
# once; merge names the tasks a set lacks.
# Needs a Vulkan device (lavapipe at least). Usage: tasks.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
require_vulkan

# A plan's JSON: tasks numbered 0..active-1, at most N; the bands tile the rows [0, H) in order;
# every layer is computed by the tasks exactly once (bands: all of them; points parts: 1..P, each
# once; whole: one task); the model's total within 10% of one bake (or one task).
plan_ok() { # FILE N H
  python3 - "$@" << 'PY'
import json, sys
p = json.load(open(sys.argv[1])); N, H = int(sys.argv[2]), int(sys.argv[3])
t = p['task_list']; names = [l['name'] for l in p['layers']]
assert p['tasks'] == N and 1 <= p['active'] == len(t) <= N, 'task count'
assert [x['task'] for x in t] == list(range(len(t))), 'numbering'
bands = [x for x in t if 'rows' in x]
y = 0
for b in bands:
    assert b['rows'][0] == y and b['rows'][1] > y, 'bands do not tile: %s' % b['rows']
    y = b['rows'][1]
assert not bands or y == H, 'bands end at %d, not %d' % (y, H)
assert len(bands) == p['bands']
for n in names:
    holders = [x for x in t if n in x['layers']]
    split = [l['split'] for l in p['layers'] if l['name'] == n][0]
    if split == 'bands':
        assert holders == bands, n
    elif split == 'points parts':
        parts = sorted(x['points_part'][0] for x in holders if n in x.get('points_layers', []))
        assert parts == list(range(1, p['points_parts'] + 1)) and len(holders) == len(parts), n
    else:
        assert len(holders) == 1 and n not in holders[0].get('points_layers', []), n
m = p['model_seconds']
assert abs(sum(x['seconds'] for x in t) - m['split']) < 1e-6 * m['split'] + 1e-9
assert m['split'] <= 1.10 * m['one_bake'] + 1e-9 or len(t) == 1, 'over budget: %s' % m
assert abs(max(x['seconds'] for x in t) - m['longest']) < 1e-9 + 1e-9 * m['longest']
PY
}

# bake SCENE's N tasks (ARGS after the scene) into dir tN, merge, compare with the one-command bake
split_ok() { # LABEL N SCENE ARGS...
  local label=$1 n=$2 scene=$3
  shift 3
  rm -rf t && mkdir t
  "$FB" render $scene "$@" -o whole.exr --quiet || { bad "$label: the whole bake failed"; return; }
  for ((k = 0; k < n; k++)); do
    "$FB" render $scene "$@" --task-startup 0 --task $k/$n -o t/part-$k.exr --quiet || bad "$label: task $k/$n failed"
  done
  if "$FB" merge t/part-*.exr -o merged.exr --quiet && cmp -s whole.exr merged.exr; then ok; else bad "$label: $n tasks do not merge to the whole bake"; fi
}

# ---- plan ----
"$FB" plan --tasks 8 --set size=2048x1024 --json > p8.json && plan_ok p8.json 8 1024 && ok || bad "the default scene's plan for 8 tasks"
"$FB" plan --tasks 8 --set size=2048x1024 --json > p8b.json && cmp -s p8.json p8b.json && ok || bad "the plan is not deterministic"
check "the default sky is banded, terrain whole" python3 -c "
import json; p = json.load(open('p8.json')); s = {l['name']: l['split'] for l in p['layers']}
assert s['sky'] == 'bands' and s['terrain'] == 'whole', s; assert p['active'] >= 2"
for n in 1 2 3 5 16 64; do
  "$FB" plan --tasks $n --set size=1024x512 --json > pn.json && plan_ok pn.json $n 512 && ok || bad "default scene plan, $n tasks"
  "$FB" plan --tasks $n --task-startup 0 --set size=384x192 --set layers.plants.points=300000000 --json > pz.json && plan_ok pz.json $n 192 && ok || bad "no-start-up plan, $n tasks"
done
# with no start-up, 16 tasks are all used and the chaos game (300 M points) is split by points
"$FB" plan --tasks 16 --task-startup 0 --set size=384x192 --set layers.plants.points=300000000 --json > p16.json
check "the plants split by points when it pays" python3 -c "
import json; p = json.load(open('p16.json')); assert p['active'] == 16 and p['points_parts'] >= 2, (p['active'], p['points_parts'])"
"$FB" plan --tasks 4 --set size=2048x1024 > plan.txt
check "the text plan names tasks from 0 and the model's totals" grep -q "^0  *rows 0-" plan.txt
check "the text plan's summary line" grep -q "^one bake .* s; the [0-9]* tasks .* in all (1\.[01][0-9]x)" plan.txt
# a layer writing a heightmap is computed whole by one task, which writes the heightmap
printf '{"size": [160, 96], "layers": [{"type": "fbm", "name": "hills", "octaves": 6, "heightmap": "hills.png"}, {"type": "fbm", "name": "clouds", "octaves": 4}]}' > hm.json
"$FB" plan hm.json --tasks 3 --task-startup 0 --json > phm.json && plan_ok phm.json 3 96 && ok || bad "heightmap plan"
check "a heightmap layer is whole" python3 -c "
import json; p = json.load(open('phm.json')); s = {l['name']: l['split'] for l in p['layers']}; assert s == {'hills': 'whole', 'clouds': 'bands'}, s"

# ---- every kind of split merges to the one-command bake, byte for byte ----
D="--set size=256x128 --set layers.plants.points=200000000 --set layers.terrain.insert=3000"
for be in native vulkan; do
  for n in 2 3 7; do split_ok "default scene, $be" $n "" $D --backend $be; done
  split_ok "default scene, per-layer parts, $be" 5 "" $D --set parts=per-layer --backend $be
done
split_ok "default scene, auto" 6 "" $D
printf '{"size": [120, 72], "seed": 3, "layers": [{"type": "fbm", "name": "height", "octaves": 7},
 {"type": "fbm", "name": "clouds", "noise": "value", "warp": 1.5, "half": true},
 {"type": "op", "name": "snow", "op": "threshold", "inputs": ["height"], "level": 0.3, "width": 0.2},
 {"type": "ifs", "name": "fern", "points": 30000000},
 {"type": "op", "name": "lowfern", "op": "multiply", "inputs": ["fern.A", "snow"]}]}' > ops.json
split_ok "ops using a chaos game (whole)" 4 ops.json
"$FB" plan ops.json --tasks 4 --task-startup 0 --json > pops.json && plan_ok pops.json 4 72 && ok || bad "ops plan"
check "an op using a chaos game keeps it whole, with its sources" python3 -c "
import json; p = json.load(open('pops.json')); s = {l['name']: l['split'] for l in p['layers']}
assert s['fern'] == s['lowfern'] == s['snow'] == s['height'] == 'whole' and s['clouds'] == 'bands', s"
rm -f hills.png
split_ok "a heightmap layer" 3 hm.json
check "the heightmap task wrote hills.png, the same as the whole bake's" test -s hills.png
cp hills.png hills_split.png && "$FB" render hm.json -o hm_whole.exr --quiet && cmp -s hills.png hills_split.png && ok || bad "the split's heightmap differs"

# ---- an idle task writes nothing; --json says so ----
"$FB" render --set size=64x32 --task 5/8 -o idle.exr 2> idle.txt
check "an idle task exits 0 and writes no file" test ! -e idle.exr
check "an idle task says why" grep -q "task 5/8 has nothing to do: the plan gives this bake to tasks 0-" idle.txt
"$FB" render --set size=64x32 --task 5/8 -o idle.exr --json > idle.json
check "an idle task's --json" python3 -c "
import json; j = json.load(open('idle.json')); assert j['task'] == {'index': 5, 'of': 8, 'idle': True}, j"
"$FB" render $D --task-startup 0 --task 1/3 -o t1.exr --json > t1.json
check "a task's --json names its share" python3 -c "
import json; j = json.load(open('t1.json')); assert j['task']['index'] == 1 and j['task']['of'] == 3 and j['task']['share'], j"

# ---- merge checks the set ----
rm -rf t && mkdir t
for k in 0 1 2 3 4; do "$FB" render $D --task-startup 0 --task $k/5 -o t/p$k.exr --quiet; done
"$FB" plan $D --task-startup 0 --tasks 5 > p5.txt
share() { awk -v k=$1 '$1 == k { $1 = ""; $NF = ""; sub(/^ +/, ""); sub(/ +$/, ""); print }' p5.txt; }
expect_fail 2 "merge: 2 of the plan's 5 tasks are missing: task 1 ($(share 1)), task 3 ($(share 3))$" o.exr -- merge t/p0.exr t/p2.exr t/p4.exr -o o.exr
expect_fail 2 "t/p2.exr and t/p2.exr are both task 2/5" o.exr -- merge t/p0.exr t/p1.exr t/p2.exr t/p2.exr t/p3.exr t/p4.exr -o o.exr
"$FB" render $D --task-startup 0 --task 0/4 -o other.exr --quiet
expect_fail 2 "a task of another plan than t/p0.exr" o.exr -- merge t/p0.exr other.exr -o o.exr
"$FB" render $D --set seed=9 --task-startup 0 --task 1/5 -o seed9.exr --quiet
expect_fail 2 "baked from another scene than t/p0.exr" o.exr -- merge t/p0.exr seed9.exr -o o.exr
"$FB" render $D --region 0,0,256,64 -o region.exr --quiet
expect_fail 2 "1 of the 2 files are task files (render --task), the others not: merge one kind at a time" o.exr -- merge t/p0.exr region.exr -o o.exr

# --from a task's file bakes that task again (its plan's start-up too): the same bytes
"$FB" render --from t/p1.exr -o again.exr --quiet && cmp -s t/p1.exr again.exr && ok || bad "render --from a task file is not that task"

# ---- bad flags: one line, exit 2, no file ----
expect_fail 2 "--task: expected K/N with 0 <= K < N <= 1024 (K counts from 0, like SLURM_ARRAY_TASK_ID), found \"3/3\"" o.exr -- render --task 3/3 -o o.exr
expect_fail 2 "--task: expected K/N" o.exr -- render --task 1/0 -o o.exr
expect_fail 2 "--task: expected K/N" o.exr -- render --task -1/4 -o o.exr
expect_fail 2 "--task: expected K/N" o.exr -- render --task x -o o.exr
expect_fail 2 "--task: not with --region" o.exr -- render --task 0/2 --region 0,0,8,8 -o o.exr
expect_fail 2 "--task: not with --preview" o.exr -- render --task 0/2 --preview o.png -o o.exr
expect_fail 2 "--task-startup: only with --task K/N" o.exr -- render --task-startup 0 -o o.exr
expect_fail 2 "--task-startup: expected seconds in 0..3600, found \"nan\"" o.exr -- render --task 0/2 --task-startup nan -o o.exr
expect_fail 2 "plan: --tasks N is required" o.exr -- plan
expect_fail 2 "--tasks: expected an integer in 1..1024, found \"0\"" o.exr -- plan --tasks 0
expect_fail 2 "--tasks: expected an integer in 1..1024, found \"2000\"" o.exr -- plan --tasks 2000

cli_finish
