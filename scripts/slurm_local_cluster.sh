#!/usr/bin/env bash
# A one-node SLURM cluster on this machine, to try the cluster path (scripts/slurm_array.sh) on a
# laptop or in CI without a real cluster:
#
#   scripts/slurm_local_cluster.sh start     # install slurm-wlm + munge if missing, start the daemons
#   export SLURM_CONF=/tmp/somnurbs-slurm/slurm.conf    # (start prints this line)
#   scripts/slurm_array.sh experiments/ch6_same.toml 3 --profile quick
#   scripts/slurm_local_cluster.sh status
#   scripts/slurm_local_cluster.sh stop      # stop the daemons it started, by their PIDs
#
# It needs root (or sudo) to install packages and to run munged as the munge user; no systemd is
# needed: munged, slurmctld and slurmd are started by hand. Everything the cluster writes (config,
# state, spool, PID and log files) lives in SOMNURBS_SLURM_DIR (default /tmp/somnurbs-slurm); the
# config names one node, `hostname -s` with `nproc` CPUs, in one default partition, and no
# accounting (use squeue/scontrol, not sacct). SOMNURBS_SLURM_TIMEOUT (default 60) bounds the wait
# for the node to be idle, in seconds. SOMNURBS_SLURM_PORT (default 6817) is slurmctld's port;
# slurmd listens on the next one.
set -euo pipefail

dir="${SOMNURBS_SLURM_DIR:-/tmp/somnurbs-slurm}"
timeout="${SOMNURBS_SLURM_TIMEOUT:-60}"
port="${SOMNURBS_SLURM_PORT:-6817}"
conf="$dir/slurm.conf"
node="$(hostname -s)"
export SLURM_CONF="$conf"

say() { echo "slurm_local_cluster: $*"; }
die() { echo "slurm_local_cluster: error: $*" >&2; exit 2; }

# Run as root, through sudo when we are not root.
as_root() {
  if [ "$(id -u)" = 0 ]; then "$@"; else sudo "$@"; fi
}

# The PID in a PID file when that process is alive and is the named program, else nothing.
live_pid() {
  local file="$1" prog="$2" pid
  [ -r "$file" ] || return 0
  pid="$(tr -dc 0-9 <"$file")"
  [ -n "$pid" ] && [ -r "/proc/$pid/comm" ] && [ "$(cat "/proc/$pid/comm")" = "$prog" ] && echo "$pid"
  return 0
}

install_packages() {
  local missing=()
  command -v slurmctld >/dev/null && command -v slurmd >/dev/null && command -v sbatch >/dev/null || missing+=(slurm-wlm)
  command -v munged >/dev/null || missing+=(munge)
  [ ${#missing[@]} = 0 ] && return 0
  command -v apt-get >/dev/null || die "${missing[*]} missing and no apt-get here: install them with your package manager"
  say "installing ${missing[*]}"
  # Update the package lists only when they do not know the packages yet.
  if ! apt-cache show "${missing[@]}" >/dev/null 2>&1; then
    as_root apt-get update -qq
  fi
  as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}

start_munge() {
  # A munged that already answers (the system's, or ours from an earlier start) is used as is.
  if munge -n </dev/null 2>/dev/null | unmunge >/dev/null 2>&1; then
    say "munged already running"
    return 0
  fi
  if ! as_root test -s /etc/munge/munge.key; then
    say "creating /etc/munge/munge.key"
    as_root mkdir -p /etc/munge
    as_root sh -c 'umask 077; dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 2>/dev/null'
    as_root chown munge:munge /etc/munge/munge.key
    as_root chmod 400 /etc/munge/munge.key
  fi
  as_root mkdir -p /run/munge /var/lib/munge /var/log/munge
  as_root chown munge:munge /run/munge /var/lib/munge /var/log/munge
  as_root chmod 755 /run/munge
  as_root runuser -u munge -- /usr/sbin/munged
  local pid
  pid="$(as_root cat /run/munge/munged.pid)"
  echo "$pid" >"$dir/munged.pid"   # ours to stop
  for _ in $(seq 1 50); do
    munge -n </dev/null 2>/dev/null | unmunge >/dev/null 2>&1 && return 0
    sleep 0.1
  done
  die "munged (PID $pid) does not answer; see /var/log/munge/munged.log"
}

write_conf() {
  local cpus
  cpus="$(nproc)"
  mkdir -p "$dir/state" "$dir/spool"
  cat >"$conf" <<EOF
# One-node cluster written by scripts/slurm_local_cluster.sh: node $node, $cpus CPUs.
ClusterName=somnurbs
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
MpiDefault=none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
ReturnToService=2
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
NodeName=$node NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=local Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
}

node_state() { sinfo -h -n "$node" -o %T 2>/dev/null | head -n 1; }

start() {
  [ "$(id -u)" = 0 ] || command -v sudo >/dev/null || die "run as root (or with sudo available)"
  if [ -n "$(live_pid "$dir/slurmctld.pid" slurmctld)" ] || [ -n "$(live_pid "$dir/slurmd.pid" slurmd)" ]; then
    die "a cluster from $dir is already running (scripts/slurm_local_cluster.sh stop first)"
  fi
  install_packages
  mkdir -p "$dir"
  rm -rf "$dir/state" "$dir/spool" "$dir/munged.pid"
  write_conf
  start_munge
  as_root slurmctld -f "$conf" || { stop; die "slurmctld did not start; see $dir/slurmctld.log"; }
  as_root slurmd -f "$conf" || { stop; die "slurmd did not start; see $dir/slurmd.log"; }
  local t0=$SECONDS state=""
  while [ $((SECONDS - t0)) -lt "$timeout" ]; do
    state="$(node_state)"
    case "$state" in
      idle*) say "node $node idle after $((SECONDS - t0)) s ($(nproc) CPUs); config $conf"
             echo "export SLURM_CONF=$conf"
             return 0 ;;
      down*|drain*) as_root scontrol update nodename="$node" state=resume >/dev/null 2>&1 || true ;;
    esac
    sleep 0.2
  done
  echo "slurm_local_cluster: error: node $node not idle after $timeout s (state: ${state:-none}); last log lines:" >&2
  tail -n 5 "$dir/slurmctld.log" "$dir/slurmd.log" >&2 || true
  stop
  exit 1
}

# Stop one daemon by its PID file: TERM, wait up to 10 s, then KILL.
stop_daemon() {
  local file="$1" prog="$2" pid
  pid="$(live_pid "$file" "$prog")"
  if [ -z "$pid" ]; then
    rm -f "$file"
    return 0
  fi
  as_root kill -TERM "$pid" 2>/dev/null || true
  for _ in $(seq 1 100); do
    [ -d "/proc/$pid" ] || break
    sleep 0.1
  done
  if [ -d "/proc/$pid" ]; then as_root kill -KILL "$pid" 2>/dev/null || true; fi
  say "stopped $prog (PID $pid)"
  rm -f "$file"
}

stop() {
  # Cancel what is left (a running job's processes belong to slurmstepd, not slurmd).
  if [ -n "$(live_pid "$dir/slurmctld.pid" slurmctld)" ]; then
    local jobs
    jobs="$(squeue -h -o %A 2>/dev/null | sort -u | tr '\n' ' ')"
    if [ -n "${jobs// /}" ]; then
      say "cancelling jobs $jobs"
      # shellcheck disable=SC2086
      scancel $jobs 2>/dev/null || true
      for _ in $(seq 1 50); do
        [ -z "$(squeue -h -o %A 2>/dev/null)" ] && break
        sleep 0.2
      done
    fi
  fi
  stop_daemon "$dir/slurmd.pid" slurmd
  stop_daemon "$dir/slurmctld.pid" slurmctld
  stop_daemon "$dir/munged.pid" munged
}

status() {
  local running=0 pid
  for d in slurmctld slurmd munged; do
    pid="$(live_pid "$dir/$d.pid" "$d")"
    if [ -n "$pid" ]; then echo "$d: running (PID $pid)"; running=1; else echo "$d: not running (from $dir)"; fi
  done
  if [ "$running" = 1 ] && [ -r "$conf" ]; then
    echo "export SLURM_CONF=$conf"
    sinfo || true
    squeue || true
  fi
}

case "${1:-}" in
  start) start ;;
  stop) stop ;;
  status) status ;;
  *) echo "usage: scripts/slurm_local_cluster.sh start|stop|status" >&2; exit 2 ;;
esac
