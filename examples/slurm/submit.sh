#!/bin/bash
# Runs a qdmr study on a Slurm cluster: a job array of SHARDS tasks (study.sbatch), then the merge and the report
# (merge.sbatch) once every task succeeded. Prints the two job ids.
#   examples/slurm/submit.sh SPEC RESULTS SHARDS [sbatch options...]
#   examples/slurm/submit.sh studies/extremes.json /shared/results/extremes 8 --partition=cpu
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
[ $# -ge 3 ] || { echo "usage: submit.sh SPEC RESULTS SHARDS [sbatch options...]" >&2; exit 2; }
spec="$(realpath "$1")" results="$(realpath -m "$2")" shards="$3"
shift 3
[[ "$shards" =~ ^[1-9][0-9]*$ ]] || { echo "submit.sh: SHARDS must be a positive integer, got '$shards'" >&2; exit 2; }
mkdir -p "$results"
array=$(sbatch --parsable --chdir="$results" --array="1-$shards" "$@" "$here/study.sbatch" "$spec" "$results")
array="${array%%;*}"
merge=$(sbatch --parsable --chdir="$results" --dependency="afterok:$array" --kill-on-invalid-dep=yes "$@" \
  "$here/merge.sbatch" "$results")
echo "$array ${merge%%;*}"
