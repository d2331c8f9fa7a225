#!/usr/bin/env bash
# A single-node Slurm cluster on localhost for the tests, from Debian's
# packages (munge, slurmctld, slurmd, slurm-client), with no systemd: every
# daemon runs in the foreground (-D / -F) as a child of this script's
# caller's session, with its state, sockets, logs and configuration under
# one folder, and is stopped by the PIDs recorded there.
#
#   local_cluster.sh start DIR   # prints nothing; DIR/env holds SLURM_CONF
#   local_cluster.sh stop DIR    # kills the daemons it started, by PID
#
# Exit status: 0 up (or stopped); 1 a daemon did not come up (its log is
# printed); 77 the packages are missing (the caller reports a skip).
set -euo pipefail

cmd="${1:-}"
dir="${2:-}"
[[ -n "$cmd" && -n "$dir" ]] || { echo "usage: $0 start|stop DIR" >&2; exit 2; }

stop() {
  [[ -f "$dir/pids" ]] || return 0
  local pid
  while read -r pid; do kill -TERM "$pid" 2>/dev/null || true; done < "$dir/pids"
  for _ in $(seq 50); do
    local alive=0
    while read -r pid; do kill -0 "$pid" 2>/dev/null && alive=1; done < "$dir/pids"
    [[ $alive == 0 ]] && break
    sleep 0.1
  done
  while read -r pid; do kill -KILL "$pid" 2>/dev/null || true; done < "$dir/pids"
  rm -f "$dir/pids"
}

if [[ "$cmd" == stop ]]; then stop; exit 0; fi
[[ "$cmd" == start ]] || { echo "usage: $0 start|stop DIR" >&2; exit 2; }

for tool in munged slurmctld slurmd sbatch squeue scancel scontrol; do
  command -v "$tool" > /dev/null || {
    echo "$tool is missing (apt-get install munge slurmctld slurmd slurm-client)" >&2
    exit 77
  }
done

mkdir -p "$dir"
dir="$(cd "$dir" && pwd)"
mkdir -p "$dir/munge" "$dir/state" "$dir/spool" "$dir/log"
chmod 700 "$dir/munge"
: > "$dir/pids"
user="$(id -un)"

# munge: a fresh key, the socket under DIR.
head -c 1024 /dev/urandom > "$dir/munge/munge.key"
chmod 400 "$dir/munge/munge.key"
socket="$dir/munge/munge.socket"
munged -F --force --key-file="$dir/munge/munge.key" --socket="$socket" \
  --pid-file="$dir/munge/munged.pid" --log-file="$dir/log/munged.log" \
  --seed-file="$dir/munge/seed" > "$dir/log/munged.out" 2>&1 &
echo $! >> "$dir/pids"

# Ports from the PID, so that two test runs on one machine do not collide.
port=$(( 20000 + ($$ % 20000) ))
node_line="$(slurmd -C | head -1)"
cat > "$dir/slurm.conf" <<CONF
ClusterName=penumbra-test
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=$user
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$socket
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/pgid
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
ReturnToService=2
SchedulerType=sched/backfill
SchedulerParameters=sched_interval=1
MinJobAge=60
SlurmctldTimeout=30
SlurmdTimeout=30
$node_line NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=local Nodes=ALL Default=YES MaxTime=INFINITE State=UP OverSubscribe=NO
CONF
echo "export SLURM_CONF=$dir/slurm.conf" > "$dir/env"
export SLURM_CONF="$dir/slurm.conf"

slurmctld -D -i -f "$dir/slurm.conf" > "$dir/log/slurmctld.out" 2>&1 &
echo $! >> "$dir/pids"
slurmd -D -f "$dir/slurm.conf" > "$dir/log/slurmd.out" 2>&1 &
echo $! >> "$dir/pids"

for _ in $(seq 300); do
  if sinfo -h -o '%T' 2>/dev/null | grep -qE '^(idle|mixed|allocated)'; then exit 0; fi
  sleep 0.1
done
echo "the local Slurm cluster did not come up in 30 s; logs:" >&2
tail -n 20 "$dir"/log/* >&2 || true
stop
exit 1
