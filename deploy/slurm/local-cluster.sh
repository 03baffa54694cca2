#!/usr/bin/env bash
# A one-node Slurm cluster on this machine, for trying the batch pipeline (and for its test).
#
#   deploy/slurm/local-cluster.sh up     install Slurm and munge if missing (apt, as root), write
#                                        a munge key and a slurm.conf naming this host with its
#                                        CPUs and memory, start munged, slurmctld and slurmd,
#                                        wait until the node is idle
#   deploy/slurm/local-cluster.sh down   stop the daemons it started, by their process ids
#   deploy/slurm/local-cluster.sh env    print the line that points Slurm's commands at it
#   deploy/slurm/local-cluster.sh install   only install the packages if missing
#
# Everything lives under $VMC_SLURM_DIR (default /tmp/vmc-slurm): slurm.conf, logs, state, the
# pid files. Slurm's commands find the cluster through SLURM_CONF=$VMC_SLURM_DIR/slurm.conf
# (`eval "$(deploy/slurm/local-cluster.sh env)"`). Runs as root (the daemons need it).
# Exit status: 0 done, 2 Slurm cannot be installed or started here (the reason on stderr).
set -euo pipefail

DIR=${VMC_SLURM_DIR:-/tmp/vmc-slurm}
CONF=$DIR/slurm.conf
HOST=$(hostname -s)

die() { echo "local-cluster: $*" >&2; exit 2; }

install_if_missing() {
  if command -v slurmctld >/dev/null && command -v slurmd >/dev/null \
    && command -v munged >/dev/null && command -v sbatch >/dev/null; then
    return
  fi
  [ "$(id -u)" = 0 ] || die "Slurm is not installed and installing it needs root"
  command -v apt-get >/dev/null || die "Slurm is not installed and there is no apt-get"
  echo "local-cluster: installing slurmd slurmctld munge slurm-client" >&2
  DEBIAN_FRONTEND=noninteractive apt-get install -y -q slurmd slurmctld munge slurm-client \
    >"${TMPDIR:-/tmp}/vmc-slurm-apt.log" 2>&1 \
    || { apt-get update -q >/dev/null 2>&1 && DEBIAN_FRONTEND=noninteractive apt-get install \
      -y -q slurmd slurmctld munge slurm-client >"${TMPDIR:-/tmp}/vmc-slurm-apt.log" 2>&1; } \
    || die "apt-get install of Slurm failed (see ${TMPDIR:-/tmp}/vmc-slurm-apt.log)"
}

write_conf() {
  local cpus mem_mb
  cpus=$(nproc)
  # Slurm refuses a node that has less memory than configured: leave 5 % aside.
  mem_mb=$(awk '/MemTotal/ { printf "%d", $2 / 1024 * 0.95 }' /proc/meminfo)
  mkdir -p "$DIR/state" "$DIR/spool" "$DIR/log"
  cat >"$CONF" <<CONF
# One-node cluster written by deploy/slurm/local-cluster.sh
ClusterName=vmc-local
SlurmctldHost=$HOST(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
StateSaveLocation=$DIR/state
SlurmdSpoolDir=$DIR/spool
SlurmctldPidFile=$DIR/slurmctld.pid
SlurmdPidFile=$DIR/slurmd.pid
SlurmctldLogFile=$DIR/log/slurmctld.log
SlurmdLogFile=$DIR/log/slurmd.log
SlurmctldPort=6817
SlurmdPort=6818
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
SlurmdTimeout=60
InactiveLimit=0
KillWait=5
NodeName=$HOST NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem_mb State=UNKNOWN
PartitionName=local Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
CONF
}

start_munge() {
  if [ ! -s /etc/munge/munge.key ]; then
    mkdir -p /etc/munge
    dd if=/dev/urandom of=/etc/munge/munge.key bs=1 count=1024 status=none
  fi
  if munge -n </dev/null 2>/dev/null | unmunge >/dev/null 2>&1; then
    return # a munged is already serving this machine: use it, leave it alone
  fi
  mkdir -p /run/munge /var/lib/munge /var/log/munge
  if id munge >/dev/null 2>&1; then
    chown munge:munge /etc/munge /etc/munge/munge.key /run/munge /var/lib/munge /var/log/munge
    chmod 0700 /etc/munge && chmod 0400 /etc/munge/munge.key
    runuser -u munge -- munged || die "munged did not start"
  else
    munged --force || die "munged did not start"
  fi
  cp /run/munge/munged.pid "$DIR/munged.pid"
  for _ in $(seq 50); do
    munge -n </dev/null 2>/dev/null | unmunge >/dev/null 2>&1 && return
    sleep 0.1
  done
  die "munged does not answer"
}

up() {
  install_if_missing
  [ "$(id -u)" = 0 ] || die "the daemons must be started as root"
  if [ -f "$DIR/slurmctld.pid" ] && kill -0 "$(cat "$DIR/slurmctld.pid")" 2>/dev/null; then
    echo "local-cluster: already up ($CONF)" >&2
    return
  fi
  write_conf
  start_munge
  slurmctld -f "$CONF" -i || die "slurmctld did not start (see $DIR/log/slurmctld.log)"
  slurmd -f "$CONF" || die "slurmd did not start (see $DIR/log/slurmd.log)"
  export SLURM_CONF=$CONF
  for _ in $(seq 120); do
    state=$(sinfo -h -n "$HOST" -o %t 2>/dev/null || true)
    if [ "$state" = idle ]; then
      echo "local-cluster: up, node $HOST idle ($(nproc) CPUs); SLURM_CONF=$CONF" >&2
      return
    fi
    sleep 0.5
  done
  die "node $HOST is not idle after 60 s (state '${state:-none}'; see $DIR/log)"
}

stop_pid_file() {
  local f=$1 pid
  [ -f "$f" ] || return 0
  pid=$(cat "$f")
  if kill -0 "$pid" 2>/dev/null; then
    kill "$pid"
    for _ in $(seq 100); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -0 "$pid" 2>/dev/null && kill -9 "$pid"
  fi
  rm -f "$f"
}

down() {
  stop_pid_file "$DIR/slurmd.pid"
  stop_pid_file "$DIR/slurmctld.pid"
  stop_pid_file "$DIR/munged.pid" # only if this script started it
  echo "local-cluster: down" >&2
}

case "${1:-}" in
  up) up ;;
  down) down ;;
  env) echo "export SLURM_CONF=$CONF" ;;
  install) install_if_missing ;;
  *) echo "usage: $0 up|down|env|install" >&2; exit 1 ;;
esac
