#!/usr/bin/env bash
# The noise study (docs/noise.md, docs/results.md "Noisy recordings"): synthetic 3D recordings of
# a 1 mm worm at 0-10 µm of noise on 33 and 128 nodes, reconstructed with Table 1's weights, with
# automatic weights (with and without time coupling) and by a GCV smoothing spline, all scored
# (then planar recordings of 49 points, docs/noise.md N12, and recordings with smooth changes of
# shape, N13),
# against the truth in one run (about 2 minutes on 2 cores). Writes docs/noise_study.svg and
# docs/noise_study.csv and prints the table.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
target/release/cosserat noise-study cases/bench/noise_study.toml --out "$tmp/ns" --quiet "$@"
cp "$tmp/ns/noise_study.svg" "$tmp/ns/noise_study.csv" docs/
# planar recordings (2D, noise in x and y): docs/noise.md N12
target/release/cosserat noise-study cases/bench/noise_study_planar.toml --out "$tmp/np" --quiet "$@"
cp "$tmp/np/noise_study.csv" docs/noise_study_planar.csv
# smooth changes of shape (docs/noise.md N13)
target/release/cosserat noise-study cases/bench/noise_study_shapes.toml --out "$tmp/nh" --quiet "$@"
cp "$tmp/nh/noise_study.csv" docs/noise_study_shapes.csv
