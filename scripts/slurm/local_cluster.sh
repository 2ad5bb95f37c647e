#!/usr/bin/env bash
# A one-node Slurm cluster on this machine, for tests and demos. Run as root.
#
#   scripts/slurm/local_cluster.sh start DIR    generate DIR/slurm.conf and a munge key, start
#                                               munged, slurmctld and slurmd, wait for the node
#   scripts/slurm/local_cluster.sh stop DIR     cancel the cluster's jobs, stop exactly the
#                                               daemons started in DIR and wait for them to exit
#   scripts/slurm/local_cluster.sh status DIR   which daemons run, and sinfo (exit 0 when all run)
#
# Everything lives under DIR: slurm.conf, cgroup.conf, munge/ (key, socket, pid, log, seed),
# state/ (StateSaveLocation), spool/ (SlurmdSpoolDir), log/ and run/ (pid files). The munged
# started here uses its own socket, so it does not clash with a system munge. Use the cluster with
#   export SLURM_CONF=DIR/slurm.conf
# before sinfo, sbatch, squeue, scancel (start prints it).
#
# Environment:
#   TWIN_SLURMCTLD_PORT  port of slurmctld (default 47817)
#   TWIN_SLURMD_PORT     port of slurmd (default 47818)
#   TWIN_SLURM_TIMEOUT   seconds to wait for the node to come up / the daemons to exit (default 60)
#
# Needs Debian's slurmctld, slurmd, slurm-client and munge (scripts/install_deps.sh installs them).
set -euo pipefail

CTLD_PORT="${TWIN_SLURMCTLD_PORT:-47817}"
SLURMD_PORT="${TWIN_SLURMD_PORT:-47818}"
TIMEOUT="${TWIN_SLURM_TIMEOUT:-60}"

die() { echo "local_cluster: error: $*" >&2; exit 1; }
log() { echo "local_cluster: $*"; }

usage() {
  echo "usage: $0 start DIR | stop DIR | status DIR" >&2
  exit 2
}

[ $# -eq 2 ] || usage
ACTION="$1"
[ -n "$2" ] || usage
case "$ACTION" in start | stop | status) ;; *) usage ;; esac

# Absolute DIR: the daemons and the jobs run in other working directories.
if [ "$ACTION" = start ]; then
  mkdir -p "$2"
elif [ ! -d "$2" ]; then
  echo "local_cluster: no folder $2" >&2
  exit 1
fi
DIR="$(cd "$2" && pwd -P)"
CONF="$DIR/slurm.conf"
MUNGE_SOCKET="$DIR/munge/munge.socket.2"
NODE="$(hostname -s)"

# name:pid-file:log, in start order (stop goes the other way).
DAEMONS=(
  "munged:$DIR/munge/munged.pid:$DIR/munge/munged.log"
  "slurmctld:$DIR/run/slurmctld.pid:$DIR/log/slurmctld.log"
  "slurmd:$DIR/run/slurmd.pid:$DIR/log/slurmd.log"
)

pidfile_of() {
  local d name pidfile logf
  for d in "${DAEMONS[@]}"; do
    IFS=: read -r name pidfile logf <<<"$d"
    [ "$name" = "$1" ] && echo "$pidfile" && return 0
  done
  return 1
}

# The pid recorded in a pid file, when that process is alive and is the daemon named (a pid file
# left behind may name a pid reused by an unrelated process).
live_pid() {
  local name="$1" pidfile="$2" pid comm
  [ -s "$pidfile" ] || return 1
  pid="$(tr -dc '0-9' <"$pidfile")"
  [ -n "$pid" ] || return 1
  comm="$(cat "/proc/$pid/comm" 2>/dev/null)" || return 1
  # comm is cut at 15 characters; slurmctld may show as slurmctld-wlm through the alternative.
  case "$comm" in "$name"*) echo "$pid" ;; *) return 1 ;; esac
}

# Processes left by this cluster's jobs once its daemons are gone: slurmstepd processes (slurmd
# passes its environment, with SLURM_CONF=$CONF set when starting it, to them; they outlive
# slurmd), everything below them, and job processes (SLURM_JOB_ID set and SLURM_CONF=$CONF)
# that escaped that tree. Never this script or its ancestors.
leftover_pids() {
  local p pid ppid rest comm e
  local -a envs
  local -A parent=() pick=() mine=()
  # Builtins only (read, mapfile): a fork per process would make this take seconds.
  for p in /proc/[0-9]*; do
    pid="${p#/proc/}"
    { read -r rest <"$p/stat"; } 2>/dev/null || continue
    rest="${rest##*) }" # after "pid (comm) "
    ppid="${rest#* }"
    parent[$pid]="${ppid%% *}"
    { read -r comm <"$p/comm"; } 2>/dev/null || continue
    { mapfile -d '' -t envs <"$p/environ"; } 2>/dev/null || continue
    local conf=0 job=0
    for e in "${envs[@]}"; do
      case "$e" in
        "SLURM_CONF=$CONF") conf=1 ;;
        SLURM_JOB_ID=*) job=1 ;;
      esac
    done
    if [ $conf -eq 1 ] && { [ "$comm" = slurmstepd ] || [ $job -eq 1 ]; }; then
      pick[$pid]=1
    fi
  done
  pid=$$
  while [ -n "$pid" ] && [ "$pid" != 0 ]; do
    mine[$pid]=1
    pid="${parent[$pid]:-}"
  done
  # Descendants of what was picked (a job may have cleared its environment).
  local changed=1
  while [ $changed -eq 1 ]; do
    changed=0
    for pid in "${!parent[@]}"; do
      if [ -z "${pick[$pid]:-}" ] && [ -n "${pick[${parent[$pid]}]:-}" ]; then
        pick[$pid]=1
        changed=1
      fi
    done
  done
  for pid in "${!pick[@]}"; do
    [ -n "${mine[$pid]:-}" ] || echo "$pid"
  done
}

port_in_use() {
  ss -Htln "sport = :$1" 2>/dev/null | grep -q .
}

require_tools() {
  local t missing=()
  for t in munged slurmctld slurmd sinfo squeue scancel; do
    command -v "$t" >/dev/null 2>&1 || missing+=("$t")
  done
  [ ${#missing[@]} -eq 0 ] ||
    die "not installed: ${missing[*]} (scripts/install_deps.sh installs slurmctld slurmd slurm-client munge)"
}

write_conf() {
  local cpus
  cpus="$(nproc)"
  cat >"$CONF" <<EOF
# Generated by scripts/slurm/local_cluster.sh: a one-node cluster for tests, all state under
# $DIR.
ClusterName=twinbenchlocal
SlurmctldHost=$NODE(127.0.0.1)
SlurmctldPort=$CTLD_PORT
SlurmdPort=$SLURMD_PORT
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$MUNGE_SOCKET
StateSaveLocation=$DIR/state
SlurmdSpoolDir=$DIR/spool
SlurmctldPidFile=$DIR/run/slurmctld.pid
SlurmdPidFile=$DIR/run/slurmd.pid
SlurmctldLogFile=$DIR/log/slurmctld.log
SlurmdLogFile=$DIR/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
PlugStackConfig=$DIR/plugstack.conf
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SwitchType=switch/none
SchedulerType=sched/backfill
MailProg=/bin/true
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
NodeName=$NODE NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=local Nodes=$NODE Default=YES MaxTime=INFINITE State=UP
EOF
  : >"$DIR/plugstack.conf"
}

start_munged() {
  local key="$DIR/munge/munge.key"
  if [ ! -s "$key" ]; then
    if command -v mungekey >/dev/null 2>&1; then
      mungekey --create --keyfile="$key" >/dev/null
    else
      dd if=/dev/urandom of="$key" bs=1 count=1024 status=none
    fi
  fi
  chmod 0400 "$key"
  munged --key-file="$key" --socket="$MUNGE_SOCKET" --pid-file="$DIR/munge/munged.pid" \
    --log-file="$DIR/munge/munged.log" --seed-file="$DIR/munge/munged.seed" ||
    die "munged did not start; read $DIR/munge/munged.log"
  # A credential round trip through the new socket.
  local i
  for ((i = 0; i < 50; i++)); do
    if munge -n -S "$MUNGE_SOCKET" 2>/dev/null | unmunge -S "$MUNGE_SOCKET" >/dev/null 2>&1; then
      return 0
    fi
    sleep 0.1
  done
  die "munged does not answer on $MUNGE_SOCKET; read $DIR/munge/munged.log"
}

node_state() {
  sinfo -h -n "$NODE" -o %T 2>/dev/null | head -n1 || true
}

cmd_start() {
  require_tools
  [ "$(id -u)" -eq 0 ] || die "run as root (the daemons run as SlurmUser=root)"
  local d name pidfile logf pid
  for d in "${DAEMONS[@]}"; do
    IFS=: read -r name pidfile logf <<<"$d"
    if pid="$(live_pid "$name" "$pidfile")"; then
      die "$name already runs from $DIR (pid $pid); run: $0 stop $DIR"
    fi
  done
  [ "$CTLD_PORT" != "$SLURMD_PORT" ] || die "TWIN_SLURMCTLD_PORT and TWIN_SLURMD_PORT must differ"
  for p in "$CTLD_PORT" "$SLURMD_PORT"; do
    if port_in_use "$p"; then
      die "port $p is in use (another cluster?); choose others with TWIN_SLURMCTLD_PORT / TWIN_SLURMD_PORT"
    fi
  done

  mkdir -p "$DIR/munge" "$DIR/state" "$DIR/spool" "$DIR/log" "$DIR/run"
  # munged wants the folders above its socket searchable by all (mktemp -d makes 0700 ones);
  # search only, not listing, for DIR. The key stays 0400.
  chmod go+x "$DIR"
  chmod 0755 "$DIR/munge"
  write_conf
  export SLURM_CONF="$CONF"

  local t0=$SECONDS
  start_munged
  # -c: a fresh start; recovered node state would read "idle" before slurmd has registered.
  slurmctld -c -f "$CONF" || die "slurmctld did not start; read $DIR/log/slurmctld.log"
  slurmd -f "$CONF" -N "$NODE" || die "slurmd did not start; read $DIR/log/slurmd.log"

  local state=""
  while :; do
    state="$(node_state)"
    [ "$state" = "idle" ] && break
    for d in "${DAEMONS[@]}"; do
      IFS=: read -r name pidfile logf <<<"$d"
      # Daemons write their pid file shortly after forking; give them a moment before judging.
      if ((SECONDS - t0 > 3)) && ! live_pid "$name" "$pidfile" >/dev/null; then
        echo "local_cluster: error: $name exited during start-up; read $logf:" >&2
        tail -n 20 "$logf" >&2 2>/dev/null || true
        exit 1
      fi
    done
    if ((SECONDS - t0 >= TIMEOUT)); then
      echo "local_cluster: error: node $NODE not idle after ${TIMEOUT} s (state: '${state:-none}');" \
        "read $DIR/log/slurmctld.log and $DIR/log/slurmd.log:" >&2
      tail -n 10 "$DIR/log/slurmctld.log" "$DIR/log/slurmd.log" >&2 2>/dev/null || true
      exit 1
    fi
    sleep 0.5
  done
  log "node $NODE idle after $((SECONDS - t0)) s (ports $CTLD_PORT, $SLURMD_PORT); use it with"
  echo "  export SLURM_CONF=$CONF"
}

cmd_stop() {
  export SLURM_CONF="$CONF"
  local d name pidfile logf pid pids=() t0=$SECONDS
  # Cancel the jobs first so that their slurmstepd processes end cleanly.
  if live_pid slurmctld "$DIR/run/slurmctld.pid" >/dev/null && [ -f "$CONF" ]; then
    local jobs
    jobs="$(squeue -h -o %A 2>/dev/null | sort -u || true)"
    if [ -n "$jobs" ]; then
      # shellcheck disable=SC2086
      scancel $jobs 2>/dev/null || true
      while [ -n "$(squeue -h -o %A 2>/dev/null || true)" ] && ((SECONDS - t0 < 15)); do
        sleep 0.5
      done
    fi
  fi
  # slurmd and slurmctld together, then munged (they use it while shutting down).
  local group
  for group in "slurmd slurmctld" "munged"; do
    local waiting=()
    for name in $group; do
      if pid="$(live_pid "$name" "$(pidfile_of "$name")")"; then
        kill -TERM "$pid" 2>/dev/null || true
        waiting+=("$pid")
        pids+=("$pid")
      fi
    done
    for pid in "${waiting[@]}"; do wait_gone "$pid"; done
  done
  local left
  left="$(leftover_pids)"
  if [ -n "$left" ]; then
    # shellcheck disable=SC2086
    kill -KILL $left 2>/dev/null || true
    for pid in $left; do
      pids+=("$pid")
      wait_gone "$pid"
    done
  fi
  rm -f "$DIR/munge/munged.pid" "$DIR/run/slurmctld.pid" "$DIR/run/slurmd.pid"
  if [ ${#pids[@]} -eq 0 ]; then
    log "nothing was running from $DIR"
  else
    log "stopped ${pids[*]} in $((SECONDS - t0)) s"
  fi
}

# Waits for a pid to exit, TERM first, then KILL after the timeout.
wait_gone() {
  local pid="$1" t0=$SECONDS
  while kill -0 "$pid" 2>/dev/null; do
    if ((SECONDS - t0 >= TIMEOUT)); then
      echo "local_cluster: pid $pid did not exit after SIGTERM in ${TIMEOUT} s; sending SIGKILL" >&2
      kill -KILL "$pid" 2>/dev/null || true
      sleep 0.5
      kill -0 "$pid" 2>/dev/null && die "pid $pid survives SIGKILL"
      return 0
    fi
    sleep 0.1
  done
}

cmd_status() {
  local d name pidfile logf pid all=0
  for d in "${DAEMONS[@]}"; do
    IFS=: read -r name pidfile logf <<<"$d"
    if pid="$(live_pid "$name" "$pidfile")"; then
      echo "$name: running (pid $pid)"
    else
      echo "$name: not running"
      all=1
    fi
  done
  if [ $all -eq 0 ]; then
    SLURM_CONF="$CONF" sinfo -N -o '%N %T %c' || all=1
  fi
  return $all
}

case "$ACTION" in
  start) cmd_start ;;
  stop) cmd_stop ;;
  status) cmd_status ;;
esac
