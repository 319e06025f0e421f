#!/usr/bin/env bash
# Starts a one-node Slurm on localhost (munged, slurmctld and slurmd, as root, with a minimal
# slurm.conf in a temporary folder), submits scripts/slurm_shards.sbatch as a job array of four
# shards with `sbatch --array=0-3 --wait`, merges them and compares the merge with one render of
# all their samples byte for byte; stops the daemons it started. Run by tests/slurm.rs; needs
# scripts/install_slurm.sh's packages.
#   scripts/slurm_shards_test.sh PENUMBRA SCENE SPP_PER_SHARD [RENDER OPTIONS…]
# Exit 0 when the merge equals the single render; the last line says what was compared. With
# SHARDS_TIMES=FILE, each shard's and the single render's process CPU seconds (user + system)
# go to FILE, one "name seconds" a line (for docs/benchmarks.md).
set -euo pipefail
penumbra=$(realpath "$1") scene=$(realpath "$2") spp=$3
shift 3
options="$*"
here=$(cd "$(dirname "$0")" && pwd)
tmp=$(mktemp -d /tmp/penumbra-slurm.XXXXXX)
chmod 755 "$tmp"
pids=()
stop() {
    for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
    for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null || true; done
    rm -rf "$tmp"
}
trap stop EXIT

# munge: its own key, socket and files.
dd if=/dev/urandom of="$tmp/munge.key" bs=1024 count=1 status=none
chmod 400 "$tmp/munge.key"
munged --force --foreground --key-file="$tmp/munge.key" --socket="$tmp/munge.socket" \
    --pid-file="$tmp/munged.pid" --log-file="$tmp/munged.log" --seed-file="$tmp/munged.seed" \
    >"$tmp/munged.out" 2>&1 &
pids+=($!)

# Slurm: one node, this host, ports away from a system Slurm's.
host=$(hostname -s)
mkdir -p "$tmp/state" "$tmp/spool" "$tmp/out"
cat >"$tmp/slurm.conf" <<CONF
ClusterName=penumbra-test
SlurmctldHost=$host
SlurmctldPort=16817
SlurmdPort=16818
AuthType=auth/munge
AuthInfo=socket=$tmp/munge.socket
CredType=cred/munge
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/slurmctld.log
SlurmdLogFile=$tmp/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=shards Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$tmp/slurm.conf
for _ in $(seq 50); do [ -S "$tmp/munge.socket" ] && break; sleep 0.1; done
slurmctld -D -i -f "$SLURM_CONF" >"$tmp/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -f "$SLURM_CONF" >"$tmp/slurmd.out" 2>&1 &
pids+=($!)
for _ in $(seq 100); do
    sinfo -h -o %t 2>/dev/null | grep -qx idle && break
    sleep 0.2
done
if ! sinfo -h -o %t | grep -qx idle; then
    echo "slurm_shards_test: the node did not come up; slurmctld.log and slurmd.log:" >&2
    tail -n 5 "$tmp/slurmctld.out" "$tmp/slurmd.out" >&2
    exit 1
fi

# The job array: four shards of spp samples each. With SHARDS_TIMES, a wrapper records each
# task's process CPU seconds (bash's `times`: its children's user and system time).
runner=$penumbra
if [ -n "${SHARDS_TIMES:-}" ]; then
    runner=$tmp/timed-penumbra
    cat >"$runner" <<WRAP
#!/usr/bin/env bash
"$penumbra" "\$@"
# Not in a pipe: a subshell's \`times\` would not see this shell's children.
times >"$tmp/times.\$\$"
tail -n 1 "$tmp/times.\$\$" | awk -v name="shard-\${SLURM_ARRAY_TASK_ID:-}" '{ gsub(/[ms]/, " "); print name, \$1 * 60 + \$2 + \$3 * 60 + \$4 }' >>"$tmp/times"
WRAP
    chmod +x "$runner"
fi
SCENE=$scene SPP=$spp OUT=$tmp/out PENUMBRA=$runner PENUMBRA_OPTIONS=$options \
    sbatch --quiet --array=0-3 --wait --output="$tmp/out/task-%a.log" "$here/slurm_shards.sbatch"
"$penumbra" merge "$tmp"/out/shard-{0,1,2,3}.exr -o "$tmp/merged.exr" 2>/dev/null

# One render of all the samples, as a shard from 0.
# shellcheck disable=SC2086 # options is a list of options
"$runner" render "$scene" -o "$tmp/single.exr" --sample-start 0 --spp $((4 * spp)) $options >/dev/null 2>&1
if [ -n "${SHARDS_TIMES:-}" ]; then
    sed -i '$ s/^shard-[^ ]*/single/' "$tmp/times"
    cp "$tmp/times" "$SHARDS_TIMES"
fi
if ! cmp -s "$tmp/merged.exr" "$tmp/single.exr"; then
    echo "slurm_shards_test: the merge of 4 Slurm shards differs from one render of $((4 * spp)) samples" >&2
    exit 1
fi
echo "slurm_shards_test: 4 shards of $spp spp from sbatch --array=0-3 merge into one render of $((4 * spp)) spp, byte for byte"
