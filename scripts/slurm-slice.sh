#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Slices one print on a Slurm cluster: a job array with one task per layer range (texfab slice
# --shard I/N, I = $SLURM_ARRAY_TASK_ID), then a job that runs after all of them succeeded and
# merges the shards (texfab merge-slices) into the folder a single run writes, byte for byte.
#
#   scripts/slurm-slice.sh [options] MODEL OUTPUT [texfab slice options ...]
#
# Options (before MODEL):
#   --tasks N          array tasks (layer ranges); default 8
#   --cpus C           CPUs per task, passed to texfab as --threads; default 2
#   --texfab PATH      the texfab binary the nodes run; default: texfab on PATH
#   --wait             block until the merge has finished; exit non-zero if any task failed
#   --sbatch "ARGS"    extra sbatch arguments for every job (partition, account, time, ...)
# The shards go to OUTPUT.parts/ (removed after a successful merge); logs to OUTPUT.logs/.
# Everything must be on a file system the nodes share. Example:
#   scripts/slurm-slice.sh --tasks 32 --cpus 4 bunny.obj bunny-slices -e marble.png --height 120
set -euo pipefail

tasks=8
cpus=2
texfab=$(command -v texfab || true)
wait=()
extra=()
while [ $# -gt 0 ]; do
  case "$1" in
    --tasks) tasks=$2; shift 2 ;;
    --cpus) cpus=$2; shift 2 ;;
    --texfab) texfab=$2; shift 2 ;;
    --wait) wait=(--wait); shift ;;
    --sbatch) read -r -a extra <<< "$2"; shift 2 ;;
    -h|--help) sed -n '3,18p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) break ;;
  esac
done
if [ $# -lt 2 ]; then
  echo "slurm-slice: usage: $0 [--tasks N] [--cpus C] [--texfab PATH] [--wait] MODEL OUTPUT [slice options]" >&2
  exit 1
fi
[[ "$tasks" =~ ^[1-9][0-9]*$ ]] || { echo "slurm-slice: --tasks must be a positive integer" >&2; exit 1; }
[[ "$cpus" =~ ^[1-9][0-9]*$ ]] || { echo "slurm-slice: --cpus must be a positive integer" >&2; exit 1; }
[ -x "$texfab" ] || { echo "slurm-slice: texfab not found (give --texfab PATH)" >&2; exit 1; }
command -v sbatch > /dev/null || { echo "slurm-slice: sbatch not found (is Slurm installed?)" >&2; exit 1; }

model=$(realpath "$1")
output=$(realpath -m "$2")
shift 2
texfab=$(realpath "$texfab")
parts="$output.parts"
logs="$output.logs"
if [ -e "$output" ] && [ -n "$(ls -A "$output" 2> /dev/null)" ]; then
  echo "slurm-slice: $output exists and is not empty" >&2
  exit 2
fi
rm -rf "$parts"
mkdir -p "$parts" "$logs"

# The task's command, quoted once here; $SLURM_ARRAY_TASK_ID is expanded on the node.
slice=$(printf '%q ' "$texfab" slice "$model" "$@" --threads "$cpus" -q)
shard="$slice -o $(printf '%q' "$parts")/part_\$SLURM_ARRAY_TASK_ID --shard \$SLURM_ARRAY_TASK_ID/$tasks"
array=$(sbatch --parsable "${extra[@]}" --job-name=texfab-slice --array="0-$((tasks - 1))" \
  --cpus-per-task="$cpus" --output="$logs/slice_%a.log" --wrap "$shard")
array=${array%%;*}
merge=$(printf '%q ' "$texfab" merge-slices)"$(printf '%q' "$parts")/part_* -o $(printf '%q' "$output") && rm -rf $(printf '%q' "$parts")"
job=$(sbatch --parsable "${extra[@]}" "${wait[@]}" --job-name=texfab-merge --dependency="afterok:$array" \
  --kill-on-invalid-dep=yes --output="$logs/merge.log" --wrap "$merge")
echo "slurm-slice: array job ${array} ($tasks tasks), merge job ${job%%;*}: $output"
