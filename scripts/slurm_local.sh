#!/usr/bin/env bash
# A single-node Slurm on this machine, for trying `sweep submit` and for tests/it/cluster/:
# munged, slurmctld and slurmd on localhost, started as plain daemons (no systemd), with their
# configuration, state and logs under one directory.
#
#   bash scripts/slurm_local.sh up      # install (Debian: slurm-wlm, munge) if missing, start
#   export SLURM_CONF=/tmp/demsweep-slurm/slurm.conf   # what `up` prints; sbatch/squeue need it
#   bash scripts/slurm_local.sh status  # sinfo
#   bash scripts/slurm_local.sh down    # stop the daemons this script started
#
# SLURM_LOCAL_DIR (default /tmp/demsweep-slurm) holds slurm.conf, the state, the spool, the
# pid files and the logs; SLURM_LOCAL_CPUS (default 4) is the CPU count the node advertises.
# That may exceed the real cores (slurmd's config_overrides), so that a test can run several
# one-CPU array tasks at once on a 2-core machine; they then share the cores.
set -euo pipefail

DIR=${SLURM_LOCAL_DIR:-/tmp/demsweep-slurm}
CPUS=${SLURM_LOCAL_CPUS:-4}
CONF=$DIR/slurm.conf
HOST=$(hostname -s)

die() { echo "slurm_local.sh: $*" >&2; exit 1; }

install() {
    command -v slurmctld >/dev/null && command -v munged >/dev/null && command -v sbatch >/dev/null \
        && return 0
    [ "$(id -u)" = 0 ] || die "slurm-wlm and munge are not installed; run as root to install them"
    echo "installing slurm-wlm and munge (Debian packages)" >&2
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends slurm-wlm munge >/dev/null
}

alive() { [ -f "$1" ] && kill -0 "$(cat "$1")" 2>/dev/null; }

write_conf() {
    mkdir -p "$DIR/state" "$DIR/spool" "$DIR/log" "$DIR/munge"
    local mem
    mem=$(awk '/MemTotal/ { print int($2 / 1024 / 2) }' /proc/meminfo)
    # Written beside and moved in (only if it changed): `up` runs again while jobs submit, and a
    # file truncated under a reading sbatch is "empty" to it.
    local tmp=$CONF.$$
    cat >"$tmp" <<EOF
# Written by scripts/slurm_local.sh: one node, root runs everything, no cgroups.
ClusterName=demsweep-local
SlurmctldHost=$HOST(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$DIR/munge/munge.socket
CryptoType=crypto/munge
StateSaveLocation=$DIR/state
SlurmdSpoolDir=$DIR/spool
SlurmctldPidFile=$DIR/slurmctld.pid
SlurmdPidFile=$DIR/slurmd.pid
SlurmctldLogFile=$DIR/log/slurmctld.log
SlurmdLogFile=$DIR/log/slurmd.log
SlurmctldPort=6917
SlurmdPort=6918
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SwitchType=switch/none
MpiDefault=none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SlurmdParameters=config_overrides
ReturnToService=2
MaxArraySize=10001
KillWait=5
MinJobAge=300
SchedulerParameters=sched_interval=2
NodeName=$HOST NodeAddr=127.0.0.1 CPUs=$CPUS RealMemory=$mem State=UNKNOWN
PartitionName=debug Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
EOF
    if cmp -s "$tmp" "$CONF"; then rm -f "$tmp"; else mv -f "$tmp" "$CONF"; fi
}

up() {
    install
    write_conf
    # munge: its own key and socket under $DIR, so that a system munged is left alone.
    local key=$DIR/munge/munge.key sock=$DIR/munge/munge.socket
    if ! alive "$DIR/munged.pid"; then
        [ -f "$key" ] || { dd if=/dev/urandom of="$key" bs=1024 count=1 status=none; chmod 400 "$key"; }
        munged --force --key-file="$key" --socket="$sock" --pid-file="$DIR/munged.pid" \
            --log-file="$DIR/log/munged.log" --seed-file="$DIR/munge/seed"
    fi
    export SLURM_CONF=$CONF
    alive "$DIR/slurmctld.pid" || slurmctld -f "$CONF"
    alive "$DIR/slurmd.pid" || slurmd -f "$CONF"
    for _ in $(seq 1 60); do
        if sinfo -h -o %t 2>/dev/null | grep -qE '^(idle|mix|alloc)'; then
            echo "export SLURM_CONF=$CONF"
            return 0
        fi
        sleep 0.5
    done
    scontrol update nodename="$HOST" state=resume 2>/dev/null || true
    sinfo -h -o %t 2>/dev/null | grep -qE '^(idle|mix|alloc)' \
        || die "the node did not come up; see $DIR/log/"
    echo "export SLURM_CONF=$CONF"
}

down() {
    # Only the daemons this script started, by their pid files.
    for d in slurmd slurmctld munged; do
        local pidf=$DIR/$d.pid
        if alive "$pidf"; then
            kill "$(cat "$pidf")"
            for _ in $(seq 1 50); do alive "$pidf" || break; sleep 0.1; done
        fi
        rm -f "$pidf"
    done
}

case "${1:-}" in
    up) up ;;
    down) down ;;
    status) SLURM_CONF=$CONF sinfo ;;
    *) die "usage: slurm_local.sh up|down|status" ;;
esac
