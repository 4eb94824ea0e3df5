#!/usr/bin/env bash
# The main job: every case of cases/ through both engines, full length (the dynamic cantilever
# takes ~4-5 minutes in FreeFEM), writing out/<case>/{rust,freefem}/ and a comparison table
# per case (inverse cases: ~50 s of FreeFEM each; inverse Newton cases run in Rust only; worm
# clips: first frame in both engines, then the whole clip in Rust, 3 minutes for the omega turn).
# Exit status 1 if any comparison fails.
set -uo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q || exit 1
bin=target/release/cosserat
status=0
mkdir -p out
for c in cases/*.toml; do
  name=$(basename "$c" .toml)
  echo "== $name"
  $bin compare "$c" --out "out/$name" | tee "out/$name.compare.txt" || status=1
  # Clip cases: compare checks their first frame in both engines; the whole clip runs in Rust.
  if grep -q '^\[clip\]' "$c"; then
    $bin run "$c" --out "out/$name/clip" || status=1
  fi
done
exit $status
