#!/usr/bin/env bash
# One command for a fresh Debian machine: install everything, fetch the worm clips
# (data/elegansbot/, checksum-pinned), build, run the main job.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/fetch_worm_data.sh
cargo build --release
target/release/cosserat list
bash scripts/compare_all.sh
