#!/usr/bin/env bash
# A real single-node Slurm cluster on this machine, for `cosserat batch --slurm` and
# tests/slurm.rs: Debian's slurmctld, slurmd and munged (scripts/install_deps.sh installs them),
# started without systemd, with every file in one folder ($COSSERAT_SLURM_DIR, default
# /tmp/cosserat-slurm): slurm.conf, its own munge key and socket, state, spool and logs.
#
#   bash scripts/slurm_cluster.sh start    # prints `export SLURM_CONF=...`; ready in seconds
#   bash scripts/slurm_cluster.sh status   # sinfo, or exit status 1 if it is not running
#   bash scripts/slurm_cluster.sh stop     # stops the three daemons it started
#
# The Slurm clients (sbatch, squeue, sinfo) find this cluster through SLURM_CONF. Needs root
# (slurmd runs jobs as their user). Ports: $COSSERAT_SLURM_PORT (slurmctld, default 6817) and
# the next one (slurmd).
set -euo pipefail
D="${COSSERAT_SLURM_DIR:-/tmp/cosserat-slurm}"
PORT="${COSSERAT_SLURM_PORT:-6817}"
CONF="$D/slurm.conf"
export SLURM_CONF="$CONF"

die() { echo "slurm_cluster: $*" >&2; exit 1; }

pid_of() { # a daemon's pid from its pid file, if it runs
  local f="$D/$1.pid"
  [ -s "$f" ] && kill -0 "$(cat "$f")" 2>/dev/null && cat "$f"
}

stop() {
  for d in slurmd slurmctld munged; do
    if p=$(pid_of "$d"); then
      kill "$p" 2>/dev/null || true
      for _ in $(seq 50); do kill -0 "$p" 2>/dev/null || break; sleep 0.1; done
      kill -9 "$p" 2>/dev/null || true
      echo "stopped $d (pid $p)"
    fi
    rm -f "$D/$d.pid"
  done
}

start() {
  [ "$(id -u)" -eq 0 ] || die "must run as root (slurmd starts jobs as their user)"
  for c in slurmctld slurmd munged sbatch squeue sinfo; do
    command -v "$c" >/dev/null 2>&1 || die "$c not found: install slurmctld slurmd munge slurm-client (scripts/install_deps.sh)"
  done
  stop >/dev/null
  mkdir -p "$D/state" "$D/spool" "$D/log"
  if [ ! -s "$D/munge.key" ]; then
    dd if=/dev/urandom bs=1 count=1024 of="$D/munge.key" status=none
  fi
  chmod 400 "$D/munge.key"
  munged --force --key-file="$D/munge.key" --socket="$D/munge.socket" --pid-file="$D/munged.pid" \
    --log-file="$D/log/munged.log" --seed-file="$D/munged.seed"
  local host node
  host=$(hostname -s)
  # the node's real CPUs, sockets, cores and memory, as slurmd sees them
  node=$(slurmd -C | head -n 1 | sed -e 's/ UpTime=.*//')
  [[ "$node" == NodeName=* ]] || die "slurmd -C printed '$node'"
  cat >"$CONF" <<EOF
# written by scripts/slurm_cluster.sh
ClusterName=cosserat
SlurmctldHost=$host
SlurmctldPort=$PORT
SlurmdPort=$((PORT + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$D/munge.socket
StateSaveLocation=$D/state
SlurmdSpoolDir=$D/spool
SlurmctldPidFile=$D/slurmctld.pid
SlurmdPidFile=$D/slurmd.pid
SlurmctldLogFile=$D/log/slurmctld.log
SlurmdLogFile=$D/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
MpiDefault=none
ReturnToService=2
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MinJobAge=60
SlurmctldTimeout=30
SlurmdTimeout=30
$node State=UNKNOWN
PartitionName=batch Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
  slurmctld -c -f "$CONF" || die "slurmctld did not start; see $D/log/slurmctld.log"
  slurmd -f "$CONF" || die "slurmd did not start; see $D/log/slurmd.log"
  for _ in $(seq 100); do
    if sinfo --noheader --format=%t 2>/dev/null | grep -qE '^(idle|mix|alloc)'; then
      echo "Slurm cluster up: $(sinfo --noheader --format='%P %D node(s) %c CPUs %t' | head -n 1)"
      echo "export SLURM_CONF=$CONF"
      return 0
    fi
    sleep 0.1
  done
  sinfo >&2 || true
  die "the node did not become idle within 10 s; see $D/log/"
}

status() {
  pid_of slurmctld >/dev/null && pid_of slurmd >/dev/null || die "not running ($D)"
  sinfo
  echo "export SLURM_CONF=$CONF"
}

case "${1:-}" in
  start) start ;;
  stop) stop ;;
  status) status ;;
  *) die "usage: $0 start|stop|status" ;;
esac
