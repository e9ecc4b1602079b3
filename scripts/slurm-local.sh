#!/usr/bin/env bash
# A throwaway single-node Slurm for the campaign tests (tests/campaign_slurm.rs):
#   bash scripts/slurm-local.sh start   install (Debian: slurm-wlm, munge) if missing, write a
#                                       private config, start munged, slurmctld, slurmd
#   bash scripts/slurm-local.sh stop    cancel its jobs, stop the three daemons it started
# Everything lives in $SAWTOOTH_SLURM_DIR (default /tmp/sawtooth-slurm): slurm.conf, a munge
# key and socket of its own, state, logs, pid files; clients use it through
# SLURM_CONF=$SAWTOOTH_SLURM_DIR/slurm.conf. Non-default ports (6917/6918) and its own munge
# socket keep it apart from a Slurm the machine may already run. Needs root (the daemons run
# as root: SlurmUser=root). No systemd, no cgroups (proctrack/linuxproc, task/none), no
# accounting. Both commands are idempotent.
set -euo pipefail
DIR="${SAWTOOTH_SLURM_DIR:-/tmp/sawtooth-slurm}"
CONF="$DIR/slurm.conf"
export SLURM_CONF="$CONF"

say() { echo "slurm-local: $*" >&2; }
alive() { [ -s "$1" ] && kill -0 "$(cat "$1")" 2>/dev/null; }

install() {
    if command -v sbatch >/dev/null && command -v slurmctld >/dev/null && command -v slurmd >/dev/null && command -v munged >/dev/null; then
        return 0
    fi
    say "installing slurm-wlm and munge from Debian's packages"
    local sudo=""
    if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends slurm-wlm munge >/dev/null
}

write_conf() {
    mkdir -p "$DIR/ctld" "$DIR/spool" "$DIR/munge"
    chmod 700 "$DIR" "$DIR/munge"
    local cpus
    cpus=$(nproc)
    cat > "$CONF" <<CONF
# written by scripts/slurm-local.sh: one node on 127.0.0.1, for tests
ClusterName=sawtooth-test
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort=6917
SlurmdPort=6918
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$DIR/munge/munge.socket
CredType=cred/munge
StateSaveLocation=$DIR/ctld
SlurmdSpoolDir=$DIR/spool
SlurmctldPidFile=$DIR/slurmctld.pid
SlurmdPidFile=$DIR/slurmd.pid
SlurmctldLogFile=$DIR/slurmctld.log
SlurmdLogFile=$DIR/slurmd.log
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
ReturnToService=2
KillWait=5
MinJobAge=600
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
}

start() {
    install
    if alive "$DIR/slurmctld.pid" && alive "$DIR/slurmd.pid" && sinfo -h >/dev/null 2>&1; then
        say "already running ($CONF)"
        return 0
    fi
    stop_daemons
    write_conf
    if [ ! -s "$DIR/munge/munge.key" ]; then
        mungekey --create --keyfile="$DIR/munge/munge.key" 2>/dev/null \
            || dd if=/dev/urandom of="$DIR/munge/munge.key" bs=1024 count=1 status=none
        chmod 400 "$DIR/munge/munge.key"
    fi
    munged --force --key-file="$DIR/munge/munge.key" --socket="$DIR/munge/munge.socket" \
        --pid-file="$DIR/munge/munged.pid" --log-file="$DIR/munge/munged.log" --seed-file="$DIR/munge/munged.seed"
    slurmctld -f "$CONF"
    slurmd -f "$CONF" -N localhost
    local i state=""
    for i in $(seq 1 60); do
        state=$(sinfo -h -n localhost -o %T 2>/dev/null || true)
        case "$state" in
            idle*|mixed*|allocated*) say "up: node localhost $state, $(nproc) CPUs ($CONF)"; return 0 ;;
            down*|drain*|unknown*) scontrol update nodename=localhost state=resume >/dev/null 2>&1 || true ;;
        esac
        sleep 0.5
    done
    say "Slurm did not come up (node state '${state}'); logs:"
    tail -n 20 "$DIR"/slurmctld.log "$DIR"/slurmd.log "$DIR"/munge/munged.log >&2 || true
    stop_daemons
    return 1
}

stop_daemons() {
    local f
    for f in "$DIR/slurmd.pid" "$DIR/slurmctld.pid" "$DIR/munge/munged.pid"; do
        if alive "$f"; then
            local pid
            pid=$(cat "$f")
            kill "$pid" 2>/dev/null || true
            for _ in $(seq 1 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
        fi
        rm -f "$f"
    done
}

stop() {
    if [ -f "$CONF" ] && alive "$DIR/slurmctld.pid"; then
        # every job of this private cluster is a test's: cancel them so no task outlives slurmd
        scancel --user="$(id -un)" 2>/dev/null || true
        for _ in $(seq 1 40); do
            [ -z "$(squeue -h -o %i 2>/dev/null)" ] && break
            sleep 0.25
        done
    fi
    stop_daemons
    say "stopped"
}

case "${1:-}" in
    start) start ;;
    stop) stop ;;
    *) echo "usage: $0 start|stop" >&2; exit 2 ;;
esac
