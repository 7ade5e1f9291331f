#!/bin/bash
# Submits a whole sharded experiment to Slurm: build and render the references (one job),
# the shards (an array of N tasks, run-experiments.sbatch), then merge-results (one job), each
# step after the previous one succeeded.
#
#   xtask/slurm/submit.sh paper 8 [extra sbatch options, e.g. --partition=cpu]
#
# From the repository root, on a filesystem every node sees. Environment:
#   CPUS_PER_TASK  render threads and CPUs of the references job and of each shard (default:
#                  the most CPUs one node of the partition has, from `sinfo`)
#   TIME_LIMIT     time limit of each job (default 04:00:00)
#   SHARDS_DIR     where the shards write (default target/experiment-shards/<experiment>)
#   RESULTS_DIR    where merge-results writes (default: merge-results' own)
#   XTASK_FLAGS    more flags for every run-experiments and merge-results, e.g. --allow-dirty
#   LOG_DIR        the jobs' slurm-*.out logs (default slurm-logs/, ignored by git)
#   WAIT_SECONDS   how long to watch the references job for a reason it can never start
#                  (default 10; 0 skips the check)
set -euo pipefail
usage="usage: $0 EXPERIMENT N [sbatch options…]"
experiment=${1:?$usage}
n=${2:?$usage}
shift 2
die() {
    echo "submit.sh: $*" >&2
    exit 1
}
[[ $n =~ ^[1-9][0-9]*$ ]] || die "N must be a positive number of shards, not '$n'"
command -v sbatch >/dev/null || die "sbatch not found: run this on a Slurm login node"

# The partition the jobs go to: the one in the sbatch options, else the default one.
partition=
for ((i = 1; i <= $#; i++)); do
    case ${!i} in
    --partition=*) partition=${!i#--partition=} ;;
    -p | --partition) j=$((i + 1)) && partition=${!j:-} ;;
    -p*) partition=${!i#-p} ;;
    esac
done
partition=${partition:-${SBATCH_PARTITION:-}}

if [[ -z ${CPUS_PER_TASK:-} ]]; then
    # %c is a node's CPU count; one line per node, so the largest node decides.
    CPUS_PER_TASK=$(sinfo -h -N ${partition:+-p "$partition"} -o %c | tr -dc '0-9\n' | sort -n | tail -1)
    [[ -n $CPUS_PER_TASK ]] ||
        die "sinfo lists no nodes${partition:+ in partition $partition}; set CPUS_PER_TASK or --partition"
fi
[[ $CPUS_PER_TASK =~ ^[1-9][0-9]*$ ]] || die "CPUS_PER_TASK must be a positive number, not '$CPUS_PER_TASK'"
cpus=$CPUS_PER_TASK
time_limit=${TIME_LIMIT:-04:00:00}
shards=${SHARDS_DIR:-target/experiment-shards/$(basename "$experiment" .toml)}
export SHARDS_DIR=$shards
logs=${LOG_DIR:-slurm-logs}
mkdir -p "$logs" # Slurm does not create it: a job whose log it cannot open fails silently
flags="${RESULTS_DIR:+ --results $RESULTS_DIR}${XTASK_FLAGS:+ $XTASK_FLAGS}"
export XTASK_FLAGS # for run-experiments.sbatch

# A request no node can ever satisfy (too many CPUs, a time limit above the partition's) is
# refused here, before anything is queued.
common=(--cpus-per-task="$cpus" --time="$time_limit")
if ! msg=$(sbatch --test-only "$@" "${common[@]}" --wrap true 2>&1); then
    die "Slurm refuses a job of $cpus CPUs and time limit $time_limit${partition:+ in partition $partition}:
  $msg
Set CPUS_PER_TASK (CPUs per job) or TIME_LIMIT, or pick another --partition."
fi

# xtask builds manylights itself: `cargo build -p xtask -p manylights` would unify their
# dependencies' features into another set and build manylights a second time.
refs=$(sbatch --parsable "$@" "${common[@]}" --job-name=manylights-refs \
    --output="$logs/%x-%j.out" \
    --wrap "cargo build --release -p xtask && cargo xtask run-experiments --experiment $experiment --references-only --threads $cpus$flags")
array=$(sbatch --parsable "$@" "${common[@]}" --dependency=afterok:"$refs" --array=1-"$n" \
    --output="$logs/%x-%A_%a.out" \
    "$(dirname "$0")/run-experiments.sbatch" "$experiment")
merge=$(sbatch --parsable "$@" --dependency=afterok:"$array" --job-name=manylights-merge \
    --cpus-per-task=1 --time="$time_limit" --output="$logs/%x-%j.out" \
    --wrap "cargo xtask merge-results --experiment $experiment$flags $shards/*")
echo "references: job $refs; shards: array job $array (1-$n); merge: job $merge"
echo "logs: $logs/; $cpus CPUs per job"

# Some jobs the controller accepts can still never start (it says why in the job's Reason):
# cancel them all with that reason rather than leave them pending for ever.
for ((t = 0; t < ${WAIT_SECONDS:-10}; t++)); do
    state= reason=
    read -r state reason < <(squeue -h -j "$refs" -o '%T %r' 2>/dev/null) || true
    [[ ${state:-} == PENDING ]] || break # running, finished, or gone (its log says why)
    case $reason in
    PartitionConfig | PartitionTimeLimit | PartitionNodeLimit | ReqNodeNotAvail* | BadConstraints | InvalidQOS | InvalidAccount)
        job=$(scontrol show job "$refs" 2>/dev/null | grep -oE '(Partition|NumCPUs|TimeLimit)=[^ ]*' | tr '\n' ' ')
        part=$(echo "$job" | grep -oE 'Partition=[^ ]*' | cut -d= -f2)
        limits=$(scontrol show partition "$part" 2>/dev/null |
            grep -oE '(MaxTime|MaxCPUsPerNode|TotalCPUs|State)=[^ ]*' | tr '\n' ' ')
        scancel "$refs" "$array" "$merge" || true
        die "the references job cannot start (Reason=$reason): cancelled all three jobs.
  job: $job
  partition: $limits
Set CPUS_PER_TASK or TIME_LIMIT, or pick another --partition (see sinfo)."
        ;;
    esac
    sleep 1
done
