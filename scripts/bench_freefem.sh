#!/usr/bin/env bash
# FreeFEM engine speed (not a test: nothing here asserts), in one run on one machine:
#   1. `cosserat compare cases/worm_delta_turn_ld1.toml --frames 6`: FreeFEM CPU time per clip frame
#      (ff_clip_frames.csv wall_time_s, the Newton inverse of each frame) and the whole command;
#   2. `cosserat compare cases/cantilever_dynamic.toml` (1000 steps): FreeFEM CPU time per time step
#      (ff_info.csv wall_time_s / steps) and the whole command;
#   3. with --all, also `compare cases/worm_delta_turn_ld1.toml --frames all` (300 frames).
# Goals (issue 31): 10x per clip frame and per dynamic step against the scripts before (2.4 s per frame,
# 0.245 s per step on an AMD EPYC, 2 cores), each whole command <= 2 min. docs/results.md has the table.
# Needs FreeFem++ and the worm data (scripts/fetch_worm_data.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q
bin=target/release/cosserat
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
grep -m1 "model name" /proc/cpuinfo || true
wall() { /usr/bin/time -f "%e" -o "$tmp/t" "$@" >/dev/null 2>"$tmp/err" || { cat "$tmp/err" >&2; exit 1; }; cat "$tmp/t"; }
per_frame() { python3 -c "import csv; r=list(csv.DictReader(open('$1/freefem_work/ff_clip_frames.csv'))); print('%.3f s per frame over %d frames' % (sum(float(x['wall_time_s']) for x in r)/len(r), len(r)))"; }
t=$(wall $bin compare cases/worm_delta_turn_ld1.toml --frames 6 --out "$tmp/clip6")
echo "clip, 6 frames: FreeFEM $(per_frame "$tmp/clip6"); whole command ${t} s"
t=$(wall $bin compare cases/cantilever_dynamic.toml --out "$tmp/dyn")
python3 -c "
import csv
d = dict(csv.reader(open('$tmp/dyn/freefem_work/ff_info.csv')))
print('dynamic, %s steps: FreeFEM %.4f s per step (%s s); whole command $t s' % (d['steps'], float(d['wall_time_s'])/float(d['steps']), d['wall_time_s']))"
if [ "${1:-}" = "--all" ]; then
  t=$(wall $bin compare cases/worm_delta_turn_ld1.toml --frames all --out "$tmp/clipall")
  echo "clip, all frames: FreeFEM $(per_frame "$tmp/clipall"); whole command ${t} s"
fi
