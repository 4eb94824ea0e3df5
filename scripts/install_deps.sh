#!/usr/bin/env bash
# Install what the project needs on a fresh Debian machine: FreeFEM (Debian packages), pip
# (scripts/fetch_worm_data.sh downloads the worm clips with it), Slurm and munge (Debian's
# slurmctld, slurmd, munge, slurm-client: scripts/slurm_cluster.sh) and, if absent, a Rust
# toolchain from Debian. Idempotent; run as root (or with sudo available).
set -euo pipefail
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
need=()
command -v FreeFem++ >/dev/null 2>&1 || need+=(freefem++ libfreefem++)
command -v cargo >/dev/null 2>&1 || need+=(cargo rustc)
python3 -m pip --version >/dev/null 2>&1 || need+=(python3-pip)
# a single-node Slurm cluster for `cosserat batch --slurm` (scripts/slurm_cluster.sh, tests/slurm.rs)
command -v slurmctld >/dev/null 2>&1 && command -v slurmd >/dev/null 2>&1 && command -v munged >/dev/null 2>&1 \
  && command -v sbatch >/dev/null 2>&1 || need+=(slurmctld slurmd munge slurm-client)
if [ ${#need[@]} -gt 0 ]; then
  echo "installing: ${need[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${need[@]}" >/dev/null
fi
FreeFem++ -nw -v 0 /dev/null >/dev/null 2>&1 || true
echo "FreeFEM: $(command -v FreeFem++)  cargo: $(cargo --version)"
