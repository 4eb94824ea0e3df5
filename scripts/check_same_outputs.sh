#!/usr/bin/env bash
# Are the output folders of two `cosserat` binaries byte-identical on every case? For a
# refactoring that must not change what a run writes: each case of cases/ (top level,
# benchmarks/, batch/, paper/ — or the files given) run by both binaries in the Rust engine
# (`cosserat run CASE --quiet --out DIR`), then every file of the two folders compared byte for
# byte, except run.json, whose wall times, pid, host and dates differ between any two runs: there
# only the lines without those keys are compared. Also compares `--help` of every command.
#
#   [ENGINE=freefem] scripts/check_same_outputs.sh BEFORE_BINARY AFTER_BINARY [CASE.toml …]
#
# Prints one line per case (same / DIFFERENT and the files that differ) and exits 1 if any case
# differs. Not a test (it needs two builds); takes about 10 min on 2 cores for every case.
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 2 ] || { sed -n '2,12p' "$0"; exit 2; }
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
# both copied under the same file name: clap's usage lines name the binary as it was called
mkdir -p "$tmp/before" "$tmp/after"
cp "$1" "$tmp/before/cosserat"; cp "$2" "$tmp/after/cosserat"
before="$tmp/before/cosserat"; after="$tmp/after/cosserat"; shift 2
if [ $# -gt 0 ]; then cases=("$@"); else mapfile -t cases < <(ls cases/*.toml cases/*/*.toml); fi
# run.json keys that hold times, the process or the binary (differ between any two runs)
volatile='"([a-z_]*wall[a-z_]*|[a-z_]*unix[a-z_]*|pid|host[a-z_]*|[a-z_]*rss[a-z_]*|cpu_s)"'
differ=0
for c in "${cases[@]}"; do
  name=$(echo "$c" | tr '/' '_'); a="$tmp/a_$name"; b="$tmp/b_$name"
  ra=0; rb=0; out="$tmp/out"  # one folder name for both: messages name it
  "$before" run "$c" --engine "${ENGINE:-rust}" --quiet --out "$out" >/dev/null 2>"$a.err" || ra=$?
  [ ! -e "$out" ] || mv "$out" "$a"
  "$after" run "$c" --engine "${ENGINE:-rust}" --quiet --out "$out" >/dev/null 2>"$b.err" || rb=$?
  [ ! -e "$out" ] || mv "$out" "$b"
  bad=()
  [ "$ra" = "$rb" ] || bad+=("exit $ra vs $rb")
  diff -q <(sed -E "s/pid [0-9]+/pid N/g; s/[0-9.]+ s\b/T s/g" "$a.err") \
          <(sed -E "s/pid [0-9]+/pid N/g; s/[0-9.]+ s\b/T s/g" "$b.err") >/dev/null || bad+=("stderr")
  if [ -d "$a" ] || [ -d "$b" ]; then
    files=$( (cd "$a" 2>/dev/null && find . -type f; cd "$b" 2>/dev/null && find . -type f) | sort -u)
    for f in $files; do
      if [ ! -f "$a/$f" ] || [ ! -f "$b/$f" ]; then bad+=("$f (only one)"); continue; fi
      case "$f" in
        */run.json|./run.json|*/metrics.json|./metrics.json)
          cmp -s <(grep -Ev "$volatile" "$a/$f") <(grep -Ev "$volatile" "$b/$f") || bad+=("$f") ;;
        */frames.csv|./frames.csv|*/iterations.csv|./iterations.csv|*/summary.csv|./summary.csv)
          # the per-frame and per-iteration wall times are columns: compare the others
          python3 - "$a/$f" "$b/$f" <<'PY' || bad+=("$f")
import csv, sys
ra, rb = (list(csv.reader(open(p))) for p in sys.argv[1:3])
if len(ra) != len(rb) or ra[:1] != rb[:1]:
    sys.exit(1)
keep = [i for i, h in enumerate(ra[0]) if not ("wall" in h or h.endswith("_s") and "time" in h)] if ra else []
sys.exit(any([r[i] for i in keep if i < len(r)] != [s[i] for i in keep if i < len(s)] for r, s in zip(ra[1:], rb[1:])))
PY
          ;;
        *) cmp -s "$a/$f" "$b/$f" || bad+=("$f") ;;
      esac
    done
  fi
  if [ ${#bad[@]} -eq 0 ]; then echo "same       $c (exit $ra)"; else echo "DIFFERENT  $c: ${bad[*]}"; differ=1; fi
  rm -rf "$a" "$b"
done
for cmd in "" run compare sweep audit batch batch-task gather synth list modes buckling noise-study; do
  if ! cmp -s <("$before" $cmd --help 2>&1) <("$after" $cmd --help 2>&1); then
    echo "DIFFERENT  --help of '${cmd:-cosserat}'"; differ=1
  fi
done
echo "help texts compared"
exit $differ
