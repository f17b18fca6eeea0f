#!/bin/bash
# Submits a whole farm run: an array of N shards and the merge job that waits for them.
#   tools/slurm/submit.sh N RECIPE.yaml DIR [extra sbatch options for the shards...]
# Prints the two job ids. Same as the two sbatch commands in README.
set -euo pipefail
if [[ $# -lt 3 ]]; then
  echo "usage: $0 N RECIPE.yaml DIR [sbatch options...]" >&2
  exit 2
fi
n=$1 recipe=$2 out=$3
shift 3
here=$(cd "$(dirname "$0")" && pwd)
jobid=$(sbatch --parsable --array=0-$((n - 1)) "$@" "$here/generate.sbatch" "$recipe" "$out")
jobid=${jobid%%;*}
merge=$(sbatch --parsable --dependency=afterok:"$jobid" "$here/merge.sbatch" "$out")
echo "shards: job $jobid (array 0-$((n - 1))), merge: job ${merge%%;*}"
