#!/bin/bash
# A single-node Slurm on localhost for tests and benchmarks, sourced: start_slurm starts munged,
# slurmctld and slurmd as the current user (root in CI: no systemd, daemons started directly, in the
# foreground, their pids appended to the caller's array `pids`, which the caller kills on exit), with
# a munge key and a slurm.conf written into a fresh folder $S under /tmp (slurm.conf takes no spaces
# in paths), free TCP ports, the machine's real CPU count and 80% of its memory, proctrack/linuxproc,
# task/none (no cgroups). Exports SLURM_CONF for sbatch, squeue, sinfo. Fails (exit 1) when a program
# is missing or the node does not come up within 40 s.
#   source slurm_single_node.sh; pids=(); trap stop_daemons EXIT; start_slurm

free_port() {  # a TCP port nobody listens on
  local p
  for _ in $(seq 100); do
    p=$((20000 + RANDOM % 30000))
    if ! (exec 3<>"/dev/tcp/127.0.0.1/$p") 2>/dev/null; then echo "$p"; return; fi
  done
  echo "no free port" >&2; return 1
}

start_slurm() {
  for p in munged slurmctld slurmd sbatch squeue sinfo scontrol; do
    command -v "$p" >/dev/null || { echo "FAIL: $p is not installed (scripts/install-deps.sh --test)" >&2; exit 1; }
  done
  # slurm.conf takes no spaces in paths: the daemons' state lives in a folder of its own
  S=$(mktemp -d /tmp/tpkit-slurm.XXXXXX)
  mkdir -p "$S/state" "$S/spool" "$S/munge"
  chmod 700 "$S/munge"
  dd if=/dev/urandom of="$S/munge/munge.key" bs=1024 count=1 status=none
  chmod 400 "$S/munge/munge.key"
  munged --force --key-file="$S/munge/munge.key" --socket="$S/munge/munge.socket" --pid-file="$S/munge/munged.pid" \
    --log-file="$S/munge.log" --seed-file="$S/munge/seed" --foreground 2>>"$S/munged.log" &
  pids+=($!)
  for _ in $(seq 50); do [ -S "$S/munge/munge.socket" ] && break; sleep 0.1; done
  [ -S "$S/munge/munge.socket" ] || { echo "FAIL: munged did not start" >&2; exit 1; }
  local cpus mem
  cpus=$(nproc)
  mem=$(awk '/MemTotal/ { printf "%d", $2 / 1024 * 0.8 }' /proc/meminfo)
  cat > "$S/slurm.conf" <<CONF
ClusterName=tpkittest
SlurmctldHost=localhost
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$(free_port)
SlurmdPort=$(free_port)
AuthType=auth/munge
AuthInfo=socket=$S/munge/munge.socket
CredType=cred/munge
StateSaveLocation=$S/state
SlurmdSpoolDir=$S/spool
SlurmctldPidFile=$S/slurmctld.pid
SlurmdPidFile=$S/slurmd.pid
SlurmctldLogFile=$S/slurmctld.log
SlurmdLogFile=$S/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
ReturnToService=2
SchedulerType=sched/builtin
SchedulerParameters=kill_invalid_depend
MaxArraySize=1001
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=tpkit Nodes=localhost Default=YES MaxTime=INFINITE State=UP
CONF
  export SLURM_CONF="$S/slurm.conf"
  slurmctld -D -i -f "$SLURM_CONF" 2>>"$S/slurmctld.stderr.log" &
  pids+=($!)
  slurmd -D -N localhost -f "$SLURM_CONF" 2>>"$S/slurmd.stderr.log" &
  pids+=($!)
  for _ in $(seq 200); do
    [ "$(sinfo -h -o %T 2>/dev/null)" = idle ] && return 0
    for p in "${pids[@]}"; do kill -0 "$p" 2>/dev/null || { echo "FAIL: a Slurm daemon exited" >&2; exit 1; }; done
    sleep 0.2
  done
  echo "FAIL: the Slurm node did not come up: $(sinfo -h -o '%T %E' 2>&1)" >&2
  exit 1
}


# Stops every process of `pids` (TERM, then KILL after 5 s) and removes $S.
stop_daemons() {
  local p
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  for p in "${pids[@]}"; do
    for _ in $(seq 50); do kill -0 "$p" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$p" 2>/dev/null || true
  done
  if [ -n "${S:-}" ]; then rm -rf "$S"; fi
}
