#!/usr/bin/env bash
# Accuracy per second of the dynamic cantilever (§5.1): 250 to 8000 time steps, the tip error
# against the exact-in-time modal solution of the linearised rod against the wall time of each
# solve. One point at a time (--jobs 1) so that no two solves share the two cores; run it on an
# otherwise idle machine. Writes docs/accuracy_per_second.svg and .csv (columns: point,
# status, wall_time_s [s], modal_tip_rel_error [-]) and prints the table.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
target/release/cosserat audit cases/bench/accuracy_per_second.toml --jobs 1 --quiet --out "$tmp/aps"
cp "$tmp/aps/accuracy_per_second/accuracy_per_second.svg" "$tmp/aps/accuracy_per_second/accuracy_per_second.csv" docs/
column -s, -t < docs/accuracy_per_second.csv
