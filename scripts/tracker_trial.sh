#!/usr/bin/env bash
# The tracker trial of docs/results.md ("Tracker recordings"): two worms as a single-camera
# tracker records them (`cosserat synth --tracker`: 1.1 and 0.85 mm, 49 points, 30 frames/s,
# 300 frames, 1 µm of noise in x and y, lost frames and lost tail points, with their truth),
# reconstructed with cases/worm_2d_recording.toml as shipped (automatic weights), with
# clip.noise_m = 1e-6 stated, and with clip.start = "data_guess"; then two planar recordings
# with nothing lost and the length given (the omega turn at 1 µm, the delta turn at 1.5 µm of
# noise). Every run is scored against the truth beside the GCV smoothing spline
# (examples/tracker_score.rs). About a minute on 2 cores.
#
# BEFORE=/path/to/an/older/cosserat also runs that program on the same data converted to the
# only format it read (CSV frame,node,x_m,y_m,z_m from frame 0, z = 0, NaN for untracked
# nodes and dropped frames), with the body length given and the section scaled by hand.
# OUT=folder (default out/tracker_trial) keeps everything.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q --bin cosserat --example tracker_score
bin=$PWD/target/release/cosserat
score=$PWD/target/release/examples/tracker_score
out=${OUT:-out/tracker_trial}
rm -rf "$out"
mkdir -p "$out/runs"
out=$(realpath "$out")
template=cases/worm_2d_recording.toml
$bin synth --tracker --out "$out/data" >/dev/null
for turn in omega:1e-6 delta:1.5e-6; do
  $bin synth --tracker --out "$out/planar_${turn%%:*}" --count 1 --length-m 1e-3 --noise-m "${turn#*:}" \
    --kymogram "data/elegansbot/kymogram_${turn%%:*}-turn.npy" --lost-frames 0 --tail-lost-frames 0 >/dev/null
done

# case NAME RECORDING [SED-EXPRESSION]: the template on RECORDING, edited
case_for() {
  sed -e "s#^file = \"../data/tracker/worm_000.csv\"#file = \"$2\"#" ${3:+-e "$3"} "$template" > "$out/$1.toml"
  grep -q "^file = \"$2\"" "$out/$1.toml"
}
run() {
  if ! "$bin" run "$out/$1.toml" --out "$out/runs/$1" --quiet > "$out/runs/$1.txt" 2>&1; then
    echo "$1: the run failed: $(tail -n 1 "$out/runs/$1.txt")"
  fi
}
# the older program's case: the template without the keys it did not have, length and radius given
before_case() {
  sed -e "s#^file = .*#file = \"$2\"#" -e "s#^length_m = .*#length_m = $3#" -e "/^section_length_m/d" \
    -e "s#^radius_m = .*#radius_m = $(awk "BEGIN { print 2e-5 * $3 / 1e-3 }")#" "$template" > "$out/$1.toml"
}
# tracker CSV (frame,node,x_um,y_um from any frame) -> frame,node,x_m,y_m,z_m from 0, NaN gaps
convert() {
  awk -F, 'NR > 1 { f = $1 + 0; if (!(f in seen)) { seen[f] = 1 }; if (NR == 2 || f < lo) lo = f; if (f > hi) hi = f;
                    if ($2 + 0 > nmax) nmax = $2 + 0;
                    v[f "," $2] = ($3 == "" || $3 == "NaN") ? "NaN,NaN" : sprintf("%.10e,%.10e", $3 * 1e-6, $4 * 1e-6) }
           END { print "frame,node,x_m,y_m,z_m";
                 for (f = lo; f <= hi; f++) for (i = 0; i <= nmax; i++) {
                   k = f "," i; print (f - lo) "," i "," ((k in v) ? v[k] : "NaN,NaN") ",0" } }' "$1" > "$2"
}
# run_before NAME RECORDING LENGTH: the older program on the converted RECORDING, runs/NAME_before
run_before() {
  convert "$2" "$out/data/$1_m.csv"
  before_case "$1_before" "$out/data/$1_m.csv" "$3"
  "$BEFORE" run "$out/$1_before.toml" --out "$out/runs/$1_before" --quiet > "$out/runs/$1_before.txt" 2>&1 \
    || echo "$1 before: $(tail -n 1 "$out/runs/$1_before.txt")"
}

for w in 000 001; do
  rec="$out/data/worm_$w.csv"
  case_for "worm_${w}_auto" "$rec"
  case_for "worm_${w}_noise_m" "$rec" 's#^missing = "nan"#missing = "nan"\nnoise_m = 1e-6#'
  case_for "worm_${w}_data_guess" "$rec" 's#^start = "previous_frame"#start = "data_guess"#'
  runs=()
  for v in auto noise_m data_guess; do run "worm_${w}_$v"; runs+=("$out/runs/worm_${w}_$v"); done
  if [ -n "${BEFORE:-}" ]; then
    run_before "worm_$w" "$rec" "$(awk -v w="$w" 'BEGIN { print (w == "000") ? 1.1e-3 : 0.85e-3 }')"
    runs+=("$out/runs/worm_${w}_before")
  fi
  echo
  $score "$rec" "${runs[@]}"
done
for turn in omega delta; do
  rec="$out/planar_$turn/worm_000.csv"
  case_for "planar_${turn}" "$rec" 's#^length_m = "from_data"#length_m = 1e-3#'
  run "planar_${turn}"
  runs=("$out/runs/planar_${turn}")
  if [ -n "${BEFORE:-}" ]; then
    run_before "planar_$turn" "$rec" 1e-3
    runs+=("$out/runs/planar_${turn}_before")
  fi
  echo
  $score "$rec" "${runs[@]}"
done
