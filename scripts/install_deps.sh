#!/usr/bin/env bash
# Install what the project needs on a fresh Debian machine: FreeFEM (Debian packages), pip
# (scripts/fetch_worm_data.sh downloads the worm clips with it), Slurm and munge (Debian's
# slurmctld, slurmd, munge, slurm-client: scripts/slurm_cluster.sh) and, if absent, a Rust
# toolchain from Debian; then the Python package `cosserat` (python/) into the virtual environment
# .venv with numpy, pytest and matplotlib. Idempotent; run as root (or with sudo available).
set -euo pipefail
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
need=()
command -v FreeFem++ >/dev/null 2>&1 || need+=(freefem++ libfreefem++)
command -v cargo >/dev/null 2>&1 || need+=(cargo rustc)
python3 -m pip --version >/dev/null 2>&1 || need+=(python3-pip)
python3 -c 'import ensurepip, venv' >/dev/null 2>&1 || need+=(python3-venv)
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
# The Python package: a virtual environment .venv at the repository's root, and the wheel built
# from python/ by maturin (a release build of the library, one abi3 wheel for CPython >= 3.9).
cd "$(dirname "$0")/.."
[ -x .venv/bin/python ] || python3 -m venv .venv
.venv/bin/python -m pip install -q --upgrade pip
.venv/bin/python -m pip install -q numpy pytest matplotlib
start=$(date +%s)
.venv/bin/python -m pip install -q ./python
echo "Python package: $(.venv/bin/python -c 'import cosserat; print("cosserat", cosserat.__version__, "from", cosserat.__file__)') (built in $(( $(date +%s) - start )) s)"
