"""What the Python call costs against the solve, and two threads with the GIL released.

    .venv/bin/python python/bench/bench_python.py [FRAMES] [NODES]

On a synthetic 3D recording (`cosserat.synth`, 1 µm noise, a 1 mm worm rolling and twisting)
of FRAMES × NODES (default 1160 × 128, worm_roll_3d's size), `weights="auto"`:
1. `cosserat.reconstruct` (wall time of the call) against the engine's own clip time
   (`wall_time_s`, the solve of the frames) and against `cosserat run` of the same recording and
   case (target/release/cosserat, compact output), each the best of 2;
2. two threads reconstructing two recordings of FRAMES/4 frames at once against one after the
   other.
"""
import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

import cosserat

ROOT = Path(__file__).resolve().parents[2]
frames = int(sys.argv[1]) if len(sys.argv) > 1 else 1160
nodes = int(sys.argv[2]) if len(sys.argv) > 2 else 128
kym = ROOT / "data" / "elegansbot" / "kymogram_omega-turn.npy"
recs = cosserat.synth(count=2, frames=frames, nodes=nodes, noise_m=1e-6, seed=5, kymogram=kym)
x = recs[0]["positions_m"]


def timed(f):
    t = time.perf_counter()
    out = f()
    return time.perf_counter() - t, out


py = []
for _ in range(2):
    wall, r = timed(lambda: cosserat.reconstruct(x, frame_interval_s=0.04))
    py.append((wall, r["wall_time_s"]))
    assert r["status"] in ("ok", "warnings"), r["error"]
wall, engine = min(py)
print(f"recording {frames} frames x {nodes} nodes: status {r['status']}, noise {r['noise_m']:.3g} m, lambda_g {r['lambda_g']:.3g}")
print(f"python reconstruct: {wall:.3f} s; engine clip time {engine:.3f} s; outside the clip solve {wall - engine:.3f} s ({100 * (wall - engine) / engine:.1f} %)")
# fixed weights: no calibration before the clip, so the difference is the call's own cost
fixed = []
for _ in range(2):
    w, rf = timed(lambda: cosserat.reconstruct(x, frame_interval_s=0.04, weights={"lambda_g": r["lambda_g"]}))
    fixed.append((w, rf["wall_time_s"]))
w, e = min(fixed)
print(f"fixed weights: python reconstruct {w:.3f} s; engine clip time {e:.3f} s; outside the clip solve {w - e:.3f} s ({100 * (w - e) / e:.1f} %)")

# what the engine does before the first frame (reading the recording, its body length and
# length checks, as `cosserat run` does) and the call's own work (the .npy it hands over)
with tempfile.TemporaryDirectory() as tmp:
    save, _ = timed(lambda: np.save(f"{tmp}/rec.npy", x))
    text = cosserat.recording_case(nodes=nodes, frame_interval_s=0.04, file=f"{tmp}/rec.npy", weights="fixed")
    first = min(timed(lambda: cosserat.run_case(text, overrides={"clip.frames": [0, 1]}))[0] for _ in range(3))
print(f"np.save of the recording {save * 1e3:.1f} ms; the first frame alone (weights fixed, every frame read) {first:.3f} s")

binary = os.environ.get("COSSERAT_BIN", str(ROOT / "target" / "release" / "cosserat"))
with tempfile.TemporaryDirectory() as tmp:
    np.save(f"{tmp}/rec.npy", x)
    Path(f"{tmp}/rec.toml").write_text(cosserat.recording_case(nodes=nodes, frame_interval_s=0.04, file=f"{tmp}/rec.npy"))
    cli = []
    for k in range(2):
        cmd = [binary, "run", f"{tmp}/rec.toml", "--out", f"{tmp}/out{k}", "--output-format", "compact", "--quiet"]
        t, p = timed(lambda: subprocess.run(cmd, capture_output=True))
        assert p.returncode in (0, 1), p.stderr
        cli.append(t)
    same = np.array_equal(cosserat.read_compact(f"{tmp}/out0")["x_m"], r["x_m"][..., 0])
print(f"cosserat run (compact output): {min(cli):.3f} s; python / cli = {wall / min(cli):.3f}; x bit-identical: {same}")

quarter = [rc["positions_m"][: frames // 4] for rc in recs]


def one(q):
    return cosserat.reconstruct(q, frame_interval_s=0.04)


def both():
    threads = [threading.Thread(target=one, args=(q,)) for q in quarter]
    for t in threads:
        t.start()
    for t in threads:
        t.join()


serial, parallel = [], []
for _ in range(3):
    parallel.append(timed(both)[0])
    serial.append(timed(lambda: [one(q) for q in quarter])[0])
print(
    f"two recordings of {frames // 4} frames (best of 3): one after the other {min(serial):.3f} s, two threads "
    f"{min(parallel):.3f} s, speed-up {min(serial) / min(parallel):.2f}x on {os.cpu_count()} cores"
)
