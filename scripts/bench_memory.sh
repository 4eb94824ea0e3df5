#!/usr/bin/env bash
# Memory and output of long recordings: peak resident memory (/usr/bin/time -v) and output
# size of `cosserat run` on a 128-node recording of 1,000 / 10,000 / 108,000 frames (an hour at
# 30 frames/s), in the default output (CSV + VTK) and the compact one, and of `cosserat batch`
# (its default output) on the 10,000-frame recording; bytes per frame of each.
#
# The recording: `cosserat synth` (1199 frames of 128 nodes, the whole omega-turn kymogram,
# noise 1e-7 m; its truth sidecar removed, as a lab recording has none), tiled back and forth
# to each length by scripts/tile_recording.py. The case: cases/batch/roll_recording.toml on 128
# nodes (weights = "auto").
#
#   scripts/bench_memory.sh                      # this tree's binary
#   BEFORE=/path/to/old/cosserat scripts/bench_memory.sh   # and an older binary beside it
#   FRAMES="1000 10000" scripts/bench_memory.sh  # other lengths
#   KEEP=/tmp/somewhere scripts/bench_memory.sh  # keep the recordings and outputs there
#
# Prints a markdown table. Needs /usr/bin/time (Debian's `time`), python3, and free disk of
# about 20 GB for the 108,000 frames (CSV: 13 GB; the old binary's compact output needs ~10 GB
# of memory there and is skipped). Not a test: nothing here asserts. Takes about 30 min per
# binary on 2 cores (3-5 ms per frame).
set -euo pipefail
cd "$(dirname "$0")/.."
FRAMES="${FRAMES:-1000 10000 108000}"
cargo build --release -q
after="$PWD/target/release/cosserat"
tmp="${KEEP:-$(mktemp -d)}"
mkdir -p "$tmp"
[ -n "${KEEP:-}" ] || trap 'rm -rf "$tmp"' EXIT
[ -x /usr/bin/time ] || { echo "needs /usr/bin/time (apt-get install time)" >&2; exit 1; }

"$after" synth --out "$tmp/source" --count 1 --frames 1199 --nodes 128 --seed 1 --force >/dev/null
src="$tmp/source/roll_000.npy"

# peak RSS [kB], wall time [s] and output bytes of one run: label binary case out [args…]
rows=()
measure() {
  local label=$1 bin=$2 case=$3 out=$4 frames=$5; shift 5
  rm -rf "$out"
  /usr/bin/time -v "$bin" "$@" >/dev/null 2>"$out.time" || { tail -n 5 "$out.time" >&2; return 1; }
  local rss wall bytes
  rss=$(awk -F': ' '/Maximum resident set size/ {print $2}' "$out.time")
  wall=$(awk -F': ' '/Elapsed \(wall clock\)/ {print $2}' "$out.time")
  bytes=$(du -sb "$out" | cut -f1)
  rows+=("| $label | $frames | $(python3 -c "print(f'{$rss/1024:.0f}')") | $(python3 -c "print(f'{$bytes/1e6:.1f}')") | $(python3 -c "print(f'{$bytes/$frames/1e3:.1f}')") | $wall |")
}

for n in $FRAMES; do
  rec="$tmp/rec_$n.npy"
  python3 scripts/tile_recording.py "$src" "$rec" "$n"
  case_file="$tmp/rec_$n.toml"
  sed -e 's/^elements = 32 .*/elements = 127/' -e "s#^file = .*#file = \"$rec\"#" cases/batch/roll_recording.toml >"$case_file"
  for bin_label in "after:$after" ${BEFORE:+"before:$BEFORE"}; do
    label=${bin_label%%:*}; bin=${bin_label#*:}
    measure "$label, run (CSV + VTK)" "$bin" "$case_file" "$tmp/out_${label}_csv_$n" "$n" \
      run "$case_file" --quiet --out "$tmp/out_${label}_csv_$n"
    rm -rf "$tmp/out_${label}_csv_$n"
    if [ "$label" = after ] || [ "$n" -le 10000 ]; then
      measure "$label, run --output-format compact" "$bin" "$case_file" "$tmp/out_${label}_compact_$n" "$n" \
        run "$case_file" --quiet --out "$tmp/out_${label}_compact_$n" --output-format compact
      [ -n "${KEEP:-}" ] || rm -rf "$tmp/out_${label}_compact_$n"
    fi
  done
  if [ "$n" -eq 10000 ]; then
    mkdir -p "$tmp/batch_in" && ln -sf "$rec" "$tmp/batch_in/rec_$n.npy"
    measure "after, batch (its default output)" "$after" "$case_file" "$tmp/batch_out" "$n" \
      batch "$case_file" --recordings "$tmp/batch_in" --out "$tmp/batch_out" --quiet --jobs 1
  fi
done
echo "128-node recording (cases/batch/roll_recording.toml, 127 elements) on $(nproc) cores, $(lscpu | awk -F': +' '/Model name/ {print $2}') ($(date -u +%Y-%m-%d))"
echo
echo "| binary, command | frames | peak memory [MiB] | output [MB] | output per frame [kB] | wall time |"
echo "|---|---|---|---|---|---|"
printf '%s\n' "${rows[@]}"
