"""Reconstruct a synthetic recording and draw its kymographs (recovered and true bending
curvature κ2 along the body over time) with matplotlib.

    python python/examples/kymograph.py [OUT.png]

Run from the repository (it reads data/elegansbot/kymogram_omega-turn.npy, which
scripts/fetch_worm_data.sh fetches); writes kymograph.png by default.
"""
import sys
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import cosserat  # noqa: E402

out = sys.argv[1] if len(sys.argv) > 1 else "kymograph.png"

# a rolling, twisting worm of 1 mm: 100 frames at 25 frames/s, 49 nodes, 1 µm tracking noise
(rec,) = cosserat.synth(count=1, frames=100, nodes=49, noise_m=1e-6, seed=2, max_roll_rad=0.0, max_twist_per_m=0.0)
x = rec["positions_m"]
x[40, 20:26] = np.nan  # a few untracked nodes

start = time.perf_counter()
r = cosserat.reconstruct(x, frame_interval_s=0.04, progress=lambda done, total: None)
print(
    f"{r['frames_done']} frames in {time.perf_counter() - start:.2f} s: status {r['status']} ({r['frames']['flagged'].sum()} frames over the fit gate), "
    f"body length {r['body_length_m'] * 1e3:.4f} mm, noise {r['noise_m'] * 1e6:.2f} µm, lambda_g {r['lambda_g']:.3g}, "
    f"largest certificate {r['frames']['certificate'].max():.1e}"
)

t_s = r["frames"]["time_s"]
s_mm = r["s_mid_m"] * 1e3
kappa2 = r["kappa_per_m"][..., 1] * 1e-3  # [1/mm]
truth = rec["kappa_per_m"][..., 1] * 1e-3
truth_mid = 0.5 * (truth[:, 1:] + truth[:, :-1])
lim = np.abs(truth_mid).max()

fig, axes = plt.subplots(1, 3, figsize=(12, 3.6), sharey=True, constrained_layout=True)
panels = [(kappa2, "recovered κ2"), (truth_mid, "true κ2"), (kappa2 - truth_mid, "recovered − true")]
for ax, (k, title) in zip(axes, panels):
    im = ax.pcolormesh(t_s, s_mm, k.T, cmap="RdBu_r", vmin=-lim, vmax=lim, shading="nearest")
    ax.set_title(title)
    ax.set_xlabel("time [s]")
axes[0].set_ylabel("arc length s [mm]")
fig.colorbar(im, ax=axes, label="curvature [1/mm]")
fig.suptitle("Kymograph of a synthetic recording reconstructed by cosserat.reconstruct")
fig.savefig(out, dpi=110)
print(f"wrote {out}")
