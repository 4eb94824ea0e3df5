#!/usr/bin/env python3
"""The helical-buckling benchmark's figure: the rod's distance from the axis and its lateral
components along s, in both engines, against the localised helix of van der Heijden, Neukirch,
Goss & Thompson (2003), Int. J. Mech. Sci. 45, 161-196, Eqs. 27, 52 (the formulas and the
constants are those of cases/benchmarks/helical_buckling.toml, read from it).

    scripts/helical_buckling_figure.py CASE.toml RUST_NODES.csv [FREEFEM_NODES.csv] OUT.svg

Writes OUT.svg (convert with `rsvg-convert -w 1400 OUT.svg -o OUT.png`). Needs matplotlib
(`.venv/bin/python`, scripts/install_deps.sh).
"""
import csv
import math
import sys
import tomllib

import matplotlib

matplotlib.use("svg")
import matplotlib.pyplot as plt  # noqa: E402


def constants(case_path):
    with open(case_path, "rb") as f:
        c = tomllib.load(f)["constants"]
    length, b, d, force = (float(c[k]) for k in ("L", "B", "D", "F"))
    moment, tension = float(c["m"]) * b / length, float(c["tau"]) * b / length**2
    k = math.sqrt(4 * b * tension - moment**2) / (2 * b)
    a = 2 - moment**2 / (2 * b * tension)
    return dict(L=length, D=d, F=force, T=tension, k=k, a=a, omega=moment / (2 * b))


def helix(c, sigma, tent=True):
    """x, y of the localised helix at sigma = s - L/2 [m], with the imperfection's tent."""
    rho = c["a"] / c["k"] / math.cosh(c["k"] * sigma)
    x = rho * math.cos(c["omega"] * sigma)
    if tent:
        x += c["F"] / (2 * c["T"]) * (c["L"] / 2 - abs(sigma))
    return x, rho * math.sin(c["omega"] * sigma)


def nodes(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return [(float(r["s_m"]), float(r["x_m"]), float(r["y_m"])) for r in rows]


def main(argv):
    if len(argv) not in (4, 5):
        sys.exit(__doc__)
    c = constants(argv[1])
    engines = [("Rust", argv[2], "-", "C0")]
    if len(argv) == 5:
        engines.append(("FreeFEM", argv[3], "none", "C3"))
    out = argv[-1]
    s = [c["L"] * i / 2000 for i in range(2001)]
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(9, 7.5), sharex=True)
    env = [c["a"] / c["k"] / math.cosh(c["k"] * (si - c["L"] / 2)) for si in s]
    with_tent = [math.hypot(*helix(c, si - c["L"] / 2)) for si in s]
    ax1.plot(s, env, "k:", lw=1.2, label="envelope (a/k) sech(k(s - L/2)), max D/2 (Eqs. 27, 52)")
    ax1.plot(s, with_tent, "k--", lw=1.2, label="localised helix + the imperfection's tent F/(2T)(L/2 - |s - L/2|)")
    xa = [helix(c, si - c["L"] / 2)[0] for si in s]
    ya = [helix(c, si - c["L"] / 2)[1] for si in s]
    ax2.plot(s, xa, "k--", lw=1.2, label="helix + tent: x")
    ax2.plot(s, ya, "k:", lw=1.2, label="helix: y")
    for name, path, ls, colour in engines:
        pts = nodes(path)
        sn = [p[0] for p in pts]
        marker = "o" if ls == "none" else None
        kw = dict(ls=ls, color=colour, marker=marker, ms=3.5, mfc="none", lw=1.6)
        ax1.plot(sn, [math.hypot(p[1], p[2]) for p in pts], label=f"{name}, {len(pts) - 1} elements", **kw)
        ax2.plot(sn, [p[1] for p in pts], label=f"{name}: x", **kw)
        ax2.plot(sn, [p[2] for p in pts], alpha=0.55, **{**kw, "color": "C2" if colour == "C0" else "C1"},
                 label=f"{name}: y")
    ax1.set_ylabel("distance from the axis [m]")
    ax1.set_title("Helical buckling under end twist: L = 100 m, slack D = 3 m, 27 turns, both ends clamped")
    ax1.legend(fontsize=8, loc="upper left")
    ax1.grid(alpha=0.3)
    ax2.set_xlabel("reference arc length s [m]")
    ax2.set_ylabel("lateral position [m]")
    ax2.legend(fontsize=8, loc="upper left", ncol=2)
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out)


if __name__ == "__main__":
    main(sys.argv)
