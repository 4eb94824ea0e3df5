"""What `reconstruct` costs outside the engine's clip solve, with the recording handed over in
memory (now) against through a temporary .npy file (before: `np.save`, then the engine reads
the file as `cosserat run` does), in one process on one recording.

    .venv/bin/python python/bench/bench_memory_input.py [FRAMES] [NODES] [REPEATS]

On a synthetic 3D recording (`cosserat.synth`, 1 µm noise) of FRAMES × NODES (default 300 × 128)
with fixed weights (no calibration before the clip): per path the best of REPEATS (default 3)
of the call's wall time, the engine's clip time (`wall_time_s`) and the difference, the
overhead. Both paths give the same bits (checked).
"""
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import cosserat

ROOT = Path(__file__).resolve().parents[2]
frames = int(sys.argv[1]) if len(sys.argv) > 1 else 300
nodes = int(sys.argv[2]) if len(sys.argv) > 2 else 128
repeats = int(sys.argv[3]) if len(sys.argv) > 3 else 3
kym = ROOT / "data" / "elegansbot" / "kymogram_omega-turn.npy"
(rec,) = cosserat.synth(count=1, frames=frames, nodes=nodes, noise_m=1e-6, seed=5, kymogram=kym)
x = rec["positions_m"]
weights = {"lambda_g": 1e9}


def through_a_file():
    """The call as it was: the array saved as a temporary .npy, the engine reading that file."""
    with tempfile.TemporaryDirectory(prefix="cosserat-") as tmp:
        file = os.path.join(tmp, "recording.npy")
        np.save(file, x, allow_pickle=False)
        text = cosserat.recording_case(nodes=nodes, frame_interval_s=0.04, file=file, weights=weights)
        return cosserat.run_case(text)


def in_memory():
    return cosserat.reconstruct(x, frame_interval_s=0.04, weights=weights)


def best(f):
    runs = []
    for _ in range(repeats):
        t = time.perf_counter()
        r = f()
        runs.append((time.perf_counter() - t, r["wall_time_s"], r))
    return min(runs, key=lambda w: w[0] - w[1])


cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
print(f"{frames} frames x {nodes} nodes, weights fixed, best of {repeats}; CPU {cpu}, {os.cpu_count()} cores")
results = {}
for name, f in (("temporary .npy (before)", through_a_file), ("in memory (now)", in_memory)):
    wall, engine, r = best(f)
    results[name] = r
    print(f"{name:24s} call {wall:.3f} s, engine clip {engine:.3f} s, outside the clip {1e3 * (wall - engine):.1f} ms "
          f"({100 * (wall - engine) / engine:.2f} %)")
a, b = results.values()
print("same bits:", all(np.array_equal(a[k], b[k]) for k in ("x_m", "angles_rad", "kappa_per_m", "f_n_per_m")))
