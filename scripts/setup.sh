#!/usr/bin/env bash
# One command for a fresh Debian machine: install everything, fetch the worm clips
# (data/elegansbot/, checksum-pinned), build, write the tracker recordings (data/tracker/),
# and run the main job: every case of cases/ in both engines on a short but real horizon (200
# time steps, 40 fixed-point iterations, the first 3 frames of each clip; Newton cases to their
# roots), two cases at a time, each row within the tolerance derived from the case's
# conditioning (docs/decisions.md D15).
# The full comparison (whole runs, 10 clip frames, one whole clip) is scripts/compare_all.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
start=$(date +%s)
bash scripts/install_deps.sh
bash scripts/fetch_worm_data.sh
cargo build --release
bin=target/release/cosserat
# the recordings of cases/worm_2d_recording.toml: two worms as a single-camera tracker writes
# them, with their truth (data/ is gitignored; the same seed writes the same bytes)
[ -f data/tracker/worm_000.csv ] || $bin synth --tracker --out data/tracker --force
$bin list
mkdir -p out/short
status=0
ls cases/*.toml | xargs -P 2 -I{} sh -c '
  name=$(basename {} .toml)
  if '"$bin"' compare {} --short --out out/short/$name > out/short/$name.txt 2>&1; then r=pass; else r=FAIL; fi
  echo "$r  $name  ($(tail -n 1 out/short/$name.txt | cut -c1-90))"
  [ $r = pass ]' || status=1
echo
echo "short comparison of every case: $([ $status = 0 ] && echo all passed || echo FAILURES, see out/short/*.txt) in $(( $(date +%s) - start )) s (set-up included)"
echo "tables: out/short/<case>.txt and out/short/<case>/compare.csv"
echo "the full comparison (whole runs, 10 clip frames, one whole clip): bash scripts/compare_all.sh"
exit $status
