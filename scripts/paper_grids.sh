#!/usr/bin/env bash
# Every grid of the §5.2 audit specs (cases/paper/sec52_eq64.toml, sec52_eq65.toml: λl, λd, λf
# and λκ3 at the specs' fixed settings) with both solvers: the paper's fixed point run until its
# relative change stays within 1e-9 (3000 iterations at most) and Newton from the fixed point's
# iterate at 1e-4 (tolerance 1e-10), each ending converged only with a certified iterate
# (docs/certificate.md). Prints, per grid, the points each solver certifies and any point the
# fixed point certifies that Newton does not. Usage: scripts/paper_grids.sh [OUT] [QUADRATURE]
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out/paper_grids}
quad=${2:-selective}
bin=target/release/cosserat
cargo build --release --quiet
mkdir -p "$out/cases"
# eq  grid  fixed settings (sed expressions on the case file)  --set grid
grids=(
  "64|ll|s/^lambda_kappa = .*/lambda_kappa = [0, 0, 1e-20]/|lambda_l=1e-20,1e-15,1e-10,1e-6,1e-3,1,1e3"
  "64|ld|s/^lambda_kappa = .*/lambda_kappa = [0, 0, 1e-20]/|lambda_d=1e-10,1e-8,1e-6,1e-4,1e-2,1,10"
  "64|lf|s/^lambda_kappa = .*/lambda_kappa = [0, 0, 1e-20]/|lambda_f=1e-10,1e-6,1e-2,1,1e2,1e4,1e6"
  "64|lk3|s/^lambda_kappa = .*/lambda_kappa = [0, 0, 1e-10]/|lambda_kappa3=1e-15,1e-10,1e-8,1e-5,1e-2,1"
  "65|ll|s/^lambda_f = .*/lambda_f = 1/;s/^lambda_kappa = .*/lambda_kappa = [0, 0, 1e-20]/|lambda_l=1e-30,1e-20,1e-10,1e-6,1e-2"
  "65|ld|s/^lambda_f = .*/lambda_f = 1/;s/^lambda_kappa = .*/lambda_kappa = [0, 0, 1e-20]/|lambda_d=1e-14,1e-10,1e-6,1e-2,1,1e3"
  "65|lf|s/^lambda_kappa = .*/lambda_kappa = [0, 0, 1e-20]/|lambda_f=1e-30,1e-10,1e-2,1,1e2"
  "65|lk3|s/^lambda_kappa = .*/lambda_kappa = [0, 0, 1e-15]/|lambda_kappa3=1e-15,1e-10,1e-8,1e-5,1e-2,1"
)
for g in "${grids[@]}"; do
  IFS='|' read -r eq name fixed set <<<"$g"
  case $eq in 64) base=cases/inverse_bend.toml ;; 65) base=cases/inverse_bend_twist.toml ;; esac
  fp="$out/cases/eq${eq}_${name}_fixed_point.toml"
  nt="$out/cases/eq${eq}_${name}_newton.toml"
  sed -e "$fixed" -e 's/^tolerance = 3e-6/tolerance = 1e-9/' -e 's/^max_iterations = 1000/max_iterations = 3000/' "$base" >"$fp"
  sed -e "$fixed" -e 's/^method = "fixed_point"/method = "newton"\nwarm_start_tolerance = 1e-4/' \
      -e 's/^tolerance = 3e-6/tolerance = 1e-10/' -e 's/^max_iterations = 1000/max_iterations = 300/' "$base" >"$nt"
  for solver in fixed_point newton; do
    $bin sweep "$out/cases/eq${eq}_${name}_${solver}.toml" --set "$set" --set "quadrature=$quad" \
      --out "$out/eq${eq}_${name}_${solver}" --force --quiet >/dev/null 2>&1 || true
  done
  echo "== eq. ($eq) grid $name ($quad): value: fixed point | Newton (status certificate iterations)"
  paste -d'|' <(cut -d, -f1,3-5 "$out/eq${eq}_${name}_fixed_point/summary.csv") \
              <(cut -d, -f3-5 "$out/eq${eq}_${name}_newton/summary.csv") | tail -n +2 |
    awk -F'[|,]' '{ flag = ($2 == "ok" && $5 != "ok") ? "   <-- fixed point only" : ""; printf "  %s: %s %s %s | %s %s %s%s\n", $1, $2, $4, $3, $5, $7, $6, flag }'
done
