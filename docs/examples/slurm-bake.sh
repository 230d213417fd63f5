#!/usr/bin/env bash
# Bake one scene over many machines with a Slurm job array, then merge the bands.
#
#   sbatch --array=0-15 docs/examples/slurm-bake.sh scene.json 32768x16384 out/sky
#   # when the array is done (or: sbatch --dependency=afterok:JOBID --wrap "...merge...")
#   fractalbake merge out/sky.part*.exr -o out/sky.exr
#
# Each task renders the horizontal band SLURM_ARRAY_TASK_ID of SLURM_ARRAY_TASK_COUNT bands. The
# bands' pixels are those of a single-machine bake, so the merged file equals it byte for byte
# (same fractalbake build and device type on every node; across devices, within the tolerances
# of docs/usage.md). Bands split by rows cost no repeated work; columns would.
#SBATCH --job-name=fractalbake
#SBATCH --cpus-per-task=8
#SBATCH --mem=4G
set -euo pipefail
scene=$1 size=$2 prefix=$3 # size: the scene's size, WxH (or give --set size=WxH to all: the same)
task=${SLURM_ARRAY_TASK_ID:?run under sbatch --array}
count=${SLURM_ARRAY_TASK_COUNT:?}
width=${size%x*} height=${size#*x}
y0=$((height * task / count))
y1=$((height * (task + 1) / count))
mkdir -p "$(dirname "$prefix")"
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
fractalbake render "$scene" --set "size=$size" --region "0,$y0,$width,$((y1 - y0))" --threads "${SLURM_CPUS_PER_TASK:-1}" \
  --quiet -o "$prefix.part$(printf %04d "$task").exr"
