#!/usr/bin/env bash
# Runs a 3-axis sweep over the workload suite (workloads/) through a real SLURM
# (Debian's slurm-wlm 22.05 + munge) started here on localhost, and checks that
# the merged table equals the local runner's, byte for byte; then resubmits
# (resume: nothing left to run, the table again). Everything it starts runs in
# a temporary directory and is stopped on exit, also on failure.
#   slurm_test.sh RBCD_SIM
# Exit 0 pass, 1 fail, 77 skipped (SLURM or munge not installed: scripts/setup.sh --slurm).
set -euo pipefail
sim=$(realpath "$1")
root=$(cd "$(dirname "$0")/../.." && pwd)
sweep_cmd=(/usr/bin/python3 "$root/scripts/rbcd-sweep")

for tool in munged slurmctld slurmd sbatch squeue sinfo; do
  if ! command -v "$tool" >/dev/null 2>&1 && [ ! -x "/usr/sbin/$tool" ]; then
    echo "SKIPPED: $tool not installed (optional: slurm-wlm and munge, see scripts/setup.sh --slurm)"
    exit 77
  fi
done
PATH="$PATH:/usr/sbin"
if [ "$(id -u)" -ne 0 ]; then
  echo "SKIPPED: the local SLURM cluster runs as root (slurmd launches the jobs); CI runs as root"
  exit 77
fi

tmp=$(mktemp -d /tmp/rbcd_slurm.XXXXXX)
chmod 700 "$tmp"
daemons=()
cleanup() {
  local status=$?
  set +e
  if [ "$status" -ne 0 ]; then
    echo "--- logs (test failed, status $status)"
    tail -n 20 "$tmp"/*.log "$tmp"/out-slurm/slurm/logs/* 2>/dev/null
  fi
  for pid in "${daemons[@]}"; do kill "$pid" 2>/dev/null; done
  for pid in "${daemons[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null
  done
  rm -rf "$tmp"
  exit "$status"
}
trap cleanup EXIT
trap 'exit 1' INT TERM HUP

free_port() { /usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }
node=$(hostname -s)
cpus=$(nproc)

# munge: a fresh key and a private socket.
dd if=/dev/urandom of="$tmp/munge.key" bs=1024 count=1 status=none
chmod 400 "$tmp/munge.key"
munged --force --key-file="$tmp/munge.key" --socket="$tmp/munge.sock" --pid-file="$tmp/munged.pid" \
  --log-file="$tmp/munged.log" --seed-file="$tmp/munged.seed" --foreground >>"$tmp/munged.log" 2>&1 &
daemons+=($!)

mkdir -p "$tmp/state" "$tmp/spool"
cat > "$tmp/slurm.conf" <<EOF
ClusterName=rbcdtest
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$(free_port)
SlurmdPort=$(free_port)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$tmp/munge.sock
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/slurmctld.log
SlurmdLogFile=$tmp/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/builtin
ReturnToService=2
MpiDefault=none
PlugStackConfig=$tmp/plugstack.conf
NodeName=$node NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=rbcd Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
: > "$tmp/plugstack.conf"
export SLURM_CONF="$tmp/slurm.conf"

for _ in $(seq 50); do [ -S "$tmp/munge.sock" ] && break; sleep 0.1; done
slurmctld -D -i -f "$SLURM_CONF" >>"$tmp/slurmctld.log" 2>&1 &
daemons+=($!)
slurmd -D -f "$SLURM_CONF" -N "$node" >>"$tmp/slurmd.log" 2>&1 &
daemons+=($!)
state=""
for _ in $(seq 200); do
  state=$(sinfo -h -N -o %T 2>/dev/null || true)
  [ "$state" = "idle" ] && break
  sleep 0.1
done
[ "$state" = "idle" ] || { echo "FAILED: the SLURM node did not come up (state: '${state:-none}')"; exit 1; }

# The sweep: 3 axes over the workload suite (workloads/: 5 scenes with
# third-party meshes, their first 3 frames), 40 runs in array tasks of 3.
cat > "$tmp/sweep.toml" <<EOF
[base]
config = "$root/sc_main/configs/paper.toml"
set = { "zeb.id_bits" = 8 }
[axes]
zeb.banks = [1, 2]
zeb.list_length = [4, 8]
tester.stack_depth = [4, 8]
[inputs]
suites = ["$root/workloads"]
frames = "0:2"
[results]
fields = ["totals.frames", "totals.hits", "totals.overflows", "gpu.overhead_pct", "energy.total_nj"]
[slurm]
partition = "rbcd"
time = "00:05:00"
cpus_per_task = 1
runs_per_task = 3
extra = ["--nice=0"]
EOF

"${sweep_cmd[@]}" run "$tmp/sweep.toml" -o "$tmp/out-local" -q --rbcd-sim "$sim"
"${sweep_cmd[@]}" slurm "$tmp/sweep.toml" -o "$tmp/out-slurm" --wait --poll 0.5 --rbcd-sim "$sim" 2> "$tmp/submit.log" \
  || { cat "$tmp/submit.log"; echo "FAILED: the SLURM sweep"; exit 1; }
grep -q "in 14 array tasks" "$tmp/submit.log" || { cat "$tmp/submit.log"; echo "FAILED: expected 40 runs in 14 array tasks"; exit 1; }
ls "$tmp"/out-slurm/slurm/logs/merge-*.out >/dev/null || { echo "FAILED: the merge job did not run"; exit 1; }
cmp "$tmp/out-local/results.csv" "$tmp/out-slurm/results.csv" \
  || { echo "FAILED: the SLURM table differs from the local one"; diff "$tmp/out-local/results.csv" "$tmp/out-slurm/results.csv"; exit 1; }
[ "$(wc -l < "$tmp/out-slurm/results.csv")" -eq 41 ] || { echo "FAILED: expected 40 rows"; exit 1; }
# Every row ran (status 0) and read 3 frames.
awk -F, 'NR > 1 && ($2 !~ /workloads\// || $0 !~ /,0,,/) { bad = 1 } END { exit bad }' "$tmp/out-slurm/results.csv" \
  || { echo "FAILED: a row did not run its workload"; cat "$tmp/out-slurm/results.csv"; exit 1; }
status=$("${sweep_cmd[@]}" status "$tmp/out-slurm")
[[ "$status" == *"40/40 runs done, 0 failed; slurm: no jobs queued" ]] || { echo "FAILED: status says: $status"; exit 1; }

# Resume: a resubmission finds every run complete and only merges.
rm "$tmp/out-slurm/results.csv"
"${sweep_cmd[@]}" slurm "$tmp/sweep.toml" -o "$tmp/out-slurm" --wait --poll 0.5 --rbcd-sim "$sim" 2> "$tmp/resume.log" \
  || { cat "$tmp/resume.log"; echo "FAILED: the resubmission"; exit 1; }
grep -q "0 to run in 0 array tasks" "$tmp/resume.log" || { cat "$tmp/resume.log"; echo "FAILED: resume reran runs"; exit 1; }
cmp "$tmp/out-local/results.csv" "$tmp/out-slurm/results.csv" || { echo "FAILED: resumed table differs"; exit 1; }
# jobs.json keeps the first submission's ids beside the resubmission's; -q prints nothing.
python3 -c 'import json, sys; j = json.load(open(sys.argv[1])); e = j["earlier"]; sys.exit(not (len(e) == 1 and e[0]["array"] and e[0]["merge"] and j["merge"]))' \
  "$tmp/out-slurm/slurm/jobs.json" || { cat "$tmp/out-slurm/slurm/jobs.json"; echo "FAILED: jobs.json lost the earlier ids"; exit 1; }
"${sweep_cmd[@]}" slurm "$tmp/sweep.toml" -o "$tmp/out-slurm" --wait --poll 0.5 -q --rbcd-sim "$sim" 2> "$tmp/quiet.log" \
  || { cat "$tmp/quiet.log"; echo "FAILED: the quiet resubmission"; exit 1; }
[ ! -s "$tmp/quiet.log" ] || { cat "$tmp/quiet.log"; echo "FAILED: slurm -q printed"; exit 1; }
# One input split in frame ranges across array tasks, merged by the merge job.
mkdir "$tmp/suite"
cp "$root/vectors/default.rbt" "$root/vectors/multi-frame-mixed.rbt" "$tmp/suite/"
cat > "$tmp/split.toml" <<EOF
[axes]
zeb.banks = [1, 2]
[inputs]
suites = ["suite"]
[split]
frames_per_run = 1
[results]
fields = ["totals.frames", "totals.hits", "totals.overflows"]
[slurm]
runs_per_task = 4
EOF
"${sweep_cmd[@]}" run "$tmp/split.toml" -o "$tmp/split-local" -q --rbcd-sim "$sim"
"${sweep_cmd[@]}" slurm "$tmp/split.toml" -o "$tmp/split-slurm" --wait --poll 0.5 --rbcd-sim "$sim" 2> "$tmp/split.log" \
  || { cat "$tmp/split.log"; echo "FAILED: the split SLURM sweep"; exit 1; }
grep -q "12 runs, 12 to run in 3 array tasks" "$tmp/split.log" || { cat "$tmp/split.log"; echo "FAILED: expected 3 tasks"; exit 1; }
cmp "$tmp/split-local/results.csv" "$tmp/split-slurm/results.csv" || { echo "FAILED: split tables differ"; exit 1; }
for run in $(awk -F, 'NR > 1 { print $NF }' "$tmp/split-local/results.csv"); do
  cmp "$tmp/split-local/runs/$run/collisions.txt" "$tmp/split-slurm/runs/$run/collisions.txt" \
    || { echo "FAILED: merged collisions of $run differ"; exit 1; }
done
echo "passed: SLURM table equals the local one (40 runs over workloads/, 14 array tasks, merge job), resume merges only;"
echo "        frame ranges in array tasks merge into the local runner's table and collision files"
