"""cosserat.reconstruct: the numbers of a synthetic recording, its input forms and errors."""
import numpy as np
import pytest

import cosserat

FIELDS = ["x_m", "angles_rad", "d1", "d2", "d3", "f_n_per_m", "l_nm_per_m", "data_m", "omega_rad_per_s"]


def test_a_clean_recording_is_reconstructed_with_certified_frames(recording, reconstructed):
    r = reconstructed
    assert r["status"] == "ok", r["error"]
    assert (r["frames_done"], r["frames_total"]) == (12, 12)
    assert list(r["frame"]) == list(range(12))
    for name in FIELDS:
        assert r[name].shape == (12, 33, 3), name
        assert r[name].dtype == np.float64
    assert r["kappa_per_m"].shape == (12, 32, 3)
    # every frame certified (η ≤ 1e-10) and followed: positions within a few noise levels
    assert np.all(r["frames"]["certificate"] <= 1e-10)
    assert not r["frames"]["flagged"].any()
    assert np.max(np.abs(r["x_m"] - recording["positions_m"])) < 10 * 5e-7
    # the directors are orthonormal
    d1, d2, d3 = r["d1"], r["d2"], r["d3"]
    assert np.max(np.abs(np.einsum("fnk,fnk->fn", d1, d2))) < 1e-12
    assert np.max(np.abs(np.linalg.norm(d3, axis=2) - 1)) < 1e-12
    # the body length estimated from the data, the noise level and λg chosen on it
    assert abs(r["body_length_m"] - 1e-3) < 0.02e-3
    assert 0.3 * 5e-7 < r["noise_m"] < 3 * 5e-7
    assert r["weights"]["lambda_g"] == r["lambda_g"] <= 1e9
    assert r["metrics"]["frames"] == 12


def test_the_recovered_curvature_follows_the_truth(recording, reconstructed):
    """Bending (κ1² + κ2²)^½ at the inner element midpoints against the truth's at the nodes
    around them: within 15 % of its largest value."""
    k = reconstructed["kappa_per_m"]
    t = recording["kappa_per_m"]
    t_mid = 0.5 * (t[:, 1:] + t[:, :-1])
    bend = np.hypot(k[..., 0], k[..., 1])[:, 3:-3]
    bend_true = np.hypot(t_mid[..., 0], t_mid[..., 1])[:, 3:-3]
    assert np.max(np.abs(bend - bend_true)) < 0.15 * np.max(bend_true)


def test_fixed_weights_are_used_as_given(recording):
    r = cosserat.reconstruct(
        recording["positions_m"][:4], frame_interval_s=0.04, body_length_m=1e-3, weights={"lambda_g": 1e8}
    )
    assert r["status"] == "ok"
    assert r["weights"] is None and r["lambda_g"] == 1e8
    assert r["body_length_m"] == 1e-3
    # with λg = 1e8 instead of the chosen one the fit differs
    auto = cosserat.reconstruct(recording["positions_m"][:4], frame_interval_s=0.04, body_length_m=1e-3)
    assert not np.array_equal(r["x_m"], auto["x_m"])


def test_untracked_nodes_and_a_lost_frame_are_filled_and_flagged(recording):
    x = recording["positions_m"][:6].copy()
    x[2, 10:14] = np.nan  # four untracked nodes
    x[4] = np.nan  # a lost frame
    r = cosserat.reconstruct(x, frame_interval_s=0.04)
    f = r["frames"]
    assert r["frames_done"] == 6
    assert list(f["nodes_tracked"]) == [33, 33, 29, 33, 0, 33]
    assert list(f["filled"]) == [False, False, True, False, False, False]
    assert list(f["lost"]) == [False, False, False, False, True, False]
    assert np.all(np.isfinite(r["x_m"]))


def test_non_contiguous_read_only_and_float32_inputs(recording):
    x = recording["positions_m"][:3]
    base = cosserat.reconstruct(x, frame_interval_s=0.04)
    # non-contiguous: every second entry of a wider array; read-only
    wide = np.zeros((3, 33, 6))
    wide[..., ::2] = x
    view = wide[..., ::2]
    view.setflags(write=False)
    assert not view.flags.c_contiguous
    r = cosserat.reconstruct(view, frame_interval_s=0.04)
    assert np.array_equal(r["x_m"], base["x_m"])
    # float32 is converted exactly: the same as its float64 values
    x32 = x.astype(np.float32)
    r32 = cosserat.reconstruct(x32, frame_interval_s=0.04)
    r64 = cosserat.reconstruct(x32.astype(np.float64), frame_interval_s=0.04)
    assert np.array_equal(r32["x_m"], r64["x_m"])
    # a nested list is an array-like too
    rl = cosserat.reconstruct(x.tolist(), frame_interval_s=0.04)
    assert np.array_equal(rl["x_m"], base["x_m"])


@pytest.mark.parametrize("dtype", [np.complex128, object, np.longdouble])
def test_dtypes_that_do_not_convert_exactly_are_refused(recording, dtype):
    x = recording["positions_m"][:2].astype(dtype)
    if dtype is np.longdouble and np.finfo(np.longdouble).nmant <= 52:
        pytest.skip("long double is float64 on this platform")
    with pytest.raises(TypeError, match="cannot be converted to float64 without loss"):
        cosserat.reconstruct(x, frame_interval_s=0.04)


def test_bad_shapes_and_values_raise_value_error(recording):
    x = recording["positions_m"][:2]
    with pytest.raises(ValueError, match="expected frames × nodes × 3"):
        cosserat.reconstruct(x[0], frame_interval_s=0.04)
    with pytest.raises(ValueError, match="expected frames × nodes × 3"):
        cosserat.reconstruct(x[..., :1], frame_interval_s=0.04)
    # a body length the data does not have: the CLI's message, naming rod.length_m
    with pytest.raises(ValueError, match=r"rod\.length_m = 2e-3"):
        cosserat.reconstruct(x, frame_interval_s=0.04, body_length_m=2e-3)
    # a negative frame interval: the case's validation names the key
    with pytest.raises(ValueError, match="frame_interval_s"):
        cosserat.reconstruct(x, frame_interval_s=-0.04)
    with pytest.raises(ValueError, match="unknown key"):
        cosserat.reconstruct(x, frame_interval_s=0.04, weights={"lambda_q": 1})
    with pytest.raises(ValueError, match='expected "auto", "fixed"'):
        cosserat.reconstruct(x, frame_interval_s=0.04, weights="sometimes")


def test_progress_is_reported_and_its_exception_stops_the_solve(recording):
    seen = []
    cosserat.reconstruct(recording["positions_m"][:5], frame_interval_s=0.04, progress=lambda d, t: seen.append((d, t)))
    assert seen and seen[-1] == (5, 5)
    assert all(t == 5 for _, t in seen) and [d for d, _ in seen] == sorted(d for d, _ in seen)

    class Stop(Exception):
        pass

    def stop(done, total):
        raise Stop(f"at {done}")

    with pytest.raises(Stop):
        cosserat.reconstruct(recording["positions_m"], frame_interval_s=0.04, progress=stop)
    # the stop request is cleared: the next call runs whole
    r = cosserat.reconstruct(recording["positions_m"][:3], frame_interval_s=0.04)
    assert r["frames_done"] == 3


def test_the_recording_is_read_in_memory_and_checked_as_a_file_is(recording, reconstructed, monkeypatch):
    """No file is written for the engine: saving or a temporary folder would fail here."""
    def refuse(*args, **kwargs):
        raise AssertionError("reconstruct wrote a file")

    monkeypatch.setattr(np, "save", refuse)
    monkeypatch.setattr(cosserat.tempfile, "TemporaryDirectory", refuse)
    monkeypatch.setattr(cosserat.tempfile, "mkstemp", refuse)
    r = cosserat.reconstruct(recording["positions_m"], frame_interval_s=0.04)
    assert np.array_equal(r["x_m"], reconstructed["x_m"])
    # a position the file reader refuses is refused alike, naming the array, frame and node
    x = recording["positions_m"][:3].copy()
    x[1, 4, 2] = np.inf
    with pytest.raises(ValueError, match=r"positions_m.*frame 1.*node 4"):
        cosserat.reconstruct(x, frame_interval_s=0.04)
