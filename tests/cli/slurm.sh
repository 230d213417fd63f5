#!/usr/bin/env bash
# The Slurm recipe (docs/examples/slurm-bake.sh) on a real Slurm: munged, slurmctld and slurmd
# started here on localhost (tests/slurm/slurm.conf.in), the recipe submits the plan's tasks as a
# job array and a dependent merge; the merged file equals the one-command bake byte for byte. Then
# one array task is cancelled, and the merge job fails naming it.
# First, without Slurm, the recipe's input checks: values from the environment that would run code or
# divide by zero, and outputs its merge could not write, stop it before anything is submitted.
# Returns 77 (the cluster part not run) where slurm-wlm is not installed or this is not root (slurmd
# runs as root), after the checks above passed (1 where one failed).
# Usage: slurm.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
recipe=$ROOT/docs/examples/slurm-bake.sh

# ---- the recipe's inputs, without Slurm: nothing from the environment is evaluated, bad values stop
# it (exit 2, one line) before it bakes or submits anything. A fake sbatch records any submission.
mkdir -p fake
printf '#!/bin/sh\necho "$@" >> %s/submitted\necho 1\n' "$T" > fake/sbatch
chmod +x fake/sbatch
printf '#!/bin/sh\necho "$@" >> %s/baked\n' "$T" > fake/fractalbake
chmod +x fake/fractalbake
"$FB" scene default --set size=256x128 > inj.json
inject() { # inject DESCRIPTION ENV... -- ARGS: exit 2, one stderr line, nothing run, no file made
  local what=$1
  shift
  local envs=()
  while [ "$1" != -- ]; do envs+=("$1"); shift; done
  shift
  rm -f touched submitted baked
  env PATH="$T/fake:$PATH" "${envs[@]}" bash "$recipe" "$@" > inj.out 2> inj.err
  local rc=$?
  check "$what: exit $rc, wanted 2 ($(cat inj.err))" test $rc -eq 2
  check "$what: one stderr line" test "$(wc -l < inj.err)" -eq 1
  check "$what: no command run from the environment" test ! -e touched
  check "$what: nothing baked or submitted" test ! -e submitted -a ! -e baked
}
inject "SLURM_ARRAY_TASK_ID running a command" 'SLURM_ARRAY_TASK_ID=BASH_VERSINFO[$(touch touched)]' -- --task inj.json parts 4
inject "SLURM_ARRAY_TASK_MIN running a command" SLURM_ARRAY_TASK_ID=1 'SLURM_ARRAY_TASK_MIN=a[$(touch touched)]' -- --task inj.json parts 4
inject "SLURM_ARRAY_TASK_STEP running a command" SLURM_ARRAY_TASK_ID=1 'SLURM_ARRAY_TASK_STEP=x[$(touch touched)]' -- --task inj.json parts 4
inject "SLURM_ARRAY_TASK_STEP=0" SLURM_ARRAY_TASK_ID=1 SLURM_ARRAY_TASK_STEP=0 -- --task inj.json parts 4
inject "SLURM_ARRAY_TASK_ID=-1" SLURM_ARRAY_TASK_ID=-1 -- --task inj.json parts 4
inject "a task beyond N" SLURM_ARRAY_TASK_ID=9 -- --task inj.json parts 4
inject "SLURM_CPUS_PER_TASK running a command" SLURM_ARRAY_TASK_ID=1 'SLURM_CPUS_PER_TASK=$(touch touched)' -- --task inj.json parts 4
inject "TASKS not an integer" -- inj.json out/x.exr '4$(touch touched)'
inject "TASKS=0" -- inj.json out/x.exr 0
inject "an output named .png" -- inj.json OUT.png 4
echo plain > afile
inject "an output in a folder that cannot be made" -- inj.json afile/x.exr 4
inject "a missing scene" -- missing.json x.exr 4
# a good task runs fractalbake with the task's number and the threads Slurm gives it
rm -f baked
env PATH="$T/fake:$PATH" SLURM_ARRAY_TASK_ID=7 SLURM_ARRAY_TASK_MIN=3 SLURM_ARRAY_TASK_STEP=2 SLURM_CPUS_PER_TASK=3 \
  bash "$recipe" --task inj.json parts 4
check "a task's K is (ID - MIN) / STEP: $(cat baked 2> /dev/null)" grep -q -- "--task 2/4 --threads 3 --quiet -o parts/task-0002.exr" baked

for c in munged mungekey slurmctld slurmd sbatch scontrol sinfo; do
  command -v $c > /dev/null || {
    echo "no $c (Debian: slurm-wlm): the Slurm cluster part not run"
    [ "$fail" -eq 0 ] || cli_finish
    exit 77
  }
done
[ "$(id -u)" -eq 0 ] || {
  echo "not root (slurmd runs jobs as root here): the Slurm cluster part not run"
  [ "$fail" -eq 0 ] || cli_finish
  exit 77
}
require_vulkan

D=$T/slurm
mkdir -p "$D/state" "$D/spool"
stop() {
  scontrol shutdown > /dev/null 2>&1
  for p in slurmd slurmctld munged; do [ -s "$D/$p.pid" ] && kill "$(cat "$D/$p.pid")" 2> /dev/null; done
  sleep 1
  rm -rf "$T"
}
trap stop EXIT
port=$((20000 + $$ % 20000))
sed -e "s|@HOST@|$(hostname -s)|g; s|@CPUS@|$(nproc)|g; s|@DIR@|$D|g; s|@PORT@|$port|; s|@DPORT@|$((port + 1))|" \
  "$ROOT/tests/slurm/slurm.conf.in" > "$D/slurm.conf"
export SLURM_CONF=$D/slurm.conf
mungekey --create --keyfile="$D/munge.key" && chmod 600 "$D/munge.key"
munged --socket="$D/munge.socket" --key-file="$D/munge.key" --pid-file="$D/munged.pid" --log-file="$D/munged.log" \
  --seed-file="$D/munge.seed" --force || bad "munged did not start"
slurmctld -c -i || bad "slurmctld did not start: $(tail -3 "$D/slurmctld.log")"
slurmd || bad "slurmd did not start: $(tail -3 "$D/slurmd.log")"
for _ in $(seq 60); do
  sinfo -h -o %t 2> /dev/null | grep -q idle && break
  sleep 0.5
done
check "the one-node Slurm is up" sh -c 'sinfo -h -o %t | grep -q idle'

# the recipe needs only `fractalbake` on PATH (what `cmake --install` puts there)
export PATH=$(dirname "$FB"):$PATH
"$FB" scene default --set size=1024x512 > scene.json
"$FB" plan scene.json --tasks 4 --json > plan.json
active=$(python3 -c "import json; print(json.load(open('plan.json'))['active'])")
check "the plan gives the 1024 x 512 default scene to 2 or more of 4 tasks" test "$active" -ge 2
if bash "$recipe" --wait scene.json out/sky.exr 4 > submit.txt 2> submit.err; then ok; else bad "the recipe failed: $(cat submit.txt submit.err out/sky.parts/*.out 2> /dev/null)"; fi
check "the recipe says what it submitted" grep -q "^slurm-bake.sh: $active of 4 tasks as array job [0-9]*; merge job [0-9]* writes $T/out/sky.exr" submit.txt
check "each task wrote its file" test "$(ls out/sky.parts/task-*.exr | wc -l)" -eq "$active"
"$FB" render scene.json -o one.exr --quiet
if cmp -s one.exr out/sky.exr; then ok; else bad "the Slurm bake differs from the one-command bake"; fi

# a cancelled task: the jobs are submitted held, one array task is cancelled, the rest released;
# the merge job (afterany) runs, fails, and its output names the missing task
bash "$recipe" scene.json out/cut.exr 4 --hold > submit2.txt 2>&1 || bad "the held submission failed: $(cat submit2.txt)"
array=$(sed -n 's/.* array job \([0-9]*\);.*/\1/p' submit2.txt) merge=$(sed -n 's/.* merge job \([0-9]*\) .*/\1/p' submit2.txt)
scancel "${array}_1" && scontrol release "$array" && scontrol release "$merge" || bad "cancel/release failed"
for _ in $(seq 240); do
  state=$(scontrol show job "$merge" 2> /dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p')
  case "$state" in COMPLETED | FAILED | CANCELLED | TIMEOUT) break ;; esac
  sleep 0.5
done
check "the merge job ran and failed (state $state)" test "$state" = FAILED
check "no merged file after a failed task" test ! -e out/cut.exr
check "the merge names the cancelled task" grep -q "merge: 1 of the plan's $active tasks is missing: task 1 (" out/cut.parts/slurm-merge-*.out

cli_finish
