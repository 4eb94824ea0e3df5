#!/usr/bin/env bash
# The full audit of the paper: every spec of cases/paper/ on its full grids and whole clips
# (release build), report in out/audit/REPORT.md, and the wall time of the audit.
# Usage: scripts/audit.sh [extra `cosserat audit` arguments, e.g. --jobs 2]
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
start=$(date +%s)
status=0
./target/release/cosserat audit "$@" || status=$?
echo "full audit: $(( $(date +%s) - start )) s wall time on $(nproc) cores (exit status $status)"
exit $status
