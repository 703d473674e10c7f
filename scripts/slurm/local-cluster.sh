#!/usr/bin/env bash
# A throw-away single-machine Slurm cluster (munged + slurmctld + slurmd on this host), everything
# (config, keys, state, logs, sockets) in one folder; no system service is used or left running.
# Used by the Slurm test (tests/dist) and for trying the job scripts on a laptop.
#
#   scripts/slurm/local-cluster.sh start DIR   # prints "export SLURM_CONF=DIR/slurm.conf"
#   scripts/slurm/local-cluster.sh stop DIR    # stops exactly the daemons started for DIR
#
# Works without systemd and without cgroups (containers): proctrack/linuxproc, task/none, no
# cgroup plugins, no accounting daemon. Exit 3 when the daemons cannot start (the reason on stderr).
set -euo pipefail

cmd=${1:-}
dir=${2:-}
[[ -n "$cmd" && -n "$dir" ]] || { echo "usage: $0 start|stop DIR" >&2; exit 2; }

stop_pid() {  # stop the daemon whose pid file is $1 (only that pid), wait up to 10 s
  local f=$1 pid
  [[ -f "$f" ]] || return 0
  pid=$(cat "$f" 2>/dev/null || true)
  if [[ -n "$pid" ]] && kill -0 "$pid" 2>/dev/null; then
    kill -TERM "$pid" 2>/dev/null || true
    for _ in $(seq 100); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -0 "$pid" 2>/dev/null && kill -KILL "$pid" 2>/dev/null || true
  fi
  rm -f "$f"
}

if [[ "$cmd" == stop ]]; then
  stop_pid "$dir/slurmd.pid"
  stop_pid "$dir/slurmctld.pid"
  stop_pid "$dir/munged.pid"
  exit 0
fi
[[ "$cmd" == start ]] || { echo "usage: $0 start|stop DIR" >&2; exit 2; }

for b in munged slurmctld slurmd sbatch sinfo; do
  command -v "$b" >/dev/null || { echo "local-cluster: $b not installed (apt-get install slurm-wlm munge)" >&2; exit 3; }
done
mkdir -p "$dir"
dir=$(cd "$dir" && pwd)
mkdir -p "$dir/state" "$dir/spool" "$dir/log" "$dir/munge"
chmod 700 "$dir/munge"

fail() {
  echo "local-cluster: $1" >&2
  for l in "$dir"/log/*.log; do [[ -f "$l" ]] && { echo "--- $l" >&2; tail -5 "$l" >&2; }; done
  "$0" stop "$dir" || true
  exit 3
}

# munge: a fresh key and a private socket.
dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$dir/munge/munge.key"
munged --key-file="$dir/munge/munge.key" --socket="$dir/munge/munge.socket" --pid-file="$dir/munged.pid" \
  --log-file="$dir/log/munged.log" --seed-file="$dir/munge/munged.seed" --force >/dev/null 2>&1 ||
  fail "munged did not start"

# Two free TCP ports near a value derived from the folder, so parallel clusters do not collide.
port_free() { ! (echo >"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }
base=$((20000 + $(cksum <<<"$dir" | cut -d' ' -f1) % 20000))
while ! port_free "$base" || ! port_free $((base + 1)); do base=$((base + 2)); done

host=$(hostname -s)
cpus=$(nproc)
mem=$(($(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 / 2))
user=$(id -un)
cat >"$dir/slurm.conf" <<CONF
# Written by scripts/slurm/local-cluster.sh: one node, this host, no cgroups, no accounting.
ClusterName=proctex-local
SlurmctldHost=${host}(127.0.0.1)
SlurmctldPort=${base}
SlurmdPort=$((base + 1))
SlurmUser=${user}
SlurmdUser=${user}
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=${dir}/munge/munge.socket,cred_expire=5
StateSaveLocation=${dir}/state
SlurmdSpoolDir=${dir}/spool/%n
SlurmctldPidFile=${dir}/slurmctld.pid
SlurmdPidFile=${dir}/slurmd.pid
SlurmctldLogFile=${dir}/log/slurmctld.log
SlurmdLogFile=${dir}/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=30
InactiveLimit=0
MinJobAge=300
KillWait=5
Waittime=0
SchedulerParameters=sched_interval=1,bf_interval=1
MessageTimeout=10
NodeName=${host} NodeAddr=127.0.0.1 CPUs=${cpus} RealMemory=${mem} State=UNKNOWN
PartitionName=debug Nodes=${host} Default=YES MaxTime=INFINITE State=UP OverSubscribe=NO
CONF
export SLURM_CONF="$dir/slurm.conf"
slurmctld -f "$SLURM_CONF" -i >>"$dir/log/slurmctld.out" 2>&1 || fail "slurmctld did not start"
slurmd -f "$SLURM_CONF" >>"$dir/log/slurmd.out" 2>&1 || fail "slurmd did not start"
for _ in $(seq 150); do
  state=$(sinfo -h -N -o %t 2>/dev/null | head -1 || true)
  [[ "$state" == idle* || "$state" == mix* ]] && { echo "export SLURM_CONF=$SLURM_CONF"; exit 0; }
  sleep 0.2
done
fail "the node did not become idle within 30 s (state: ${state:-none})"
