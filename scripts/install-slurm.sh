#!/usr/bin/env bash
# Installs Debian's Slurm workload manager and MUNGE (slurmctld, slurmd, slurm-client, munge) for
# crates/cli/tests/sweep_slurm.rs, which starts a two-node cluster on this host inside a private
# network namespace and runs a sweep's shards as an `sbatch --array`. Idempotent and quiet when
# the programs are already there (what crates/cli/build.rs probes). Debian's packages enable and
# start their daemons as system services; the test starts its own, so those are stopped and
# disabled again where systemd runs them.
set -euo pipefail
programs=(slurmctld slurmd sbatch squeue sacct scontrol munged mungekey)
have_all() {
  for p in "${programs[@]}"; do
    command -v "$p" >/dev/null 2>&1 || [ -x "/usr/sbin/$p" ] || return 1
  done
}
if have_all; then
  exit 0
fi
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
# policy-rc.d exit 101: the packages' maintainer scripts do not start the system daemons.
policy=/usr/sbin/policy-rc.d
created_policy=""
if [ ! -e "$policy" ]; then
  printf '#!/bin/sh\nexit 101\n' | $sudo tee "$policy" >/dev/null
  $sudo chmod +x "$policy"
  created_policy=1
fi
trap '[ -n "$created_policy" ] && $sudo rm -f "$policy"' EXIT
$sudo apt-get install -y -qq --no-install-recommends slurmctld slurmd slurm-client munge >/dev/null
if command -v systemctl >/dev/null 2>&1 && [ -d /run/systemd/system ]; then
  $sudo systemctl disable --now slurmctld slurmd munge >/dev/null 2>&1 || true
fi
have_all
echo "Slurm $(dpkg-query -W -f '${Version}' slurmd 2>/dev/null) and MUNGE installed"
