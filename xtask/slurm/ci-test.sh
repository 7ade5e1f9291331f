#!/bin/bash
# The Slurm path end to end on a one-node cluster on this machine (run by .ci/run, as root):
# installs Debian's slurm-wlm and munge when missing, starts munged, slurmctld and slurmd on
# localhost with a minimal slurm.conf in a temporary state directory, then
#   1. submits ci-test/tiny.toml (4 cells) with submit.sh as 2 shards and checks that the merged
#      table equals a single run's (cells.csv but for its timing columns);
#   2. asks submit.sh for more CPUs than the node has, and
#   3. for a time limit above its partition's (a job Slurm accepts but never starts), and checks
#      that each fails at once with a message and leaves nothing queued;
#   4. checks that `git status` is as before.
# Stops the daemons it started and removes its state and the references it rendered on exit.
# Where Slurm cannot be installed it prints `SKIPPED: …` and exits 0. Last line: the count.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
cd "$root"
export PATH=$PATH:/usr/sbin:/sbin
t0=$SECONDS
passed=0
failed=0
skip() {
    echo "SKIPPED: slurm test: $*"
    echo "slurm: 0 passed, 0 failed, 1 skipped"
    exit 0
}
have_slurm() { command -v slurmctld && command -v slurmd && command -v munged && command -v sbatch; } >/dev/null

if ! have_slurm; then
    [[ $(id -u) == 0 ]] || skip "slurm-wlm is not installed, and installing it needs root"
    command -v apt-get >/dev/null || skip "slurm-wlm is not installed and there is no apt-get"
    echo "slurm test: installing slurm-wlm and munge (apt-get)…"
    if ! { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge; } \
        >/tmp/slurm-ci-apt.log 2>&1; then
        tail -5 /tmp/slurm-ci-apt.log
        skip "apt-get install slurm-wlm munge failed (log: /tmp/slurm-ci-apt.log)"
    fi
    have_slurm || skip "slurm-wlm installed but its daemons are not on PATH"
fi
[[ $(id -u) == 0 ]] || skip "slurmd runs jobs as root here: run as root"

state=$(mktemp -d /tmp/manylights-slurm-ci.XXXXXX)
chmod 755 "$state" # munged wants its socket's directory searchable
pids=()
refs_before=$(ls references)
status_before=$(git status --porcelain 2>/dev/null || true)
# The references this test rendered (a committed one it reused stays).
remove_new_references() {
    comm -13 <(echo "$refs_before") <(ls references) | while read -r d; do rm -rf "references/$d"; done
}
cleanup() {
    local rc=$?
    set +e # clean up all that can be, whatever fails
    if [[ -n ${SLURM_CONF:-} ]]; then
        # Cancel while slurmd still runs, so that it ends each job's slurmstepd (which would
        # outlive it), and wait for the steps' sockets in the spool to go.
        squeue -h -o %A 2>/dev/null | sort -u | xargs -r scancel 2>/dev/null
        for _ in $(seq 100); do
            [[ -z $(squeue -h -o %A 2>/dev/null) ]] && ! compgen -G "$state/spool/${node}_*" >/dev/null && break
            sleep 0.2
        done
        compgen -G "$state/spool/${node}_*" >/dev/null && echo "slurm test: job steps still running: $(ls "$state/spool")"
    fi
    for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
    for p in "${pids[@]}"; do
        for _ in $(seq 50); do kill -0 "$p" 2>/dev/null || break; sleep 0.1; done
        kill -9 "$p" 2>/dev/null || true
    done
    remove_new_references
    if [[ $rc != 0 ]]; then
        for f in "$state"/*.log "$state"/logs/*; do
            [[ -f $f ]] && echo "--- $f" && tail -20 "$f"
        done
    fi
    if [[ -n ${KEEP_SLURM_STATE:-} ]]; then echo "state kept in $state"; else rm -rf "$state"; fi
}
trap cleanup EXIT

# ---- the cluster: munged, slurmctld, slurmd, all in $state ----
key=$state/munge.key
dd if=/dev/urandom of="$key" bs=1024 count=1 status=none
chmod 400 "$key"
munged -F --force --key-file="$key" --socket="$state/munge.socket" --pid-file="$state/munged.pid" \
    --log-file="$state/munged.log" --seed-file="$state/munged.seed" >"$state/munged.out" 2>&1 &
pids+=($!)
node=$(hostname -s)
cpus=$(nproc)
port=$((20000 + RANDOM % 20000))
mkdir -p "$state/ctld" "$state/spool"
cat >"$state/slurm.conf" <<EOF
ClusterName=manylights-ci
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$state/munge.socket
StateSaveLocation=$state/ctld
SlurmdSpoolDir=$state/spool
SlurmctldPidFile=$state/slurmctld.pid
SlurmdPidFile=$state/slurmd.pid
SlurmctldLogFile=$state/slurmctld.log
SlurmdLogFile=$state/slurmd.log
ProctrackType=proctrack/pgid
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
ReturnToService=2
MpiDefault=none
MailProg=/bin/true
NodeName=$node NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=ci Nodes=$node Default=YES MaxTime=INFINITE State=UP
PartitionName=short Nodes=$node MaxTime=1 State=UP
EOF
export SLURM_CONF=$state/slurm.conf
for _ in $(seq 50); do [[ -S $state/munge.socket ]] && break; sleep 0.1; done
slurmctld -D -i -f "$SLURM_CONF" >"$state/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -N "$node" -f "$SLURM_CONF" >"$state/slurmd.out" 2>&1 &
pids+=($!)
up=
for _ in $(seq 60); do
    [[ $(sinfo -h -o %T 2>/dev/null) == idle ]] && up=1 && break
    sleep 0.5
done
[[ -n $up ]] || { echo "slurm test: the one-node cluster did not come up"; exit 1; }
echo "slurm test: cluster up ($cpus CPUs, node $node, port $port) after $((SECONDS - t0)) s"

# ---- the builds the jobs use, once (the references job would build them too): apart, as
# `cargo xtask` and xtask build them (together, their dependencies' features would differ) ----
cargo build --release -p xtask
cargo build --release -p manylights
echo "slurm test: release build ready after $((SECONDS - t0)) s"

exp=$here/ci-test/tiny.toml
# A developer's uncommitted edits must not stop the test: it compares tables, not provenance.
export XTASK_FLAGS=--allow-dirty
ok() { echo "ok: $1" && passed=$((passed + 1)); }
bad() { echo "FAILED: $1" && failed=$((failed + 1)); }

# cells.csv without the columns that time a render (they differ from run to run). They come
# before any quoted field that may hold a comma, so splitting at every comma finds them.
untimed() {
    awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) if ($i ~ /_seconds$/) drop[i] = 1 }
        { out = ""; for (i = 1; i <= NF; i++) if (!(i in drop)) out = out $i ","; print out }' "$1"
}

# ---- 1. sharded through Slurm, merged, equals one run ----
cargo xtask run-experiments --experiment "$exp" --threads "$cpus" --allow-dirty --results "$state/single"
out=$(SHARDS_DIR=$state/shards RESULTS_DIR=$state/merged LOG_DIR=$state/logs \
    "$here/submit.sh" "$exp" 2)
echo "$out"
jobs=$(echo "$out" | grep -oE 'job [0-9]+' | grep -oE '[0-9]+' | tr '\n' ' ')
for _ in $(seq 300); do
    [[ -z $(squeue -h -o %A 2>/dev/null) ]] && break
    sleep 0.5
done
states=$(for j in $jobs; do scontrol show job "$j" | grep -oE 'JobState=[A-Z_]+'; done | sort | uniq -c)
echo "slurm test: jobs $jobs: $(echo $states)"
if [[ -n $(squeue -h -o %A) ]]; then
    bad "sharded run: jobs still queued after 150 s"
elif echo "$states" | grep -qv 'JobState=COMPLETED'; then
    bad "sharded run: a job did not complete"
elif ! cmp <(untimed "$state/single/cells.csv") <(untimed "$state/merged/cells.csv"); then
    diff <(untimed "$state/single/cells.csv") <(untimed "$state/merged/cells.csv") | head -20
    bad "sharded run: the merged table differs from a single run's"
elif [[ $(untimed "$state/merged/cells.csv" | wc -l) != 5 ]]; then
    bad "sharded run: expected 4 cells, cells.csv has $(($(wc -l <"$state/merged/cells.csv") - 1))"
else
    ok "2 shards through Slurm, merged, equal a single run's table (4 cells)"
fi

# ---- 2. a job that cannot be scheduled fails at once ----
t=$SECONDS
if msg=$(CPUS_PER_TASK=$((cpus * 16)) LOG_DIR=$state/logs "$here/submit.sh" "$exp" 2 2>&1); then
    bad "submit.sh accepted $((cpus * 16)) CPUs per task on a $cpus-CPU node: $msg"
elif [[ -n $(squeue -h -o %A) ]]; then
    bad "submit.sh failed but left jobs queued"
elif [[ $msg != *CPUS_PER_TASK* ]]; then
    bad "submit.sh's message does not say what to change: $msg"
else
    echo "$msg" | sed 's/^/    /'
    ok "too many CPUs: refused in $((SECONDS - t)) s with a message, nothing queued"
fi

# ---- 3. a job the controller accepts but can never start (Reason=PartitionConfig) ----
t=$SECONDS
if msg=$(TIME_LIMIT=10 LOG_DIR=$state/logs SHARDS_DIR=$state/shards3 RESULTS_DIR=$state/merged3 \
    "$here/submit.sh" "$exp" 2 --partition=short 2>&1); then
    bad "submit.sh queued jobs above the partition's time limit: $msg"
elif [[ -n $(squeue -h -o %A) ]]; then
    bad "submit.sh failed but left jobs queued"
elif [[ $msg != *Reason=* ]]; then
    bad "submit.sh's message does not give Slurm's reason: $msg"
else
    echo "$msg" | sed 's/^/    /'
    ok "time limit above the partition's: cancelled in $((SECONDS - t)) s with the reason, nothing queued"
fi

# ---- 4. nothing left in the checkout ----
remove_new_references
if [[ $(git status --porcelain 2>/dev/null || true) == "$status_before" ]]; then
    ok "the checkout is as it was (git status)"
else
    diff <(echo "$status_before") <(git status --porcelain) | sed 's/^/    /'
    bad "the test left files in the checkout"
fi

echo "slurm test: $((SECONDS - t0)) s in all"
echo "slurm: $passed passed, $failed failed"
[[ $failed == 0 ]]
