"""Each call has its own stop request: a call cancelled through its cosserat.Cancel stops and
raises Cancelled, while a call in another thread runs on to the same numbers as an undisturbed
run (with one process-wide flag, the cancel would have stopped both)."""
import threading

import numpy as np
import pytest

import cosserat

from conftest import ROOT


@pytest.fixture(scope="module")
def long_recording():
    (e,) = cosserat.synth(count=1, frames=100, nodes=65, noise_m=5e-7, seed=1,
                          kymogram=ROOT / "data/elegansbot/kymogram_omega-turn.npy")
    return e["positions_m"]


def test_a_cancelled_call_stops_and_another_thread_s_call_runs_on(long_recording, recording, reconstructed):
    cancel_a = cosserat.Cancel()
    a_running, seen_a, outcome = threading.Event(), [], {}

    def a():
        def progress(done, total):
            seen_a.append(done)
            a_running.set()
        try:
            outcome["a"] = cosserat.reconstruct(long_recording, frame_interval_s=0.04, progress=progress,
                                                cancel=cancel_a)
        except cosserat.Cancelled as e:
            outcome["a"] = e

    def b():
        # B cancels A while B itself is solving (after its own first frame)
        def progress(done, total):
            if done >= 1:
                cancel_a.set()
        outcome["b"] = cosserat.reconstruct(recording["positions_m"], frame_interval_s=0.04, progress=progress,
                                            cancel=cosserat.Cancel())

    ta = threading.Thread(target=a)
    ta.start()
    assert a_running.wait(60), "A never reported a frame"
    tb = threading.Thread(target=b)
    tb.start()
    tb.join()
    ta.join()
    assert isinstance(outcome["a"], cosserat.Cancelled), outcome["a"]
    assert cancel_a.is_set() and seen_a[-1] < 100
    b = outcome["b"]
    assert b["status"] == reconstructed["status"] and b["frames_done"] == 12
    for name in ("x_m", "angles_rad", "kappa_per_m", "f_n_per_m", "l_nm_per_m"):
        assert np.array_equal(b[name], reconstructed[name]), name


def test_a_call_given_a_set_cancel_does_not_start_and_others_are_unaffected(recording):
    done = cosserat.Cancel()
    done.set()
    with pytest.raises(cosserat.Cancelled):
        cosserat.reconstruct(recording["positions_m"][:3], frame_interval_s=0.04, cancel=done)
    with pytest.raises(cosserat.Cancelled):
        cosserat.run_case(ROOT / "cases" / "timoshenko_5pct.toml", cancel=done)
    # no flag of the process was set: the next call runs whole
    assert cosserat.reconstruct(recording["positions_m"][:3], frame_interval_s=0.04)["frames_done"] == 3
    assert "set=True" in repr(done) and not cosserat.Cancel().is_set()
