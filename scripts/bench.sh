#!/usr/bin/env bash
# Benchmark of what exists today (groundwork for issue 5's speed goals; not those goals):
# wall time and peak memory of whole processes, Rust vs FreeFEM where both run.
#   - Timoshenko 10 %: `cosserat run` end to end (best of 5).
#   - Dynamic cantilever: `cosserat run` end to end.
#   - Worm clip (omega turn, Table 1 by Newton, 600 frames): frames/s, iterations, peak RSS.
#   - FreeFEM vs Rust on the first worm frame (same element, same data): per-frame time ratio.
# Needs the worm data (scripts/fetch_worm_data.sh). Prints a table; writes nothing else.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q
bin=target/release/cosserat
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
wall() { /usr/bin/time -f "%e %M" -o "$tmp/t" "$@" >/dev/null 2>&1; cat "$tmp/t"; }
best=1e9
for _ in 1 2 3 4 5; do
  t=$(wall $bin run cases/timoshenko_10pct.toml --quiet --out "$tmp/t10" | cut -d' ' -f1)
  best=$(python3 -c "print(min($best, $t))")
done
echo "timoshenko_10pct   whole process best of 5: ${best} s"
read -r t m < <(wall $bin run cases/cantilever_dynamic.toml --quiet --out "$tmp/dyn")
echo "cantilever_dynamic whole process: ${t} s, peak RSS $((m / 1024)) MB"
sed -e 's/^method = "fixed_point"/method = "newton"\nwarm_start_tolerance = 1e-3/' -e 's/^tolerance = 1e-6/tolerance = 1e-10/' \
    -e "s|file = \"../data|file = \"$PWD/data|" cases/worm_omega_turn.toml > "$tmp/worm.toml"
read -r t m < <(wall $bin run "$tmp/worm.toml" --quiet --out "$tmp/worm")
frames=$(($(wc -l < "$tmp/worm/frames.csv") - 1))
its=$(python3 -c "import csv; r=list(csv.DictReader(open('$tmp/worm/frames.csv'))); print('%.1f' % (sum(float(x['iterations']) for x in r)/len(r)))")
echo "worm_omega_turn (Table 1, Newton): ${frames} frames in ${t} s ($(python3 -c "print('%.1f' % ($frames/$t))") frames/s), mean ${its} iterations/frame, peak RSS $((m / 1024)) MB"
read -r t m < <(wall $bin run cases/worm_omega_turn_ld1.toml --quiet --out "$tmp/ld1")
frames=$(($(wc -l < "$tmp/ld1/frames.csv") - 1))
echo "worm_omega_turn_ld1 (case file): ${frames} frames in ${t} s ($(python3 -c "print('%.1f' % ($frames/$t))") frames/s), peak RSS $((m / 1024)) MB"
cargo run --release -q --example bench_kkt
$bin compare cases/worm_omega_turn.toml --out "$tmp/cmp" | grep "wall time"
