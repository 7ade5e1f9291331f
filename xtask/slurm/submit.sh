#!/bin/bash
# Submits a whole sharded experiment to Slurm: build and render the references (one job),
# the shards (an array of N tasks, run-experiments.sbatch), then merge-results into
# results/<experiment>/ (one job), each step after the previous one succeeded.
#
#   xtask/slurm/submit.sh paper 8 [extra sbatch options, e.g. --partition=cpu]
#
# From the repository root, on a filesystem every node sees.
set -euo pipefail
experiment=${1:?usage: $0 EXPERIMENT N [sbatch options…]}
n=${2:?usage: $0 EXPERIMENT N [sbatch options…]}
shift 2
shards=${SHARDS_DIR:-target/experiment-shards/$experiment}
export SHARDS_DIR=$shards
refs=$(sbatch --parsable "$@" --job-name=manylights-refs --cpus-per-task=8 --time=04:00:00 \
    --wrap "cargo build --release -p xtask -p manylights && cargo xtask run-experiments --experiment $experiment --references-only")
array=$(sbatch --parsable "$@" --dependency=afterok:"$refs" --array=1-"$n" \
    "$(dirname "$0")/run-experiments.sbatch" "$experiment")
merge=$(sbatch --parsable "$@" --dependency=afterok:"$array" --job-name=manylights-merge \
    --cpus-per-task=1 --time=01:00:00 \
    --wrap "cargo xtask merge-results --experiment $experiment $shards/*")
echo "references: job $refs; shards: array job $array (1-$n); merge: job $merge"
