#!/usr/bin/env bash
# Batch benchmark: a corpus of $COUNT synthetic recordings x $FRAMES frames (cosserat synth,
# 33 nodes, cases/batch/roll_recording.toml) through
#   1. the local batch (`cosserat batch`, one recording per core),
#   2. Slurm, one recording per array task (`--slurm --per-task 1 --wait`),
#   3. Slurm, 25 recordings per array task (`--slurm --per-task 25 --wait`),
# on this machine: whole-command wall time and frames per second. The Slurm rows use the
# single-node cluster of scripts/slurm_cluster.sh (started and stopped here; needs root).
# Each run writes a fresh output folder (no skip of complete recordings). Prints a markdown
# table; writes nothing outside a temporary folder. Not a test: nothing here asserts, except
# that every summary is the same apart from timing.
set -euo pipefail
cd "$(dirname "$0")/.."
COUNT="${COUNT:-50}"
FRAMES="${FRAMES:-300}"
cargo build --release -q
bin="$PWD/target/release/cosserat"
tmp=$(mktemp -d)
export COSSERAT_SLURM_DIR="$tmp/cluster"
trap 'bash scripts/slurm_cluster.sh stop >/dev/null 2>&1 || true; rm -rf "$tmp"' EXIT
"$bin" synth --out "$tmp/corpus" --count "$COUNT" --frames "$FRAMES" --seed 1 >/dev/null
case_file=cases/batch/roll_recording.toml
total=$((COUNT * FRAMES))
now() { date +%s.%N; }
rows=()
row() { # label, seconds
  rows+=("| $1 | $COUNT | $total | $(printf '%.1f' "$2") | $(python3 -c "print(f'{$total / $2:.0f}')") |")
}
t0=$(now)
"$bin" batch "$case_file" --recordings "$tmp/corpus" --out "$tmp/local" --quiet >/dev/null
row "local batch (\`--jobs $(nproc)\`)" "$(python3 -c "print($(now) - $t0)")"
if bash scripts/slurm_cluster.sh start >"$tmp/cluster.log" 2>&1; then
  export SLURM_CONF="$COSSERAT_SLURM_DIR/slurm.conf"
  for k in 1 25; do
    t0=$(now)
    "$bin" batch "$case_file" --recordings "$tmp/corpus" --out "$tmp/slurm$k" --slurm --per-task "$k" --wait --quiet >/dev/null 2>"$tmp/slurm$k.err" || { cat "$tmp/slurm$k.err" >&2; exit 1; }
    row "Slurm, $k per task ($(( (COUNT + k - 1) / k )) array tasks)" "$(python3 -c "print($(now) - $t0)")"
    # the gathered summary must be the local one, timing excepted
    diff <(cut -d, -f1-8 "$tmp/local/summary.csv") <(cut -d, -f1-8 "$tmp/slurm$k/summary.csv") >/dev/null \
      || { echo "summaries differ between the local batch and Slurm ($k per task)" >&2; exit 1; }
  done
else
  echo "Slurm not available: $(tail -n 1 "$tmp/cluster.log")" >&2
fi
echo "Batch of $COUNT recordings x $FRAMES frames x 33 nodes on $(nproc) cores ($(date -u +%Y-%m-%d))"
echo
echo "| run | recordings | frames | wall time [s] | frames/s |"
echo "|---|---|---|---|---|"
printf '%s\n' "${rows[@]}"
