#!/usr/bin/env bash
# One command for a fresh Debian machine: install everything, build, run the main job.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
cargo build --release
target/release/cosserat list
bash scripts/compare_all.sh
