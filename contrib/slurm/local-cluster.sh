#!/usr/bin/env bash
# A one-node Slurm cluster on this machine, for trying `geardyn … --executor slurm` and for the
# CI's integration test (tests/slurm.rs). Not a production setup: controller and node on one
# host, root as SlurmUser, no accounting, no cgroups.
#
#   contrib/slurm/local-cluster.sh start    # installs slurm-wlm + munge (apt) if missing, starts
#                                           # munged, slurmctld and slurmd; prints the SLURM_CONF
#                                           # line to export
#   contrib/slurm/local-cluster.sh status   # sinfo and squeue
#   contrib/slurm/local-cluster.sh stop     # stops the three daemons
#
# Everything (config, munge key and socket, state, spool, logs, pid files) lives under
# ${GEARDYN_SLURM_DIR:-/tmp/geardyn-slurm}; nothing in /etc is touched.
#
# Exit codes: 0 done, 2 usage, 3 not root, or Slurm is missing and cannot be installed here
# (no apt-get, no mirror), 4 a daemon did not come up (its log's tail is printed).
set -euo pipefail

dir=${GEARDYN_SLURM_DIR:-/tmp/geardyn-slurm}
conf=$dir/slurm.conf
socket=$dir/munge/munge.socket.2

usage() {
    echo "usage: $0 start|stop|status" >&2
    exit 2
}

install_if_missing() {
    if [ "$(id -u)" != 0 ]; then
        echo "this script runs its one-node cluster as root (slurmd starts the tasks, munged" >&2
        echo "and slurmctld run as SlurmUser=root): run it as root, or use your own cluster" >&2
        exit 3
    fi
    if command -v slurmctld >/dev/null && command -v slurmd >/dev/null \
        && command -v sbatch >/dev/null && command -v munged >/dev/null; then
        return
    fi
    if ! command -v apt-get >/dev/null || [ "$(id -u)" != 0 ]; then
        echo "Slurm (slurmctld, slurmd, sbatch) and munge are not installed, and this script can" >&2
        echo "install them only as root with apt-get. Install slurm-wlm and munge (or your" >&2
        echo "distribution's packages), or run against your own cluster." >&2
        exit 3
    fi
    echo "installing slurm-wlm and munge with apt-get" >&2
    export DEBIAN_FRONTEND=noninteractive
    if ! apt-get update -qq >/dev/null; then
        echo "apt-get update failed (no package mirror reachable?)" >&2
        exit 3
    fi
    # The packages' own service starts fail without systemd; the daemons are started below.
    apt-get install -y -qq slurm-wlm munge >/dev/null 2>&1 || true
    if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
        echo "apt-get could not install slurm-wlm and munge" >&2
        exit 3
    fi
}

# The daemon of a pid file is alive: the pid exists and is that daemon (not a process that
# got the pid of one that died).
running() {
    local daemon=$1 pidfile=$dir/run/$1.pid pid
    [ -f "$pidfile" ] || return 1
    pid=$(cat "$pidfile")
    [ "$(cat "/proc/$pid/comm" 2>/dev/null)" = "$daemon" ]
}

fail_with_log() {
    echo "$1 did not start; the end of $2:" >&2
    tail -n 20 "$2" >&2 || true
    exit 4
}

write_conf() {
    local host cpus memory_mb
    host=$(hostname -s)
    cpus=$(nproc)
    # What the node offers jobs: 90 % of the machine's memory.
    memory_mb=$(awk '/MemTotal/ { printf "%d", $2 / 1024 * 0.9 }' /proc/meminfo)
    cat >"$conf" <<EOF
ClusterName=geardyn-local
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$socket
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/run/slurmctld.pid
SlurmdPidFile=$dir/run/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
ReturnToService=2
MpiDefault=none
SwitchType=switch/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
KillWait=30
MinJobAge=30
NodeName=$host CPUs=$cpus RealMemory=$memory_mb State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
}

start() {
    install_if_missing
    mkdir -p "$dir"/{munge,state,spool,run,log}
    chmod 700 "$dir/munge"
    write_conf
    export SLURM_CONF=$conf

    if ! running munged; then
        if [ ! -f "$dir/munge/munge.key" ]; then
            dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none
            chmod 400 "$dir/munge/munge.key"
        fi
        munged --force --key-file="$dir/munge/munge.key" --socket="$socket" \
            --pid-file="$dir/run/munged.pid" --log-file="$dir/log/munged.log" \
            --seed-file="$dir/munge/munged.seed" \
            || fail_with_log munged "$dir/log/munged.log"
    fi
    if ! running slurmctld; then
        # Without -c: the state saved under $dir keeps the job ids counting up across
        # restarts, so a study's record of its jobs never meets a new job of the same id.
        slurmctld || fail_with_log slurmctld "$dir/log/slurmctld.log"
    fi
    if ! running slurmd; then
        slurmd || fail_with_log slurmd "$dir/log/slurmd.log"
    fi
    # The node registers within a few seconds; jobs submitted before would only wait.
    for _ in $(seq 60); do
        # Exact states: "idle*" (not responding) and "idle~" (powered down) are not up.
        state=$(sinfo -h -n "$(hostname -s)" -o %T 2>/dev/null || true)
        case $state in
            idle | mixed | allocated) break ;;
        esac
        sleep 0.5
    done
    case ${state:-} in
        idle | mixed | allocated) ;;
        *)
            echo "the node did not come up (state '${state:-none}')" >&2
            tail -n 20 "$dir/log/slurmd.log" "$dir/log/slurmctld.log" >&2 || true
            exit 4
            ;;
    esac
    echo "local Slurm cluster up: $(nproc) CPUs on $(hostname -s); for sbatch, squeue and geardyn:" >&2
    echo "export SLURM_CONF=$conf"
}

stop() {
    export SLURM_CONF=$conf
    for daemon in slurmd slurmctld munged; do
        pidfile=$dir/run/$daemon.pid
        if running "$daemon"; then
            pid=$(cat "$pidfile")
            kill "$pid" 2>/dev/null || true
            for _ in $(seq 50); do
                kill -0 "$pid" 2>/dev/null || break
                sleep 0.2
            done
            kill -9 "$pid" 2>/dev/null || true
        fi
        rm -f "$pidfile"
    done
    echo "local Slurm cluster stopped" >&2
}

status() {
    export SLURM_CONF=$conf
    sinfo
    squeue
}

case ${1:-} in
    start) start ;;
    stop) stop ;;
    status) status ;;
    *) usage ;;
esac
