"""cosserat.run_case (files, TOML text, overrides, errors), cosserat.synth, the GIL and Ctrl-C."""
import os
import signal
import threading
import time

import numpy as np
import pytest

import cosserat

from conftest import ROOT

INVERSE = ROOT / "cases" / "inverse_bend_twist_newton.toml"


def test_an_inverse_case_runs_with_its_metrics():
    r = cosserat.run_case(INVERSE, overrides={"rod.elements": 40})
    assert r["status"] == "ok", r["error"]
    assert r["engine"] == "rust" and r["case"] == "inverse_bend_twist_newton"
    assert r["x_m"].shape == (41, 3) and r["kappa_per_m"].shape == (40, 3) and r["f_n_per_m"].shape == (41, 3)
    m = r["metrics"]
    assert m["certificate"] <= 1e-10
    # the recovered centreline follows the data
    assert np.max(np.abs(r["x_m"] - r["data_m"])) < 1e-3 * 1e-3
    # an override changes the result: another tracking weight, another fit
    r2 = cosserat.run_case(INVERSE, overrides={"rod.elements": 40, "inverse.lambda_g": 1e7})
    assert not np.array_equal(r["x_m"], r2["x_m"])


def test_a_forward_case_from_toml_text():
    text = (ROOT / "cases" / "timoshenko_5pct.toml").read_text()
    r = cosserat.run_case(text, overrides={"rod.elements": 20})
    assert r["status"] == "ok"
    assert r["x_m"].shape == (21, 3) and "f_n_per_m" not in r
    # the tip deflection against the elastica's: within 0.1 % on 20 elements
    assert abs(r["metrics"]["elastica_rel_error"]) < 1e-3
    assert r["x_m"][-1, 1] == r["metrics"]["tip_y_m"] < 0


def test_the_freefem_engine_gives_the_rust_engine_s_tip():
    case = ROOT / "cases" / "timoshenko_5pct.toml"
    rust = cosserat.run_case(case, overrides={"rod.elements": 20})
    ff = cosserat.run_case(case, overrides={"rod.elements": 20}, engine="freefem")
    assert ff["engine"] == "freefem" and ff["status"] == "ok"
    assert abs(ff["metrics"]["tip_y_m"] / rust["metrics"]["tip_y_m"] - 1) < 1e-9
    assert not np.array_equal(ff["x_m"], rust["x_m"])  # two engines, not one result twice


def test_bad_cases_raise_with_the_cli_message(tmp_path):
    with pytest.raises(ValueError, match="inverse.lambda_g"):
        cosserat.run_case(INVERSE, overrides={"inverse.lambda_g": -1.0})
    with pytest.raises(ValueError, match="rod"):
        cosserat.run_case(INVERSE, overrides={"rod.elements": "many"})
    with pytest.raises(ValueError):
        cosserat.run_case("[rod]\nlength_m = \n")
    with pytest.raises(FileNotFoundError, match="nowhere.toml"):
        cosserat.run_case(tmp_path / "nowhere.toml")
    with pytest.raises(ValueError, match="engine `abacus`"):
        cosserat.run_case(INVERSE, engine="abacus")
    with pytest.raises(TypeError, match="override `rod.elements`"):
        cosserat.run_case(INVERSE, overrides={"rod.elements": {1: 2}})


def test_a_clip_case_runs_as_reconstruct(tmp_path, recording):
    x = recording["positions_m"][:4]
    np.save(tmp_path / "w.npy", x)
    text = cosserat.recording_case(nodes=33, frame_interval_s=0.04, file=str(tmp_path / "w.npy"))
    r = cosserat.run_case(text, overrides={"clip.frames": [1, 4]})
    assert list(r["frame"]) == [1, 2, 3]
    whole = cosserat.run_case(text)
    assert np.array_equal(whole["x_m"], cosserat.reconstruct(x, frame_interval_s=0.04)["x_m"])
    with pytest.raises(ValueError, match="clip"):
        cosserat.run_case(text, engine="freefem")


def test_synth_is_deterministic_and_its_truth_is_orthonormal():
    a = cosserat.synth(count=2, frames=5, nodes=17, seed=7, kymogram=ROOT / "data/elegansbot/kymogram_omega-turn.npy")
    b = cosserat.synth(count=2, frames=5, nodes=17, seed=7, kymogram=ROOT / "data/elegansbot/kymogram_omega-turn.npy")
    assert [e["name"] for e in a] == ["roll_000", "roll_001"]
    assert a[0]["positions_m"].shape == (5, 17, 3) and a[0]["d3"].shape == (5, 17, 3)
    assert np.array_equal(a[1]["positions_m"], b[1]["positions_m"])
    assert not np.array_equal(a[0]["positions_m"], a[1]["positions_m"])
    d1, d3 = a[0]["d1"], a[0]["d3"]
    assert np.max(np.abs(np.einsum("fnk,fnk->fn", d1, d3))) < 1e-12
    with pytest.raises(ValueError, match="kymogram"):
        cosserat.synth(kymogram="/nonexistent/kymogram.npy")


@pytest.fixture(scope="module")
def long_recording():
    (e,) = cosserat.synth(count=1, frames=150, nodes=65, noise_m=5e-7, seed=1,
                          kymogram=ROOT / "data/elegansbot/kymogram_omega-turn.npy")
    return e["positions_m"]


def test_the_gil_is_released_during_a_solve(long_recording):
    """While another thread reconstructs, this one keeps running Python."""
    done = threading.Event()
    t = threading.Thread(target=lambda: (cosserat.reconstruct(long_recording[:40], frame_interval_s=0.04), done.set()))
    t.start()
    spins, start = 0, time.perf_counter()
    while not done.is_set():
        spins += 1
    elapsed = time.perf_counter() - start
    t.join()
    assert elapsed > 0.05, "the solve was too short to tell"
    # with the GIL held by the solve this thread would get ~one switch interval per 5 ms
    assert spins / elapsed > 1e5


def test_ctrl_c_raises_keyboard_interrupt_within_a_frame(long_recording):
    """SIGINT (what Ctrl-C sends) 50 ms after frame 5 was reported, while the clip is solved."""
    seen, sent = [], []

    def interrupt():
        sent.append(time.perf_counter())
        os.kill(os.getpid(), signal.SIGINT)

    def progress(done, total):
        seen.append((time.perf_counter(), done))
        if done >= 5 and not sent and not hasattr(progress, "timer"):
            progress.timer = threading.Timer(0.05, interrupt)
            progress.timer.start()

    with pytest.raises(KeyboardInterrupt):
        cosserat.reconstruct(long_recording, frame_interval_s=0.04, progress=progress)
    stopped = time.perf_counter()
    progress.timer.join()
    assert sent, "the clip ended before the signal"
    frames = [d for _, d in seen]
    per_frame = (seen[-1][0] - seen[0][0]) / max(frames[-1] - frames[0], 1)
    # seen within a tick (20 ms), the solve stopped within its frame
    assert stopped - sent[0] < 0.1 + 2 * per_frame, (stopped - sent[0], per_frame)
    assert frames[-1] < 150
    # the stop request is cleared: the next call runs whole
    assert cosserat.reconstruct(long_recording[:3], frame_interval_s=0.04)["frames_done"] == 3
