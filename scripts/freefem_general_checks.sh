#!/usr/bin/env bash
# FreeFEM-only checks of the general rod (docs/decisions.md D20-D23: a reference configuration, the chart of a case,
# clamped / pinned / free / moving ends, point loads) against exact or independent answers: a reference arc that
# stays put and lies on its circle, the roll-up of a cantilever into a full circle (order 2), a pinned-pinned column
# against Timoshenko's beam, a held twist in any orientation, follower point loads, moving clamps (static and in
# time, against the exact torsion wave), the dynamic cantilever in another chart, and the 45-degree bend against
# Simo & Vu-Quoc. Each case.idp is written by scripts/freefem_general_checks.py; nothing here needs the Rust engine.
# Not a cargo test (about 4 minutes on 2 cores); the cross-engine tests of these features are in tests/.
# Usage: scripts/freefem_general_checks.sh [--keep DIR] [--only NAME ...]     exit status 1 if a check fails
set -euo pipefail
cd "$(dirname "$0")/.."
command -v FreeFem++ >/dev/null || { echo "FreeFem++ not found: apt-get install -y freefem++ libfreefem++" >&2; exit 2; }
export FF_LOADPATH=${FF_LOADPATH:-/usr/lib/freefem++}
grep -m1 "model name" /proc/cpuinfo || true
exec python3 scripts/freefem_general_checks.py "$@"
