#!/usr/bin/env python3
"""Snapshots of the three-dimensional flying spaghetti (docs/benchmarks.md, D32), projected on
the x-z and x-y planes, as an SVG on stdout. Each argument is a run folder of the case ended at
the snapshot's time (`cosserat run` with `T` and `steps` scaled together, so every run takes the
same time steps): its nodes.csv (positions in space) and the T of its folder name `t_T`.

    for k in "1.25 50" "2.5 100" ...; do set -- $k; sed -e "s/^T = 10 /T = $1 /" \
        -e "s/^steps = 400/steps = $2/" cases/benchmarks/flying_spaghetti_3d.toml > c.toml
        cosserat run c.toml --quiet --out t_$1; done
    python3 scripts/figure_flying_spaghetti_3d.py t_* > f.svg && rsvg-convert f.svg -o f.png
"""
import csv
import sys

runs = []
for d in sys.argv[1:]:
    t = float(d.rstrip("/").split("t_")[-1])
    rows = list(csv.DictReader(open(f"{d}/nodes.csv")))
    runs.append((t, [(float(r["x_m"]), float(r["y_m"]), float(r["z_m"])) for r in rows]))
    # the reference (t = 0): x - u
    ref = [tuple(float(r[f"{c}_m"]) - float(r[f"u{c}_m"]) for c in "xyz") for r in rows]
runs.append((0.0, ref))
runs.sort()
W, H, M = 900, 320, 50  # panel width, height, margin [px]
xs = [p[0] for _, ps in runs for p in ps]
lo, hi = min(xs) - 1, max(xs) + 1
scale = (W - 2 * M) / (hi - lo)
out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{2 * H + 40}" font-family="sans-serif" font-size="13">',
       f'<rect width="{W}" height="{2 * H + 40}" fill="white"/>',
       f'<text x="{W / 2}" y="22" text-anchor="middle" font-size="15">The flying spaghetti in space: the rod every 1.25 s (blue: loaded, until 5 s; the dot is the loaded end s = L)</text>']
for k, (axis, name) in enumerate([(2, "z"), (1, "y")]):
    y0 = 40 + k * H + (H - 40 if axis == 2 else H / 2)  # the axis' zero line (z >= 0 above it)
    X = lambda v: M + (v - lo) * scale
    Y = lambda v: y0 - v * scale
    out.append(f'<line x1="{M}" y1="{y0}" x2="{W - M}" y2="{y0}" stroke="#bbb"/>')
    out.append(f'<text x="{M - 8}" y="{y0 + 4}" text-anchor="end">{name} = 0</text>')
    out.append(f'<text x="{W - M}" y="{40 + k * H + 16}" text-anchor="end">x–{name} projection (1 m = {scale:.0f} px)</text>')
    for i, (t, ps) in enumerate(runs):
        shade = int(200 * (1 - i / max(1, len(runs) - 1)))
        colour = f"rgb({shade},{shade},{255 if t <= 5 else shade})"
        pts = " ".join(f"{X(p[0]):.1f},{Y(p[axis]):.1f}" for p in ps)
        out.append(f'<polyline points="{pts}" fill="none" stroke="{colour}" stroke-width="2"/>')
        out.append(f'<circle cx="{X(ps[-1][0]):.1f}" cy="{Y(ps[-1][axis]):.1f}" r="3" fill="{colour}"/>')
        if k == 0:
            cx = sum(p[0] for p in ps) / len(ps)
            out.append(f'<text x="{X(cx):.1f}" y="{40 + H - 22 + 14 * (i % 2)}" text-anchor="middle" font-size="11">{t:g} s</text>')
out.append("</svg>")
print("\n".join(out))
