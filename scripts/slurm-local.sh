#!/usr/bin/env bash
# A one-node Slurm cluster on this machine, for the tests and for trying the docs' batch scripts
# (Debian slurm-wlm and munge; `bash scripts/setup.sh --tests` installs them). Its own munged,
# slurmctld and slurmd with every file under one state folder the script owns; no cgroups, no system
# configuration touched. Made for root (the CI); as another user slurmd runs jobs as that user.
#
#   scripts/slurm-local.sh start    start the cluster (nothing to do if it runs); prints SLURM_CONF
#   scripts/slurm-local.sh stop     cancel its jobs, stop the three daemons it started (by pid file)
#   scripts/slurm-local.sh status   exit 0 when all three daemons run, 3 otherwise
#   scripts/slurm-local.sh env      the line to use it: eval "$(scripts/slurm-local.sh env)"
#
# Environment: ARMSIM_SLURM_DIR (state folder; default /tmp/armsim-slurm-UID), ARMSIM_SLURM_PORT
# (slurmctld's port, slurmd's is the next; default 16817, away from a real cluster's 6817).
set -euo pipefail

dir=${ARMSIM_SLURM_DIR:-/tmp/armsim-slurm-$(id -u)}
port=${ARMSIM_SLURM_PORT:-16817}
conf=$dir/slurm.conf
node=localnode
daemons=(munged slurmctld slurmd)

say() { echo "slurm-local: $*"; }
fail() { echo "slurm-local: error: $*" >&2; exit 1; }

pid_file() { echo "$dir/$1.pid"; }

# The daemon's pid when its pid file names a live process of that name (not a reused pid).
find_pid() {
    local f pid
    f=$(pid_file "$1")
    [ -r "$f" ] || return 1
    pid=$(tr -dc '0-9' < "$f")
    [ -n "$pid" ] && [ -r "/proc/$pid/comm" ] && [ "$(cat "/proc/$pid/comm")" = "$1" ] || return 1
    echo "$pid"
}

is_running() { find_pid "$1" > /dev/null; }

all_running() {
    local d
    for d in "${daemons[@]}"; do is_running "$d" || return 1; done
}

check_installed() {
    local b missing=()
    for b in munged slurmctld slurmd sbatch squeue sinfo scontrol scancel; do
        command -v "$b" > /dev/null || [ -x "/usr/sbin/$b" ] || missing+=("$b")
    done
    [ ${#missing[@]} -eq 0 ] || fail "not installed: ${missing[*]} (Debian slurm-wlm and munge: bash scripts/setup.sh --tests)"
}

write_config() {
    local user cpus
    user=$(id -un)
    cpus=$(nproc)
    cat > "$conf" <<EOF
# Written by scripts/slurm-local.sh: a one-node cluster, no cgroups, state under $dir.
ClusterName=armsim-local
SlurmctldHost=$(hostname)(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/munge/munge.socket.2
StateSaveLocation=$dir/ctld
SlurmdSpoolDir=$dir/spool/%n
SlurmctldPidFile=$(pid_file slurmctld)
SlurmdPidFile=$(pid_file slurmd)
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
ReturnToService=2
SchedulerType=sched/backfill
SchedulerParameters=sched_interval=1
MinJobAge=600
KillWait=5
InactiveLimit=0
NodeName=$node NodeHostname=$(hostname) NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=local Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
}

start_munge() {
    is_running munged && return 0
    mkdir -p "$dir/munge"
    chmod 700 "$dir/munge"
    if [ ! -s "$dir/munge/munge.key" ]; then
        head -c 1024 /dev/urandom > "$dir/munge/munge.key"
    fi
    chmod 600 "$dir/munge/munge.key"
    local force=()
    [ "$(id -u)" -eq 0 ] && force=(--force)  # munged refuses root without it
    /usr/sbin/munged "${force[@]}" --socket="$dir/munge/munge.socket.2" --key-file="$dir/munge/munge.key" \
        --pid-file="$(pid_file munged)" --log-file="$dir/log/munged.log" --seed-file="$dir/munge/munged.seed" \
        || fail "munged did not start (see $dir/log/munged.log)"
}

wait_until() {  # wait_until SECONDS WHAT COMMAND...
    local seconds=$1 what=$2
    shift 2
    for _ in $(seq 1 $((seconds * 5))); do
        "$@" > /dev/null 2>&1 && return 0
        sleep 0.2
    done
    fail "$what not ready after $seconds s (logs in $dir/log)"
}

node_is_idle() { [ "$(sinfo -h -n "$node" -o %T 2>/dev/null)" = idle ]; }

cmd_start() {
    check_installed
    if all_running; then
        say "already running (SLURM_CONF=$conf)"
        return 0
    fi
    # A partial cluster (a daemon died): stop what is left, start afresh.
    for d in "${daemons[@]}"; do is_running "$d" && { cmd_stop; break; }; done
    mkdir -p "$dir/ctld" "$dir/spool" "$dir/log"
    write_config
    export SLURM_CONF=$conf
    start_munge
    wait_until 10 munged test -S "$dir/munge/munge.socket.2"
    # -i: ignore a state from an earlier run's jobs (the cluster starts empty).
    /usr/sbin/slurmctld -f "$conf" -i || fail "slurmctld did not start (see $dir/log/slurmctld.log)"
    wait_until 30 slurmctld scontrol ping
    /usr/sbin/slurmd -f "$conf" -N "$node" || fail "slurmd did not start (see $dir/log/slurmd.log)"
    wait_until 60 "node $node" node_is_idle
    say "running: $(nproc) CPUs on node $node; use it with: export SLURM_CONF=$conf"
}

stop_daemon() {
    local pid
    pid=$(find_pid "$1") || return 0
    kill "$pid" 2>/dev/null || true
    for _ in $(seq 1 50); do [ -d "/proc/$pid" ] || break; sleep 0.2; done
    if [ -d "/proc/$pid" ]; then kill -9 "$pid" 2>/dev/null || true; fi
    rm -f "$(pid_file "$1")"
    say "stopped $1 ($pid)"
}

cmd_stop() {
    export SLURM_CONF=$conf
    if is_running slurmctld && is_running slurmd; then  # its jobs first, so no job step outlives slurmd
        local jobs
        jobs=$(squeue -h -o %i 2>/dev/null || true)
        if [ -n "$jobs" ]; then
            # shellcheck disable=SC2086
            scancel $jobs 2>/dev/null || true
            for _ in $(seq 1 75); do [ -z "$(squeue -h -o %i 2>/dev/null)" ] && break; sleep 0.2; done
        fi
    fi
    stop_daemon slurmd
    stop_daemon slurmctld
    stop_daemon munged
}

cmd_status() {
    local d pid state=0
    for d in "${daemons[@]}"; do
        if pid=$(find_pid "$d"); then echo "$d: running ($pid)"; else echo "$d: stopped"; state=3; fi
    done
    [ $state -eq 0 ] && SLURM_CONF=$conf sinfo -h -o "node %n: %T, %c CPUs" 2>/dev/null || true
    echo "SLURM_CONF=$conf"
    return $state
}

case "${1:-}" in
    start) cmd_start ;;
    stop) cmd_stop ;;
    status) cmd_status ;;
    env) echo "export SLURM_CONF=$conf" ;;
    *) echo "usage: $0 start|stop|status|env (got '${1:-}')" >&2; exit 2 ;;
esac
