#!/usr/bin/env bash
# Runs every benchmark once and appends the machine-readable lines, with date and machine, to
# bench/results.jsonl. Usage: bench/run.sh [--size WxH]
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
machine="$(lscpu | sed -n 's/^Model name: *//p' | head -1), $(nproc) cores"
./build/fractalbake bench --json "$@" | while read -r line; do
  echo "{\"date\": \"$(date -u +%Y-%m-%d)\", \"machine\": \"$machine\", \"result\": $line}"
done | tee -a bench/results.jsonl
