#!/usr/bin/env bash
# A study on a real single-node Slurm cluster, started here in a temporary folder: munged with a fresh key,
# slurmctld and slurmd from a slurm.conf generated for this host, on free ports. examples/slurm/submit.sh submits a
# 4-task array of a small study and the dependent merge + report job; the test waits for both and checks that the
# merged rows' deterministic columns equal an unsharded run's and that the report was written. It stops every
# daemon it started and removes the folder. Skipped (exit 77, with the reason) when the cluster cannot run here.
#   slurm_study_test.sh QDMR SOURCE_DIR
set -euo pipefail
qdmr="$(realpath "$1")" source="$(realpath "$2")"

skip() { echo "SKIP: $*"; exit 77; }
[ "$(id -u)" -eq 0 ] || skip "needs root (slurmd runs jobs as their user; a private cluster here runs as root)"
for tool in munged munge slurmctld slurmd sbatch squeue sinfo scontrol; do
  command -v "$tool" >/dev/null || skip "$tool is not installed (Debian: slurm-wlm, munge; scripts/setup installs them)"
done

work="$(mktemp -d /tmp/qdmr-slurm.XXXXXX)"
chmod 0755 "$work"
daemons=()
cleanup() {
  SLURM_CONF="$work/slurm.conf" scontrol shutdown >/dev/null 2>&1 || true
  for pidfile in "${daemons[@]}"; do
    [ -f "$pidfile" ] || continue
    pid="$(cat "$pidfile")"
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null || true
  done
  # slurmstepd processes of a job that outlived its daemons (none when the test passes)
  pkill -9 -f "$work" 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
fail() {
  echo "FAIL: $*" >&2
  for log in "$work"/*.log "$work"/results/*.log; do
    [ -f "$log" ] && { echo "--- $log" >&2; tail -n 20 "$log" >&2; }
  done
  exit 1
}

# munge: a fresh key and a private socket.
mkdir -m 0700 "$work/munge"
dd if=/dev/urandom of="$work/munge/munge.key" bs=1024 count=1 status=none
chmod 0400 "$work/munge/munge.key"
socket="$work/munge/munge.socket"
daemons+=("$work/munge/munged.pid")
munged --force --key-file="$work/munge/munge.key" --socket="$socket" --pid-file="$work/munge/munged.pid" \
  --log-file="$work/munged.log" --seed-file="$work/munge/munged.seed" >/dev/null 2>&1 ||
  skip "munged does not start here: $(tail -n 1 "$work/munged.log" 2>/dev/null)"
munge -n -S "$socket" | unmunge -S "$socket" >/dev/null || fail "munge cannot encode and decode a credential"

# slurm.conf for this host: its name, its CPUs and memory as slurmd sees them, two free ports.
host="$(hostname -s)"
node="$(slurmd -C | head -n 1)"
read -r ctld_port node_port < <(python3 -c '
import socket
s = [socket.socket() for _ in range(2)]
for x in s: x.bind(("127.0.0.1", 0))
print(*[x.getsockname()[1] for x in s])')
mkdir -p "$work/state" "$work/spool" "$work/results"
cat >"$work/slurm.conf" <<CONF
ClusterName=qdmrtest
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$ctld_port
SlurmdPort=$node_port
AuthType=auth/munge
AuthInfo=socket=$socket
CredType=cred/munge
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
ReturnToService=2
$node State=UNKNOWN
PartitionName=qdmr Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$work/slurm.conf"
daemons+=("$work/slurmctld.pid" "$work/slurmd.pid")
slurmctld -i >/dev/null 2>&1 || skip "slurmctld does not start here: $(tail -n 1 "$work/slurmctld.log" 2>/dev/null)"
slurmd >/dev/null 2>&1 || skip "slurmd does not start here: $(tail -n 1 "$work/slurmd.log" 2>/dev/null)"
for _ in $(seq 60); do
  state="$(sinfo -h -n "$host" -o %t 2>/dev/null || true)"
  [ "$state" = idle ] && break
  sleep 0.5
done
[ "$state" = idle ] || skip "the node did not become idle (state '$state'): $(tail -n 1 "$work/slurmd.log")"

# The study, as examples/slurm/submit.sh runs it: 4 shards, then merge and report.
spec="$source/tests/report/small_study.json"
ids="$(QDMR="$qdmr" "$source/examples/slurm/submit.sh" "$spec" "$work/results" 4)" || fail "submit.sh failed"
echo "submitted jobs $ids"
for _ in $(seq 600); do
  [ -z "$(squeue -h -o %i 2>/dev/null)" ] && break
  sleep 0.5
done
[ -z "$(squeue -h -o %i)" ] || fail "jobs still queued after 300 s: $(squeue)"
[ -f "$work/results/merged/results.json" ] || fail "the merge job wrote no merged/results.json"
[ -f "$work/results/report/index.html" ] || fail "the merge job wrote no report"
for i in 1 2 3 4; do [ -f "$work/results/shard-$i/study.json" ] || fail "shard $i did not run"; done

# The merged rows equal an unsharded run's in every deterministic column.
"$qdmr" study "$spec" -o "$work/unsharded" >/dev/null 2>&1 || fail "the unsharded study failed"
python3 "$source/tests/examples/same_study_rows.py" "$work/results/merged/results.json" \
  "$work/unsharded/results.json" || fail "the merged rows differ from the unsharded run's"
echo "slurm: ok"
