#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# A real single-node Slurm on localhost (slurmctld, slurmd, munge; no systemd, no cgroups), all
# state in one temporary folder: scripts/slurm-slice.sh submits a 4-task job array and the merge,
# and the merged folder must equal a single run of texfab slice, byte for byte.
#   tests/render/slurm_slice_test.sh TEXFAB_BINARY
# Exit 0: equal; 1: different or failed; 77: skipped (Slurm or munge not installed: run
# scripts/install-deps.sh), with the reason on stdout.
set -uo pipefail

texfab=$(realpath "$1")
repo=$(cd "$(dirname "$0")/../.." && pwd)
for tool in slurmctld slurmd sbatch sinfo scontrol munged mungekey munge; do
  command -v "$tool" > /dev/null || { echo "SKIP: $tool not installed (scripts/install-deps.sh installs Slurm and munge)"; exit 77; }
done

D=$(mktemp -d /tmp/texfab-slurm-XXXXXX)
chmod 755 "$D"
pids=()
cleanup() {
  if [ -n "${SLURM_CONF:-}" ]; then
    timeout 10 scancel --quiet --user="$(id -un)" 2> /dev/null
    timeout 10 scontrol shutdown 2> /dev/null
  fi
  for pid in "${pids[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2> /dev/null || break; sleep 0.1; done
    kill "$pid" 2> /dev/null
  done
  rm -rf "$D"
}
trap cleanup EXIT
fail() { echo "FAIL: $*"; for f in "$D"/*.log "$D"/out.logs/*.log; do [ -f "$f" ] && { echo "--- $f"; tail -20 "$f"; }; done; exit 1; }

# munge, on a private key and socket.
mungekey -c -f -k "$D/munge.key" > /dev/null 2>&1 || fail "mungekey"
munged -F --key-file="$D/munge.key" --socket="$D/munge.sock" --pid-file="$D/munged.pid" \
  --log-file="$D/munged.log" --seed-file="$D/munged.seed" --force &
pids+=($!)
for _ in $(seq 100); do munge -n -S "$D/munge.sock" > /dev/null 2>&1 && break; sleep 0.1; done
munge -n -S "$D/munge.sock" > /dev/null 2>&1 || fail "munged did not start"

# Two free ports. The daemons listen on every interface: CommunicationParameters=NoInAddrAny would
# bind them to the address of the machine's host name, which a chroot or a minimal container may
# not resolve (both daemons then exit); only holders of this test's private munge key get in.
read -r ctld_port slurmd_port < <(python3 -c 'import socket
s = [socket.socket() for _ in range(2)]
[x.bind(("", 0)) for x in s]
print(*[x.getsockname()[1] for x in s])')
mkdir -p "$D/state" "$D/spool"
cat > "$D/slurm.conf" <<EOF
ClusterName=texfab-test
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=$(id -un)
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$D/munge.sock
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
StateSaveLocation=$D/state
SlurmdSpoolDir=$D/spool
SlurmctldPidFile=$D/slurmctld.pid
SlurmdPidFile=$D/slurmd.pid
SlurmctldLogFile=$D/slurmctld.log
SlurmdLogFile=$D/slurmd.log
SlurmdParameters=config_overrides
MinJobAge=4
SchedulerParameters=batch_sched_delay=0,sched_min_interval=0
ReturnToService=2
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$(nproc)
PartitionName=test Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
# slurmd loads a cgroup plugin even with proctrack/linuxproc and task/none; name the v1 plugin,
# which initializes without a mounted cgroup file system (a chroot or a minimal container),
# instead of autodetecting from /sys/fs/cgroup.
echo "CgroupPlugin=cgroup/v1" > "$D/cgroup.conf"
export SLURM_CONF="$D/slurm.conf"
slurmctld -D -c > "$D/slurmctld.out.log" 2>&1 &
pids+=($!)
slurmd -D -N localhost > "$D/slurmd.out.log" 2>&1 &
pids+=($!)
node_idle() { timeout 5 sinfo -h -o %t 2> /dev/null | grep -q idle; }
for _ in $(seq 150); do node_idle && break; sleep 0.2; done
node_idle || fail "the node did not come up"

# The print: bundled knot, solid marble texture, 60 layers.
args=("$repo/models/meshes/knot1.off" --height 12 --dpi 200 --layer 0.2 --shell 0.8
      -e "$repo/models/exemplars/marble.png" --feature-size 3 --cache-dir "$D/cache")
"$texfab" slice "${args[@]}" -o "$D/single" -q 2> "$D/single.log" || fail "the single run failed"
# A job that does not finish in 150 s is stuck (the single run above takes seconds): say what
# Slurm saw instead of running into ctest's timeout.
timeout 150 "$repo/scripts/slurm-slice.sh" --tasks 4 --cpus 1 --texfab "$texfab" --wait "${args[@]:0:1}" \
  "$D/out" "${args[@]:1}" > "$D/submit.log" 2>&1
status=$?
if [ $status -ne 0 ]; then
  { squeue -a -o '%i %j %T %r'; scontrol show node localhost; } > "$D/queue.log" 2>&1
  [ $status -eq 124 ] && fail "the Slurm jobs did not finish in 150 s"
  fail "the Slurm run failed (exit $status)"
fi
[ -f "$D/out/slices.json" ] || fail "no merged manifest"
[ ! -e "$D/out.parts" ] || fail "the shards were not removed after the merge"
diff -r "$D/single" "$D/out" > "$D/diff.log" || fail "merged output differs from the single run"
echo "OK: $(ls "$D/out" | wc -l) files equal ($(grep -c '"layer"' "$D/out/slices.json") layers, 4 array tasks)"
