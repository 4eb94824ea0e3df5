#!/usr/bin/env bash
# Every committed case of cases/*.toml run by two builds of cosserat (Rust engine, or both engines
# with ENGINE=freefem), and every output file compared byte for byte (run.json and metrics.json,
# which hold wall times and the program's build, are compared without their timing keys).
#   bash scripts/outputs_identical.sh OLD_BINARY NEW_BINARY [CASE.toml ...]
# Prints one line per case: identical, or the files that differ; exit 1 if any differ.
# With ENGINE=freefem, OLD_FREEFEM_DIR=DIR gives the old build its own freefem/ scripts (a checkout
# of the old commit), as COSSERAT_FREEFEM_DIR; the new build uses this checkout's.
set -uo pipefail
old=$1; new=$2; shift 2
cd "$(dirname "$0")/.."
cases=("$@")
[ ${#cases[@]} -eq 0 ] && cases=(cases/*.toml)
engine=${ENGINE:-rust}
work=$(mktemp -d)
status=0
strip() { # drop keys whose values are times, versions or paths of the run
  python3 - "$1" <<'PY'
import json, sys
def clean(v):
    if isinstance(v, dict):
        return {k: clean(x) for k, x in v.items() if not any(w in k for w in ("wall", "time_s", "elapsed", "version", "pid", "started", "finished", "host", "command", "path", "dir", "duration"))}
    if isinstance(v, list):
        return [clean(x) for x in v]
    return v
print(json.dumps(clean(json.load(open(sys.argv[1]))), sort_keys=True))
PY
}
for c in "${cases[@]}"; do
  name=$(basename "$c" .toml)
  COSSERAT_FREEFEM_DIR=${OLD_FREEFEM_DIR:-$PWD/freefem} "$old" run "$c" --engine "$engine" --out "$work/old/$name" --quiet >/dev/null 2>&1
  COSSERAT_FREEFEM_DIR=$PWD/freefem "$new" run "$c" --engine "$engine" --out "$work/new/$name" --quiet >/dev/null 2>&1
  diffs=()
  while IFS= read -r f; do
    rel=${f#"$work/old/$name/"}
    g="$work/new/$name/$rel"
    if [ ! -f "$g" ]; then diffs+=("$rel(missing)"); continue; fi
    case "$rel" in
      *.json) [ "$(strip "$f")" == "$(strip "$g")" ] || diffs+=("$rel") ;;
      *) cmp -s "$f" "$g" || diffs+=("$rel") ;;
    esac
  done < <(find "$work/old/$name" -type f | sort)
  n=$(find "$work/old/$name" -type f | wc -l)
  if [ ${#diffs[@]} -eq 0 ]; then echo "$name: identical ($n files)"; else echo "$name: DIFFERENT: ${diffs[*]}"; status=1; fi
done
rm -rf "$work"
exit $status
