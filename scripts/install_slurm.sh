#!/usr/bin/env bash
# Installs a one-node Slurm's packages (Debian 12's slurm-wlm: slurmctld, slurmd and the
# commands; munge for its authentication) for tests/slurm.rs and scripts/slurm_shards_test.sh.
# Run as root (CI is). The daemons are not started here: the test's script starts its own with
# a slurm.conf in a temporary folder and stops them again.
set -euo pipefail
export DEBIAN_FRONTEND=noninteractive
if command -v sbatch >/dev/null && command -v slurmctld >/dev/null && command -v munged >/dev/null; then
    exit 0
fi
apt-get update -qq
apt-get install -y -qq --no-install-recommends slurm-wlm munge >/dev/null
# The packages may start the services they install; the test runs its own.
for service in slurmctld slurmd munge; do
    systemctl stop "$service" 2>/dev/null || service "$service" stop 2>/dev/null || true
done
