#!/usr/bin/env bash
# The full comparison: every case of cases/ and cases/benchmarks/ (with its published values)
# through both engines, whole runs (the dynamic
# cantilever's 1000 steps take ~5 minutes in FreeFEM; each inverse fixed point ~1 minute), the
# first 10 frames of each clip, then one whole clip in both engines (CLIP, default
# worm_delta_turn_ld1) with the time of each engine, then a batch of generated cases
# (GENERATED, default 24). Writes out/full/<case>/ and a table per case; exit status 1 if any
# comparison fails.
set -uo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q || exit 1
bin=target/release/cosserat
# the recordings of cases/worm_2d_recording.toml, as scripts/setup.sh writes them
[ -f data/tracker/worm_000.csv ] || $bin synth --tracker --out data/tracker --force
clip=${CLIP:-worm_delta_turn_ld1}
status=0
mkdir -p out/full
for c in cases/*.toml cases/benchmarks/*.toml; do
  name=$(basename "$c" .toml)
  echo "== $name"
  $bin compare "$c" --out "out/full/$name" | tee "out/full/$name.txt" || status=1
done
echo "== whole clip: $clip"
$bin compare "cases/$clip.toml" --frames all --out "out/full/${clip}_all" | tee "out/full/${clip}_all.txt" || status=1
echo "== generated cases"
COSSERAT_GENERATED_CASES=${GENERATED:-24} cargo test --release -q --test generated_cases -- --nocapture 2>&1 \
  | tee out/full/generated.txt | grep -E "^gen|passed|FAIL|panicked" || status=1
exit $status
