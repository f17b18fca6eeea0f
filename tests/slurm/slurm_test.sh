#!/bin/bash
# Starts a real single-node Slurm cluster (munged, slurmctld, slurmd on loopback ports chosen
# here), submits tools/slurm/generate.sbatch as a 4-task array and tools/slurm/merge.sbatch
# after it, and compares the merged dataset byte for byte with a single-process run.
#   tests/slurm/slurm_test.sh CADSYNTH_EXE SOURCE_DIR
# Exit 77 (skipped) only where Slurm cannot run: packages missing, or not root (slurmd needs it).
set -euo pipefail
exe=$(realpath "$1")
src=$(realpath "$2")

skip() {
  echo "SKIPPED: $*"
  exit 77
}
for tool in munged slurmctld slurmd sbatch sinfo scontrol; do
  command -v "$tool" > /dev/null || skip "$tool not found: install Debian's slurm-wlm and munge (tools/setup.sh does)"
done
[[ $(id -u) -eq 0 ]] || skip "slurmd must run as root to start jobs; run as root (CI does)"

work=$(mktemp -d /tmp/cadsynth_slurm.XXXXXX)
chmod 700 "$work"
export SLURM_CONF=$work/slurm.conf
export CADSYNTH=$exe
started=0
cleanup() {
  local rc=$?
  if [[ $started -eq 1 ]]; then
    scontrol shutdown > /dev/null 2>&1 || true
    for pidfile in "$work/slurmctld.pid" "$work/slurmd.pid"; do
      [[ -f $pidfile ]] || continue
      pid=$(cat "$pidfile")
      for _ in $(seq 50); do kill -0 "$pid" 2> /dev/null || break; sleep 0.1; done
      kill -9 "$pid" 2> /dev/null || true
    done
  fi
  munged -s --socket="$work/munge.sock" > /dev/null 2>&1 || true
  if [[ $rc -ne 0 && $rc -ne 77 ]]; then
    for log in "$work"/*.log; do [[ -f $log ]] && { echo "--- $log"; tail -n 20 "$log"; }; done
  fi
  rm -rf "$work"
}
trap cleanup EXIT

# Two free loopback ports: nothing answers on them.
free_port() {
  local port
  while true; do
    port=$((20000 + RANDOM % 30000))
    (exec 3<> "/dev/tcp/127.0.0.1/$port") 2> /dev/null || { echo "$port"; return; }
  done
}
ctld_port=$(free_port)
slurmd_port=$(free_port)
while [[ $slurmd_port -eq $ctld_port ]]; do slurmd_port=$(free_port); done
echo "slurmctld on 127.0.0.1:$ctld_port, slurmd on 127.0.0.1:$slurmd_port, files in $work"

# munge with a key of its own (the test's, not the machine's).
dd if=/dev/urandom of="$work/munge.key" bs=1024 count=1 status=none
chmod 600 "$work/munge.key"
munged -f --socket="$work/munge.sock" --key-file="$work/munge.key" --pid-file="$work/munged.pid" \
  --log-file="$work/munged.log" --seed-file="$work/munged.seed"

mkdir -p "$work/state" "$work/spool"
cat > "$SLURM_CONF" << CONF
ClusterName=cadsynth-test
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$work/munge.sock
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
MpiDefault=none
SchedulerType=sched/backfill
DependencyParameters=kill_invalid_depend
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
NodeName=cadsynth-node NodeHostname=localhost NodeAddr=127.0.0.1 CPUs=2 State=UNKNOWN
PartitionName=test Nodes=cadsynth-node Default=YES MaxTime=INFINITE State=UP
CONF
started=1
slurmctld -f "$SLURM_CONF"
slurmd -f "$SLURM_CONF" -N cadsynth-node
for _ in $(seq 120); do
  [[ $(sinfo -h -o %t 2> /dev/null) == idle ]] && break
  sleep 0.5
done
[[ $(sinfo -h -o %t) == idle ]] || { echo "FAIL: the node did not come up: $(sinfo 2>&1)"; exit 1; }
echo "cluster up: $(sinfo -h -o '%P %a %D %t %N')"

# A small recipe: the default job's three scenes, 8 views each, every output format.
cd "$work"
cat > recipe.yaml << 'YAML'
camera: {preset: kinect_v1, width: 320, height: 240, fx: 262.5, fy: 262.5, cx: 159.5, cy: 119.5}
sweep: {yaw: {from: 0, to: 315, step: 45}, pitch: [40], radius: 0.8 m}
output: {formats: [bop, coco, paper, pvn3d, grasp]}
YAML
"$exe" generate recipe.yaml -o single --quiet

jobid=$(sbatch --parsable --array=0-3 --cpus-per-task=1 --output="$work/shard-%A_%a.log" \
  "$src/tools/slurm/generate.sbatch" recipe.yaml farm)
jobid=${jobid%%;*}
echo "submitted shards as array job $jobid"
if ! sbatch --wait --dependency=afterok:"$jobid" --output="$work/merge.log" "$src/tools/slurm/merge.sbatch" farm; then
  echo "FAIL: the merge job failed"
  cat "$work"/shard-*.log "$work/merge.log" 2> /dev/null || true
  exit 1
fi
# A job cancelled before it started (a shard failed: kill_invalid_depend) leaves sbatch's status 0.
if [[ ! -f $work/merge.log ]]; then
  echo "FAIL: the merge job never ran (a shard failed, so Slurm cancelled it)"
  cat "$work"/shard-*.log 2> /dev/null || true
  exit 1
fi
cat "$work/merge.log"

for i in 0 1 2 3; do
  log=$work/shard-${jobid}_$i.log
  grep -q "^shard $i/4 from SLURM_ARRAY_TASK_ID=$i of the array 0-3$" "$log" || { echo "FAIL: task $i did not run shard $i/4"; cat "$log"; exit 1; }
  grep -q '"done":6,"total":6' "$log" || { echo "FAIL: shard $i/4 did not render its 6 frames"; cat "$log"; exit 1; }
done
grep -q "merged 4 shards" "$work/merge.log" || { echo "FAIL: merge did not report 4 shards"; exit 1; }
# run.json records how each run went (times, shards): the one file that differs by design.
if ! diff -r -x run.json single farm > diff.txt; then
  echo "FAIL: the merged dataset differs from the single-process run:"
  head -n 20 diff.txt
  exit 1
fi
grep -q '"index": 3' farm/run.json || { echo "FAIL: farm/run.json does not list the 4 shards"; cat farm/run.json; exit 1; }
echo "PASS: 4 Slurm array tasks + merge job == single process ($(find farm -type f | wc -l) files, byte for byte but run.json)"
