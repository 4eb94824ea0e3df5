#!/usr/bin/env bash
# Run every program of examples/ once, as the documents that quote them do (docs/results.md,
# docs/inverse.md), with short arguments where they take some: the examples are measurements,
# not tests (`cargo clippy --all-targets` in .ci/run builds them; this script runs them). Needs
# the worm data (scripts/fetch_worm_data.sh). tracker_score is run by scripts/tracker_trial.sh.
#
#   scripts/run_examples.sh          # about 5 minutes on 2 cores
#
# Exits non-zero at the first example that fails (eq64_findings panics when a measured number
# it quotes has moved).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q --examples
run() { echo "== $*"; "target/release/examples/$@"; }
run bench_fmt
run bench_kkt 3
run bench_ops 3
run inv_sens cases/inverse_bend.toml
run newton_stall cases/inverse_bend_twist_newton.toml 1e-10 1e-6 5
run eq64_findings
echo "every example ran"
