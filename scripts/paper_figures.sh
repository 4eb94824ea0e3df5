#!/usr/bin/env bash
# The paper's figures as PNG for the README: converts every figure of a full audit
# (out/audit/<spec>/fig*.svg, `scripts/audit.sh` writes them) into docs/figures/ with
# rsvg-convert (Debian: apt-get install librsvg2-bin).
# Usage: scripts/paper_figures.sh [AUDIT_FOLDER, default out/audit]
set -euo pipefail
cd "$(dirname "$0")/.."
audit=${1:-out/audit}
command -v rsvg-convert >/dev/null || { echo "rsvg-convert not found: apt-get install librsvg2-bin" >&2; exit 1; }
[ -f "$audit/REPORT.md" ] || { echo "$audit holds no audit (run scripts/audit.sh)" >&2; exit 1; }
if grep -q -- '--quick' "$audit/REPORT.md"; then
    echo "$audit is a quick audit: the README shows the full audit's figures" >&2
    exit 1
fi
mkdir -p docs/figures
# the audit's figures only (fig*.png): the other PNGs there (deep_arch_path.png) are drawn elsewhere
rm -f docs/figures/fig*.png
for svg in "$audit"/*/fig*.svg; do
    png="docs/figures/$(basename "${svg%.svg}").png"
    rsvg-convert "$svg" -o "$png"
    echo "$png"
done
