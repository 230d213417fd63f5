#!/usr/bin/env bash
# The cost of a bake split over N tasks (fractalbake plan, render --task K/N, merge), against one
# bake of the same scene, in one run: every task of each N runs here one after another (as an array
# job's tasks would run on N machines), and their CPU seconds (user + system) are summed.
#
#   bench/split.sh [SIZE [N...]]     default: 2048x1024, N = 2 4 8 16 32 64
#   FB=build/fractalbake SCENE=docs/examples/scene.json bench/split.sh 8192x4096 2 8 64
#
# Prints a Markdown table: N, tasks with work, one bake's CPU (run just before the row's tasks), the
# tasks' CPU in all and relative to it, the merge's CPU, the longest task's wall time, and whether
# the merged file equals the one bake byte for byte.
set -euo pipefail
FB=$(realpath "${FB:-build/fractalbake}")
size=${1:-2048x1024}
shift || true
tasks=("$@")
[ ${#tasks[@]} -gt 0 ] || tasks=(2 4 8 16 32 64)
scene=()
[ -n "${SCENE:-}" ] && scene=("$(realpath "$SCENE")")
work=$(mktemp -d "${TMPDIR:-/tmp}/fb-split-XXXXXX")
trap 'rm -rf "$work"' EXIT
cp "$FB" "$work/fractalbake" # the binary measured, whatever happens to the build meanwhile
FB=$work/fractalbake
cd "$work"
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-$work}

# cpu CMD...: runs it; prints "CPU WALL" (seconds)
cpu() {
  /usr/bin/time -f "%U %S %e" -o t.txt "$@" > /dev/null
  awk '{ printf "%.3f %.3f\n", $1 + $2, $3 }' t.txt
}

read -r one one_wall < <(cpu "$FB" render "${scene[@]}" --set "size=$size" -o one.exr --quiet)
echo "scene: ${SCENE:-the default scene} at $size; one bake: $one s CPU, $one_wall s wall"
echo "(each row's one bake is run again just before its tasks: the machine's load drifts by 10% over minutes)"
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'); $(date -u +%F)"
echo
echo "| N | tasks with work | one bake CPU s | tasks' CPU s | / one bake | merge CPU s | (tasks + merge) / one | longest task wall s | model: longest task, CPU s | same bytes |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for n in "${tasks[@]}"; do
  rm -f part-*.exr merged.exr
  "$FB" plan "${scene[@]}" --set "size=$size" --tasks "$n" --json > plan.json
  active=$(python3 -c "import json; print(json.load(open('plan.json'))['active'])")
  longest_model=$(python3 -c "import json; print('%.2f' % json.load(open('plan.json'))['model_seconds']['longest'])")
  read -r one _ < <(cpu "$FB" render "${scene[@]}" --set "size=$size" -o one.exr --quiet)
  total=0 longest=0
  for ((k = 0; k < n; k++)); do
    read -r c w < <(cpu "$FB" render "${scene[@]}" --set "size=$size" --task "$k/$n" -o "part-$k.exr" --quiet)
    read -r total longest < <(awk -v t="$total" -v c="$c" -v l="$longest" -v w="$w" 'BEGIN { print t + c, (w > l ? w : l) }')
  done
  read -r m _ < <(cpu "$FB" merge part-*.exr -o merged.exr --quiet)
  same=no
  cmp -s one.exr merged.exr && same=yes
  awk -v n="$n" -v a="$active" -v t="$total" -v o="$one" -v m="$m" -v l="$longest" -v lm="$longest_model" -v s="$same" \
    'BEGIN { printf "| %d | %d | %.2f | %.2f | %.3f | %.2f | %.3f | %.2f | %s | %s |\n", n, a, o, t, t / o, m, (t + m) / o, l, lm, s }'
done
