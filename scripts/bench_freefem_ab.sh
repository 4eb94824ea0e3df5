#!/usr/bin/env bash
# FreeFEM engine speed, before against after, in ONE run on one machine (not a test: nothing here
# asserts). The FreeFEM scripts of git revision BEFORE (default 0d7d428, the scripts before the
# issue-31 work) and of the working tree run the same inputs, interleaved ROUNDS times (default 3):
#   clip:    the first 6 frames of cases/worm_delta_turn_ld1.toml (the Newton inverse, 127 elements);
#   dynamic: the first 100 of the 1000 time steps of cases/cantilever_dynamic.toml (100 elements).
# Reported: FreeFEM's own CPU time (clock()) per clip frame (ff_clip_frames.csv: the frame's own time) and per
# time step ((T(100 steps) - T(1 step))/99 from ff_info.csv: the script's set-up, ~0.06 s now, not counted), each
# round, and the ratio of the means. The inputs (case.idp, clip data) are written once by `cosserat compare`.
# Usage: scripts/bench_freefem_ab.sh [BEFORE [ROUNDS]]
set -euo pipefail
cd "$(dirname "$0")/.."
before=${1:-0d7d428}
rounds=${2:-3}
cargo build --release -q
bin=$PWD/target/release/cosserat
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
grep -m1 "model name" /proc/cpuinfo || echo "CPU: $(lscpu | grep -m1 'Vendor ID' || true)"
mkdir -p "$tmp/before"
git archive "$before" freefem | tar -x -C "$tmp/before"
$bin compare cases/worm_delta_turn_ld1.toml --frames 6 --out "$tmp/clip" >/dev/null 2>&1
$bin compare cases/cantilever_dynamic.toml --short --out "$tmp/dyn" >/dev/null 2>&1
# the dynamic input cut to its first 100 steps (the same time step)
python3 -c '
import re, sys
p = sys.argv[1]
s = open(p).read()
n = int(re.search(r"^int nsteps = (\d+);$", s, re.M).group(1))
s = re.sub(r"^real Tend = (.*);$", lambda m: "real Tend = (%s)*100./%d.;" % (m.group(1), n), s, flags=re.M)
s = re.sub(r"^int nsteps = \d+;$", "int nsteps = 100;", s, flags=re.M)
open(p, "w").write(s)' "$tmp/dyn/freefem_work/case.idp"
# and a copy cut to its first step (the set-up's time)
cp -r "$tmp/dyn/freefem_work" "$tmp/dyn1"
sed -i 's/^int nsteps = 100;$/int nsteps = 1;/; s/^real Tend = \(.*\)\*100\.\/\(.*\);$/real Tend = \1*1.\/\2;/' "$tmp/dyn1/case.idp"
grep -q '^int nsteps = 1;$' "$tmp/dyn1/case.idp"
export FF_LOADPATH=/usr/lib/freefem++
clip_cpu() {  # mean CPU per frame of one clip run with the scripts in $1
  (cd "$tmp/clip/freefem_work" && FreeFem++ -nw -v 0 "$1/clip.edp" >/dev/null 2>&1)
  python3 -c "import csv; r=list(csv.DictReader(open('$tmp/clip/freefem_work/ff_clip_frames.csv'))); print(sum(float(x['wall_time_s']) for x in r)/len(r))"
}
step_cpu() {  # CPU per time step of the dynamic run with the scripts in $1, without the set-up (the 1-step run's time)
  (cd "$tmp/dyn/freefem_work" && FreeFem++ -nw -v 0 "$1/forward.edp" >/dev/null 2>&1)
  (cd "$tmp/dyn1" && FreeFem++ -nw -v 0 "$1/forward.edp" >/dev/null 2>&1)
  python3 -c "
import csv
d = dict(csv.reader(open('$tmp/dyn/freefem_work/ff_info.csv')))
e = dict(csv.reader(open('$tmp/dyn1/ff_info.csv')))
assert int(d['steps']) == 100 and int(e['steps']) == 1
print((float(d['wall_time_s']) - float(e['wall_time_s'])) / 99.)"
}
cb=(); ca=(); sb=(); sa=()
for r in $(seq 1 "$rounds"); do
  cb+=("$(clip_cpu "$tmp/before/freefem")"); ca+=("$(clip_cpu "$PWD/freefem")")
  sb+=("$(step_cpu "$tmp/before/freefem")"); sa+=("$(step_cpu "$PWD/freefem")")
  echo "round $r (load $(cut -d' ' -f1 /proc/loadavg)): clip frame ${cb[-1]} -> ${ca[-1]} s; time step ${sb[-1]} -> ${sa[-1]} s"
done
python3 - "${cb[*]}" "${ca[*]}" "${sb[*]}" "${sa[*]}" "$before" <<'EOF'
import sys
m = [sum(map(float, a.split())) / len(a.split()) for a in sys.argv[1:5]]
print(f"mean CPU per clip frame: {m[0]:.3f} s ({sys.argv[5]}) -> {m[1]:.3f} s (working tree): {m[0]/m[1]:.1f}x")
print(f"mean CPU per time step:  {m[2]:.4f} s ({sys.argv[5]}) -> {m[3]:.4f} s (working tree): {m[2]/m[3]:.1f}x")
EOF
