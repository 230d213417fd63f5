#!/usr/bin/env bash
# Bake one scene over a Slurm cluster: the tasks of `fractalbake plan` as a job array, then a merge
# job that depends on the array, checks that every task's file is there and joins them.
#
#   docs/examples/slurm-bake.sh [--wait] SCENE.json OUT.exr TASKS [SBATCH OPTIONS...]
#
#   docs/examples/slurm-bake.sh docs/examples/scene.json out/sky.exr 16 --partition=batch --mem=4G
#
# Run it where you run sbatch; it submits the jobs itself and prints their ids. Only `fractalbake`
# (from `cmake --install`, shaders embedded) and Slurm's commands must be on PATH, on every node;
# the scene's input files and OUT's folder must be on a file system every node sees.
#  - The plan says how many of the TASKS have work (fewer when more would cost more than they
#    save); only those are submitted, as array 0..M-1. Each array task bakes `render --task K/N`
#    with K from its place in the array (any --array form works when you submit the body yourself:
#    K = (SLURM_ARRAY_TASK_ID - SLURM_ARRAY_TASK_MIN) / SLURM_ARRAY_TASK_STEP).
#  - Threads: the cpus Slurm gives a task (SLURM_CPUS_PER_TASK, else the node's); ask for more
#    with --cpus-per-task=C among the SBATCH OPTIONS. Nothing is hard-coded, so a job never waits
#    for cpus a node lacks.
#  - The merge job runs after the whole array ends (afterany, not afterok: after a failed task an
#    afterok job never runs and never ends). `fractalbake merge` then names the tasks whose files
#    are missing and the job fails, its message in slurm-JOBID.out; --wait makes this script wait
#    for it and exit with its status.
#  - The task files are kept in OUT.parts/ (delete them once OUT is written).
#  - Everything it reads from the environment or the command line is checked before use: Slurm's
#    numbers must be plain decimal integers (never evaluated as shell arithmetic), TASKS an integer,
#    OUT a .exr path in a writable folder (made if missing), and the plan must succeed, before anything is
#    submitted; a bad value stops it with one line and exit 2.
set -euo pipefail
self=$(realpath "$0")
die() {
  echo "slurm-bake.sh: $*" >&2
  exit 2
}
# int NAME VALUE MIN: VALUE is a decimal integer >= MIN (digits only: nothing is evaluated)
int() {
  [[ $2 =~ ^[0-9]{1,9}$ ]] || die "$1: expected a non-negative integer, found \"$2\""
  (( 10#$2 >= $3 )) || die "$1: expected an integer >= $3, found $2"
  echo $((10#$2))
}
threads() { int SLURM_CPUS_PER_TASK "${SLURM_CPUS_PER_TASK:-${SLURM_CPUS_ON_NODE:-1}}" 1; }

case "${1:-}" in
--task) # the body of an array task: --task SCENE PARTS N
  [ $# -eq 4 ] || die "--task: expected SCENE PARTS N"
  scene=$2 parts=$3 n=$(int N "$4" 1)
  id=$(int SLURM_ARRAY_TASK_ID "${SLURM_ARRAY_TASK_ID:?not an array task}" 0)
  min=$(int SLURM_ARRAY_TASK_MIN "${SLURM_ARRAY_TASK_MIN:-0}" 0)
  step=$(int SLURM_ARRAY_TASK_STEP "${SLURM_ARRAY_TASK_STEP:-1}" 1)
  [ "$id" -ge "$min" ] || die "SLURM_ARRAY_TASK_ID $id is below SLURM_ARRAY_TASK_MIN $min"
  k=$(((id - min) / step))
  [ "$k" -lt "$n" ] || die "task $k (from SLURM_ARRAY_TASK_ID $id) is not below N $n"
  threads=$(threads)
  export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-${TMPDIR:-/tmp}}
  exec fractalbake render "$scene" --task "$k/$n" --threads "$threads" --quiet -o "$parts/task-$(printf %04d "$k").exr"
  ;;
--merge) # the body of the merge job: --merge PARTS OUT
  [ $# -eq 3 ] || die "--merge: expected PARTS OUT"
  parts=$2 out=$3
  threads=$(threads)
  exec fractalbake merge "$parts"/task-*.exr -o "$out" --threads "$threads"
  ;;
esac

wait_merge=
if [ "${1:-}" = --wait ]; then
  wait_merge=--wait
  shift
fi
if [ $# -lt 3 ]; then
  echo "usage: slurm-bake.sh [--wait] SCENE.json OUT.exr TASKS [SBATCH OPTIONS...]" >&2
  exit 2
fi
[ -f "$1" ] || die "$1: no such scene file"
n=$(int TASKS "$3" 1)
case "$2" in
*.exr) ;;
*) die "$2: the merged output is an OpenEXR file: name it OUT.exr" ;;
esac
scene=$(realpath "$1") out=$(realpath -m "$2")
mkdir -p "$(dirname "$out")" 2> /dev/null || die "$2: cannot make the folder $(dirname "$out")"
[ -w "$(dirname "$out")" ] || die "$2: folder $(dirname "$out") is not writable"
[ ! -e "$out" ] || [ -f "$out" ] || die "$2: exists and is not a regular file"
shift 3
parts=${out%.exr}.parts
plan=$(fractalbake plan "$scene" --tasks "$n" --json) || die "fractalbake plan failed (above)"
active=$(printf '%s\n' "$plan" | sed -n 's/^ *"active": \([0-9]*\),*$/\1/p')
active=$(int "the plan's active" "${active:-x}" 1)
mkdir -p "$parts"
rm -f "$parts"/task-*.exr
array=$(sbatch --parsable --job-name=fractalbake --array="0-$((active - 1))" --output="$parts/slurm-%A_%a.out" "$@" \
  "$self" --task "$scene" "$parts" "$n")
array=${array%%;*}
merge=$(sbatch --parsable $wait_merge --job-name=fractalbake-merge --dependency="afterany:$array" \
  --output="$parts/slurm-merge-%j.out" "$@" "$self" --merge "$parts" "$out") && status=0 || status=$?
echo "slurm-bake.sh: $active of $n tasks as array job $array; merge job ${merge%%;*} writes $out"
if [ -n "$wait_merge" ] && [ $status -ne 0 ]; then
  echo "slurm-bake.sh: the merge failed: $(tail -1 "$parts"/slurm-merge-*.out)" >&2
fi
exit $status
