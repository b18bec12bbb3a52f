#!/usr/bin/env bash
# A two-node Slurm cluster on one host, for crates/cli/tests/sweep_slurm.rs: MUNGE, slurmctld and
# two slurmd (node1, node2: distinct names and ports, both at localhost), every daemon in the
# foreground as a child of this script, stopped by its pid on exit (the trap). Run it inside a
# private network namespace (`unshare -n`), where only loopback exists: nothing listens outside.
#
#   cluster.sh WORK COMMAND...   starts the cluster under WORK (state, logs, keys), waits until both
#                                nodes are idle, runs COMMAND with SLURM_CONF set, waits until the
#                                queue is empty, and stops the cluster. Every wait is bounded.
set -euo pipefail
work="$1"
shift
PATH="$PATH:/usr/sbin:/sbin"
mkdir -p "$work"/{munge,ctld,node1,node2,log,run}
chmod 700 "$work/munge"
pids=()
stop() {
  local status=$?
  # Reverse order: the nodes, the controller, then MUNGE; each by the pid it was started with.
  for ((i = ${#pids[@]} - 1; i >= 0; i--)); do
    kill "${pids[i]}" 2>/dev/null || true
  done
  for pid in "${pids[@]}"; do
    for _ in $(seq 1 50); do
      kill -0 "$pid" 2>/dev/null || break
      sleep 0.1
    done
    kill -9 "$pid" 2>/dev/null || true
    wait "$pid" 2>/dev/null || true
  done
  exit "$status"
}
trap stop EXIT
ip link set lo up
head -c 1024 /dev/urandom >"$work/munge/munge.key"
chmod 600 "$work/munge/munge.key"
socket="$work/munge/munge.socket"
munged --foreground --force --key-file="$work/munge/munge.key" --socket="$socket" \
  --pid-file="$work/munge/munged.pid" --log-file="$work/log/munged.log" --seed-file="$work/munge/seed" &
pids+=($!)
user="$(id -un)"
# EnableIPv6: with only loopback in the namespace, glibc resolves nothing for an AF_INET lookup with
# AI_ADDRCONFIG (Slurm's default); AF_UNSPEC, which this option makes Slurm use, finds 127.0.0.1.
cat >"$work/slurm.conf" <<CONF
ClusterName=coopnavtest
CommunicationParameters=EnableIPv6
SlurmctldHost=localhost
SlurmctldPort=16817
AuthType=auth/munge
AuthInfo=socket=$socket
CredType=cred/munge
SlurmUser=$user
SlurmdUser=$user
StateSaveLocation=$work/ctld
SlurmdSpoolDir=$work/%n
SlurmctldPidFile=$work/run/slurmctld.pid
SlurmdPidFile=$work/run/slurmd-%n.pid
SlurmctldLogFile=$work/log/slurmctld.log
SlurmdLogFile=$work/log/slurmd-%n.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/builtin
MpiDefault=none
ReturnToService=2
SlurmdParameters=config_overrides
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
NodeName=node1 NodeHostname=localhost Port=16818 CPUs=1 State=UNKNOWN
NodeName=node2 NodeHostname=localhost Port=16819 CPUs=1 State=UNKNOWN
PartitionName=test Nodes=node1,node2 Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$work/slurm.conf"
for _ in $(seq 1 50); do
  [ -S "$socket" ] && break
  sleep 0.1
done
slurmctld -D -i >"$work/log/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -N node1 >"$work/log/slurmd-node1.out" 2>&1 &
pids+=($!)
slurmd -D -N node2 >"$work/log/slurmd-node2.out" 2>&1 &
pids+=($!)
idle=""
for _ in $(seq 1 120); do
  if [ "$(sinfo -h -N -o '%N %t' 2>/dev/null | grep -c ' idle$')" = 2 ]; then
    idle=1
    break
  fi
  sleep 0.5
done
if [ -z "$idle" ]; then
  echo "the two nodes did not come up within 60 s:" >&2
  sinfo -N 2>&1 >&2 || true
  tail -n 20 "$work"/log/*.log >&2 || true
  exit 1
fi
"$@"
for _ in $(seq 1 600); do
  if [ -z "$(squeue -h 2>/dev/null)" ]; then
    exit 0
  fi
  sleep 0.5
done
echo "the queue did not empty within 300 s:" >&2
squeue >&2 || true
exit 1
