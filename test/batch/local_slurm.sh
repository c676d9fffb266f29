#!/usr/bin/env bash
# A one-node Slurm cluster on this machine from Debian's packages (munge, slurmctld, slurmd, slurm-client), for the
# batch tests (test/batch/test_batch_engines.cpp; doc/batch.md).
#   local_slurm.sh start DIR   generates DIR/slurm.conf (this host as controller and only node, free ports), starts a
#                              munged, slurmctld and slurmd of its own, waits until the node is idle; clients need
#                              SLURM_CONF=DIR/slurm.conf (DIR/env sets it)
#   local_slurm.sh stop DIR    cancels the cluster's jobs and stops the three daemons it started
# Everything (munge key and socket, state, spool, pid files, logs) is in DIR, so the cluster touches no system
# service: its munged listens on DIR/munge/munge.socket with a key of its own, and a munged of the machine, if any,
# is left alone. Run as root (slurmd runs the jobs as their submitter). Exit 1 with the daemon's log tail on failure.
set -uo pipefail

die() {
  echo "local_slurm: $1" >&2
  [ -n "${2:-}" ] && [ -f "$2" ] && { echo "--- last lines of $2:" >&2; tail -n 25 "$2" >&2; }
  exit 1
}

# A process that has exited (a zombie counts as exited: the sandbox's init may reap late).
alive() {
  local pid=$1
  [ -n "$pid" ] && [ -r "/proc/$pid/stat" ] && [ "$(cut -d' ' -f3 "/proc/$pid/stat" 2>/dev/null)" != Z ]
}

pid_of() { [ -f "$1" ] && cat "$1" 2>/dev/null; }

# TERM, then KILL after 10 s.
stop_pid() {
  local pid=$1
  alive "$pid" || return 0
  kill -TERM "$pid" 2>/dev/null
  for _ in $(seq 100); do alive "$pid" || return 0; sleep 0.1; done
  kill -KILL "$pid" 2>/dev/null
  for _ in $(seq 50); do alive "$pid" || return 0; sleep 0.1; done
}

# Two distinct TCP ports free at this moment (the kernel's choice, so never a fixed port that a parallel run shares).
free_ports() {
  /usr/bin/python3 -c '
import socket
sockets = [socket.socket() for _ in range(2)]
for s in sockets:
    s.bind(("127.0.0.1", 0))
print(" ".join(str(s.getsockname()[1]) for s in sockets))'
}

start_munge() {
  local m=$DIR/munge
  mkdir -p "$m" && chmod 711 "$m"
  [ -f "$m/munge.key" ] || /usr/sbin/mungekey -c -k "$m/munge.key" || die "mungekey could not create $m/munge.key"
  # --force: munged refuses to run as root without it.
  /usr/sbin/munged --force --socket="$m/munge.socket" --key-file="$m/munge.key" --pid-file="$m/munged.pid" \
    --log-file="$m/munged.log" --seed-file="$m/munged.seed" 2>>"$m/munged.log" ||
    die "munged did not start" "$m/munged.log"
  for _ in $(seq 50); do
    /usr/bin/munge -S "$m/munge.socket" -n 2>/dev/null | /usr/bin/unmunge -S "$m/munge.socket" >/dev/null 2>&1 &&
      return 0
    sleep 0.1
  done
  die "munged does not answer on $m/munge.socket (munge -n | unmunge)" "$m/munged.log"
}

write_conf() {
  local host ctld_port slurmd_port
  host=$(hostname -s)
  read -r ctld_port slurmd_port <<<"$(free_ports)"
  mkdir -p "$DIR/state" "$DIR/spool"
  cat >"$DIR/slurm.conf" <<EOF
# Written by local_slurm.sh: one node ($host), everything under $DIR.
ClusterName=implicit_sim_test
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$DIR/munge/munge.socket
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SwitchType=switch/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
# Schedule as soon as a task ends (the default waits up to 3 s between batch job starts).
SchedulerParameters=batch_sched_delay=0
ReturnToService=2
MailProg=/bin/true
StateSaveLocation=$DIR/state
SlurmdSpoolDir=$DIR/spool
SlurmctldPidFile=$DIR/slurmctld.pid
SlurmdPidFile=$DIR/slurmd.pid
SlurmctldLogFile=$DIR/slurmctld.log
SlurmdLogFile=$DIR/slurmd.log
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
  echo "export SLURM_CONF=$DIR/slurm.conf" >"$DIR/env"
}

# The daemons fork: their pid file appears a moment after the command returns (10 s).
wait_pid_file() {
  local name=$1
  for _ in $(seq 100); do
    alive "$(pid_of "$DIR/$name.pid")" && return 0
    sleep 0.1
  done
  die "$name did not write $DIR/$name.pid within 10 s, or exited" "$DIR/$name.log"
}

# Waits until sinfo shows the node idle (30 s).
wait_idle() {
  local state=""
  for _ in $(seq 300); do
    alive "$(pid_of "$DIR/slurmctld.pid")" || die "slurmctld exited" "$DIR/slurmctld.log"
    alive "$(pid_of "$DIR/slurmd.pid")" || die "slurmd exited" "$DIR/slurmd.log"
    state=$(sinfo -h -o %T 2>/dev/null)
    [ "$state" = idle ] && return 0
    sleep 0.1
  done
  echo "--- last lines of $DIR/slurmctld.log:" >&2
  tail -n 15 "$DIR/slurmctld.log" >&2
  die "the node is not idle after 30 s (sinfo: '${state:-no answer}')" "$DIR/slurmd.log"
}

start() {
  for cmd in /usr/sbin/munged /usr/sbin/slurmctld /usr/sbin/slurmd /usr/bin/sinfo /usr/bin/sbatch; do
    [ -x "$cmd" ] || die "$cmd is missing (Debian packages munge slurmctld slurmd slurm-client)"
  done
  mkdir -p "$DIR" || die "cannot create $DIR"
  start_munge
  write_conf
  export SLURM_CONF=$DIR/slurm.conf
  # -i: ignore state of an earlier cluster (there is none in a fresh DIR; a reused one may hold some).
  /usr/sbin/slurmctld -i -f "$SLURM_CONF" >>"$DIR/slurmctld.log" 2>&1 || die "slurmctld did not start" "$DIR/slurmctld.log"
  wait_pid_file slurmctld
  /usr/sbin/slurmd -f "$SLURM_CONF" >>"$DIR/slurmd.log" 2>&1 || die "slurmd did not start" "$DIR/slurmd.log"
  wait_pid_file slurmd
  wait_idle
  echo "local_slurm: node $(hostname -s) idle; SLURM_CONF=$SLURM_CONF"
}

# Cancels every job of the cluster (only this test's jobs run on it) and waits until none is left (20 s), so no
# slurmstepd outlives the daemons.
cancel_jobs() {
  alive "$(pid_of "$DIR/slurmctld.pid")" || return 0
  export SLURM_CONF=$DIR/slurm.conf
  scancel --full --user=root >/dev/null 2>&1
  for _ in $(seq 200); do
    [ -z "$(squeue -h -o %i 2>/dev/null)" ] && [ -z "$(find "$DIR/spool" -type s 2>/dev/null)" ] &&
      return 0
    sleep 0.1
  done
  echo "local_slurm: jobs still listed 20 s after scancel: $(squeue -h -o '%i %T' 2>/dev/null | tr '\n' ' ')" >&2
}

# Stops whatever a start (even a failed one) left running, by the pid files in DIR.
stop() {
  cancel_jobs
  stop_pid "$(pid_of "$DIR/slurmd.pid")"
  stop_pid "$(pid_of "$DIR/slurmctld.pid")"
  stop_pid "$(pid_of "$DIR/munge/munged.pid")"
  local left=""
  for name in slurmd slurmctld munge/munged; do
    alive "$(pid_of "$DIR/$name.pid")" && left="$left $name"
  done
  [ -z "$left" ] || die "still running after stop:$left"
}

[ $# -eq 2 ] || { echo "usage: local_slurm.sh {start|stop} DIR" >&2; exit 2; }
DIR=$(realpath -m "$2")
case "$1" in
  start) start ;;
  stop) stop ;;
  *) echo "usage: local_slurm.sh {start|stop} DIR" >&2; exit 2 ;;
esac
