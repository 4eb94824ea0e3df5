"""What Ctrl-C does mid-clip: SIGINT 50 ms after frame 300 of a recording of worm_roll_3d's size
(1160 frames × 128 nodes); prints how long after the signal KeyboardInterrupt came.

    .venv/bin/python python/bench/ctrl_c.py
"""
import os
import signal
import threading
import time
from pathlib import Path

import cosserat

KYMOGRAM = Path(__file__).resolve().parents[2] / "data" / "elegansbot" / "kymogram_omega-turn.npy"
(rec,) = cosserat.synth(count=1, frames=1160, nodes=128, noise_m=1e-6, seed=5, kymogram=KYMOGRAM)
seen, sent = [], []


def interrupt():
    sent.append(time.perf_counter())
    os.kill(os.getpid(), signal.SIGINT)


def progress(done, total):
    seen.append((time.perf_counter(), done))
    if done >= 300 and not hasattr(progress, "timer"):
        progress.timer = threading.Timer(0.05, interrupt)
        progress.timer.start()


try:
    cosserat.reconstruct(rec["positions_m"], frame_interval_s=0.04, progress=progress)
    print("the clip ended before the signal")
except KeyboardInterrupt as e:
    t = time.perf_counter()
    per = (seen[-1][0] - seen[0][0]) / (seen[-1][1] - seen[0][1])
    print(
        f"KeyboardInterrupt {1e3 * (t - sent[0]):.1f} ms after SIGINT; last frame reported {seen[-1][1]} of 1160; "
        f"frame time {1e3 * per:.1f} ms; {e!r}"
    )
r = cosserat.reconstruct(rec["positions_m"][:5], frame_interval_s=0.04)
print(f"the next call: {r['frames_done']} frames, status {r['status']}")
