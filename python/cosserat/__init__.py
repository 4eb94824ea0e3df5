"""Cosserat rod inverse reconstruction of worm centrelines, from Python.

The Rust engine of the ``cosserat`` command-line tool behind numpy arrays:

- :func:`reconstruct` a recording held in memory (frames × nodes × 3 positions [m], NaN for
  untracked nodes): per-frame positions, directors, curvature, controls, certificates, fit
  measures and flags, and the chosen noise level and tracking weight;
- :func:`run_case` a case file or TOML text (with overrides of its keys) in either engine,
  optionally into an output folder (``out=``) exactly as ``cosserat run --out`` writes it;
- :func:`compare` a case in both engines (Rust and FreeFEM) as ``cosserat compare`` does: the
  rows of its ``compare.csv`` as records;
- :func:`synth` synthetic 3D recordings with their ground truth;
- :func:`recording_case` the case file :func:`reconstruct` runs (to run it with the CLI);
- :func:`read_compact` a clip's ``fields.npz`` as the CLI writes it.

Every solve runs with the GIL released and has its own stop request. Ctrl-C (which Python
delivers to the main thread) stops the call running in the main thread within an iteration and
raises ``KeyboardInterrupt`` there; calls in other threads run on. To stop a call in any thread,
pass it a :class:`Cancel` (``cancel=``) and call ``Cancel.set()`` from elsewhere: the call stops
at its next check and raises :class:`Cancelled`. A bad case or recording raises ``ValueError``
with the CLI's message.
"""
from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Any, Callable, Dict, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _native
from ._native import Cancel, Cancelled

__version__ = _native.__version__

__all__ = [
    "reconstruct",
    "recording_case",
    "run_case",
    "compare",
    "Cancel",
    "Cancelled",
    "synth",
    "read_compact",
    "DEFAULT_KYMOGRAM",
]

#: The omega-turn kymogram `scripts/fetch_worm_data.sh` fetches (relative to the repository).
DEFAULT_KYMOGRAM = os.path.join("data", "elegansbot", "kymogram_omega-turn.npy")

Progress = Callable[[int, int], Any]
Overrides = Union[Mapping[str, Any], Sequence[Tuple[str, Any]], None]

# The weights of `[inverse]` that `weights={...}` may set.
_WEIGHT_KEYS = (
    "lambda_g",
    "lambda_f",
    "lambda_l",
    "lambda_d",
    "lambda_kappa",
    "lambda_omega",
    "stabilisation",
)

# Table 1 of Wang et al. (2023) with lambda_d = 1 and the time coupling of noisy recordings
# (cases/batch/roll_recording.toml).
_DEFAULT_WEIGHTS = {
    "lambda_g": 1e9,
    "lambda_f": 1e-3,
    "lambda_l": 1e-6,
    "lambda_d": 1,
    "lambda_kappa": [0, 0, 0],
    "lambda_omega": [1e-7, 1e-7, 1e-5],
    "stabilisation": 1e-3,
}


def _toml_value(v: Any) -> str:
    """A Python value as TOML text (floats shortest round-trip: the same bits back)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        f = float(v)
        if not np.isfinite(f):
            raise ValueError(f"{v!r} is not a finite number")
        return repr(f)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(f"a value of type {type(v).__name__}; expected bool, int, float, str or a list")


def recording_case(
    *,
    nodes: int,
    frame_interval_s: float,
    file: str,
    body_length_m: Optional[float] = None,
    weights: Union[str, Mapping[str, Any]] = "auto",
    noise_m: Optional[float] = None,
    name: str = "recording",
) -> str:
    """The case file (TOML text) :func:`reconstruct` runs on a recording.

    ``cosserat run`` on this text, with ``file`` the recording saved as ``.npy``
    (frames × nodes × 3 [m], NaN untracked), gives the same numbers as :func:`reconstruct`.
    The rod is a worm of circular section, 20 µm radius per mm of body length, E = 110 kPa,
    Poisson 0.4; Newton warm-started from the previous frame, rebased angle chart, and
    ``weights="auto"``: the tracking weight chosen from the recording's noise (docs/noise.md).

    Parameters
    ----------
    nodes: nodes per frame (the mesh has ``nodes - 1`` elements).
    frame_interval_s: time between frames [s].
    file: the recording (``.npy`` or any format ``cosserat run`` reads).
    body_length_m: body length [m]; ``None`` estimates it from the recording.
    weights: ``"auto"`` (λg from the noise, the given λg the largest allowed), ``"fixed"``
        (the default weights as given) or a dict of ``lambda_g``, ``lambda_f``, ``lambda_l``,
        ``lambda_d``, ``lambda_kappa``, ``lambda_omega``, ``stabilisation`` (fixed unless it
        holds ``"rule": "auto"``).
    noise_m: the tracking noise per coordinate [m] if known (else estimated).
    """
    if int(nodes) < 2:
        raise ValueError(f"nodes = {nodes}: a rod needs at least 2 nodes")
    w = dict(_DEFAULT_WEIGHTS)
    if isinstance(weights, str):
        if weights not in ("auto", "fixed"):
            raise ValueError(f'weights = {weights!r}: expected "auto", "fixed" or a dict of lambda_* values')
        rule = weights
    else:
        given = dict(weights)
        rule = given.pop("rule", "fixed")
        unknown = sorted(set(given) - set(_WEIGHT_KEYS))
        if unknown:
            raise ValueError(f"weights: unknown key(s) {', '.join(unknown)}; known: {', '.join(_WEIGHT_KEYS)}")
        w.update(given)
    if body_length_m is None:
        rod = 'length_m = "from_data"\nsection_length_m = 1e-3'
    else:
        rod = f"length_m = {_toml_value(float(body_length_m))}\nsection_length_m = 1e-3"
    noise = "" if noise_m is None else f"noise_m = {_toml_value(float(noise_m))}\n"
    inverse = "\n".join(f"{k} = {_toml_value(v)}" for k, v in w.items())
    return f"""description = {json.dumps(name + ": a recording reconstructed through the Python package")}

[rod]
{rod}
elements = {int(nodes) - 1}

[material]
young_modulus_pa = 1.1e5
shear_modulus_pa = "1.1e5/(2*(1 + 0.4))"
shear_correction = "4/3"

[cross_section]
shape = "circle"
radius_m = 2e-5

[clip]
kind = "recording"
file = {json.dumps(str(file))}
frame_interval_s = {_toml_value(float(frame_interval_s))}
min_cos_beta = 1e-2
start = "previous_frame"
rotation = "rebased"
missing = "nan"
{noise}
[inverse]
weights = {json.dumps(rule)}
{inverse}

[solver]
analysis = "inverse"
method = "newton"
relaxation = 0.5
warm_start_tolerance = 1e-2
tolerance = 1e-9
max_iterations = 300
"""


def _as_positions(positions_m: Any) -> np.ndarray:
    """The recording as a C-contiguous float64 array frames × nodes × 3 (or × 2).

    Any array-like is accepted (non-contiguous, read-only, a list); float16/float32 and
    integer values are converted to float64 where that is exact; other dtypes are refused.
    """
    a = np.asarray(positions_m)
    if a.dtype != np.float64:
        kind = a.dtype.kind
        if kind == "f" and a.dtype.itemsize < 8:
            a = a.astype(np.float64)  # exact: every float16/float32 is a float64
        elif kind in "iu" and (a.size == 0 or int(np.abs(a.astype(object)).max()) <= 2**53):
            a = a.astype(np.float64)  # exact: integers up to 2**53
        else:
            raise TypeError(
                f"positions_m: dtype {a.dtype} cannot be converted to float64 without loss; "
                "pass float64 positions in metres"
            )
    if a.ndim != 3 or a.shape[2] not in (2, 3):
        raise ValueError(f"positions_m: shape {a.shape}; expected frames × nodes × 3 (or × 2 for a planar recording)")
    if a.shape[0] < 1 or a.shape[1] < 2:
        raise ValueError(f"positions_m: shape {a.shape}; at least 1 frame of 2 nodes")
    return np.ascontiguousarray(a)


def _overrides(overrides: Overrides) -> list:
    if overrides is None:
        return []
    items = overrides.items() if isinstance(overrides, Mapping) else overrides
    out = []
    for item in items:
        key, value = item
        if not isinstance(key, str):
            raise TypeError(f"override key {key!r}: expected a dotted key of the case file such as 'inverse.lambda_g'")
        out.append((key, value))
    return out


def _add_weights(result: Dict[str, Any], lambda_g: Optional[float], noise_m: Optional[float]) -> Dict[str, Any]:
    chosen = result.get("weights")
    result["noise_m"] = chosen["noise_m"] if chosen else noise_m
    result["lambda_g"] = chosen["lambda_g"] if chosen else lambda_g
    return result


def reconstruct(
    positions_m: Any,
    *,
    frame_interval_s: float,
    body_length_m: Optional[float] = None,
    weights: Union[str, Mapping[str, Any]] = "auto",
    noise_m: Optional[float] = None,
    progress: Optional[Progress] = None,
    cancel: Optional[Cancel] = None,
) -> Dict[str, Any]:
    """Reconstruct a recording held in memory, frame by frame (the inverse problem of Wang et
    al. 2023 on each frame, warm-started from the previous one).

    The engine reads the array where it is (no file is written): each position checked, NaN
    nodes and frames filled, exactly as ``cosserat run`` reads the same array saved as ``.npy``
    with the case :func:`recording_case` writes, and the numbers are the same to the last bit.

    Parameters
    ----------
    positions_m: frames × nodes × 3 positions [m] (× 2: a planar recording at z = 0); NaN marks
        an untracked node, a frame of NaN a lost frame. Any array-like: non-contiguous and
        read-only arrays are fine; float32/float16/integer values are converted exactly.
    frame_interval_s: time between frames [s].
    body_length_m: body length [m]; ``None`` estimates it from the recording.
    weights: ``"auto"``, ``"fixed"`` or a dict of weights (see :func:`recording_case`).
    noise_m: tracking noise per coordinate [m] if known.
    progress: called as ``progress(frames_done, frames_total)`` on the calling thread.
    cancel: a :class:`Cancel`; its ``set()`` (from any thread) stops this call, which then
        raises :class:`Cancelled`.

    Returns
    -------
    A dict: ``status`` (``"ok"``, ``"warnings"``: frames over the fit gate, ``"failed"``: a
    frame failed, the frames before it are returned), ``error``, ``frames_done``,
    ``frames_total``, ``body_length_m``, ``noise_m`` and ``lambda_g`` (the chosen ones with
    ``"auto"``), ``weights`` (everything ``"auto"`` chose, or None), ``metrics`` (the clip's
    metrics.json), ``frame``, ``s_m`` (nodes), ``s_mid_m`` (elements); per frame × node × 3:
    ``x_m``, ``angles_rad``, ``d1``, ``d2``, ``d3``, ``f_n_per_m``, ``l_nm_per_m``, ``data_m``,
    ``omega_rad_per_s``; per frame × element × 3: ``kappa_per_m``, ``n_n``, ``m_nm``,
    ``n_local_n``, ``m_local_nm``; ``frames``: the columns of the CLI's frames.csv (certificate,
    fit measures, flags, …) as arrays.

    Raises
    ------
    ValueError: a recording the case cannot take (its message is the CLI's).
    TypeError: positions of a dtype that does not convert exactly to float64.
    KeyboardInterrupt: Ctrl-C during the solve, in the main thread (it stops within a frame).
    Cancelled: ``cancel.set()`` was called.
    """
    a = _as_positions(positions_m)
    text = recording_case(
        nodes=a.shape[1],
        frame_interval_s=frame_interval_s,
        file="positions_m",  # names the array in messages; nothing is read from it
        body_length_m=body_length_m,
        weights=weights,
        noise_m=noise_m,
    )
    case_path = os.path.join(os.getcwd(), "recording.toml")
    result = _native.run_recording(text, case_path, a, progress, cancel)
    lambda_g = dict(weights).get("lambda_g", _DEFAULT_WEIGHTS["lambda_g"]) if not isinstance(weights, str) else 1e9
    return _add_weights(result, lambda_g, noise_m)


def _case_source(case: Union[str, os.PathLike]) -> Tuple[Optional[str], str]:
    """(text, path) of a case given as a file or as TOML text."""
    if isinstance(case, os.PathLike) or (isinstance(case, str) and "\n" not in case and case.endswith(".toml")):
        return None, os.fspath(case)
    if not isinstance(case, str):
        raise TypeError(f"case: {type(case).__name__}; expected a path or TOML text")
    return case, os.path.join(os.getcwd(), "case.toml")


def run_case(
    case: Union[str, os.PathLike],
    *,
    overrides: Overrides = None,
    engine: str = "rust",
    progress: Optional[Progress] = None,
    cancel: Optional[Cancel] = None,
    out: Union[str, os.PathLike, None] = None,
    force: bool = False,
    output_format: str = "csv",
) -> Dict[str, Any]:
    """Run a case (a ``.toml`` path or TOML text) as ``cosserat run`` does.

    Parameters
    ----------
    case: a case file's path (``str`` ending in ``.toml`` or a ``Path``) or TOML text (whose
        relative clip file is resolved against the working directory).
    overrides: keys of the case file set before it is validated, dotted
        (``{"inverse.lambda_g": 1e8, "clip.frames": [0, 20], "solver.method": "fixed_point"}``).
    engine: ``"rust"`` or ``"freefem"`` (needs ``FreeFem++``; clips run in Rust only).
    progress: called as ``progress(done, total)`` on the calling thread.
    cancel: a :class:`Cancel`; its ``set()`` (from any thread) stops this call, which then
        raises :class:`Cancelled`.
    out: an output folder: written as ``cosserat run CASE --out OUT`` writes it (the same files,
        byte for byte but for times and the process in ``run.json``; written in a staging
        folder beside it under the folder's lock and put in place at the end, with ``run.json``
        saying how the run ended), and the result is returned as well. ``None``: nothing is
        written.
    force: with ``out``, replace a folder that holds files but no ``run.json`` (``--force``;
        the folder of an earlier run is replaced without it).
    output_format: with ``out``, a clip's per-node fields as ``"csv"`` or ``"compact"``
        (``fields.npz``, ``--output-format``).

    Returns
    -------
    A clip case: as :func:`reconstruct`. Otherwise a dict: ``status`` (``"ok"``,
    ``"not_converged"``, ``"stalled"``: the last iterate is returned; with ``out`` also
    ``"warnings"``: an unstable static state, as run.json says), ``error``, ``case``,
    ``engine``, ``metrics`` (metrics.json), per node ``s_m``, ``x_m``, ``angles_rad``, ``d1``,
    ``d2``, ``d3`` (and for an inverse case ``f_n_per_m``, ``l_nm_per_m``, ``data_m``), per
    element ``s_mid_m``, ``kappa_per_m``. With ``out``: also ``out``, the folder.

    Raises
    ------
    ValueError: a bad case or override (the message names the key), an unknown engine.
    FileNotFoundError: a missing case or clip file.
    OSError: ``out`` cannot be written (a folder of other files without ``force``, another
        process writing it).
    RuntimeError: the engine failed (e.g. FreeFEM missing); with ``out`` the folder's
        run.json says failed.
    KeyboardInterrupt: Ctrl-C during the solve, in the main thread.
    Cancelled: ``cancel.set()`` was called.
    """
    text, path = _case_source(case)
    folder = None if out is None else os.fspath(out)
    settings = {
        "engine": engine,
        "progress": progress,
        "cancel": cancel,
        "out": folder,
        "force": bool(force),
        "output_format": output_format,
    }
    result = _native.run_case(text, path, _overrides(overrides), settings)
    if "frames" in result:
        _add_weights(result, None, None)
    return result


def compare(
    case: Union[str, os.PathLike],
    *,
    overrides: Overrides = None,
    short: bool = False,
    frames: Union[int, str, None] = None,
    cancel: Optional[Cancel] = None,
) -> list:
    """Run a case in both engines (Rust and FreeFEM) and compare them, as ``cosserat compare``
    does: the Rust engine twice (as given, and with its input perturbed by 1e-13 to measure the
    case's conditioning, from which each tolerance is derived), then FreeFEM (``FreeFem++``, in
    a temporary folder removed afterwards). Nothing else is written.

    Parameters
    ----------
    case, overrides: as :func:`run_case`.
    short: the short horizon (``--short``): 200 time steps, 40 fixed-point iterations, 3 frames.
    frames: a clip's frames to compare (``--frames``): a count, ``"all"``, or ``None`` for the
        case's ``[compare] frames``.
    cancel: a :class:`Cancel`; its ``set()`` stops the call (FreeFEM is killed).

    Returns
    -------
    The rows of ``compare.csv``, one dict per compared quantity with its columns:
    ``quantity``, ``rust`` and ``freefem`` (floats; ``None`` for a row that compares whole
    fields), ``difference``, ``tolerance`` (floats), ``result`` (``"pass"`` or ``"FAIL"``) and
    ``basis`` (how the tolerance was found).

    Raises
    ------
    ValueError: a bad case or override; a case whose published values cannot be computed.
    RuntimeError: an engine failed (e.g. FreeFEM missing or its script failed).
    KeyboardInterrupt: Ctrl-C, in the main thread. Cancelled: ``cancel.set()`` was called.
    """
    if frames == "all":
        frames = 2**64 - 1  # usize::MAX: every frame of the clip (`--frames all`)
    elif frames is not None:
        frames = int(frames)
        if frames < 1:
            raise ValueError(f"frames = {frames}: at least 1 frame (or \"all\")")
    text, path = _case_source(case)
    settings = {"short": bool(short), "frames": frames, "cancel": cancel}
    return _native.compare(text, path, _overrides(overrides), settings)


def synth(
    *,
    count: int = 1,
    frames: int = 20,
    nodes: int = 33,
    length_m: float = 1e-3,
    frame_interval_s: float = 0.04,
    noise_m: float = 1e-7,
    seed: int = 0,
    max_roll_rad: float = float(np.pi / 2),
    max_twist_per_m: float = 500.0,
    kymogram: Union[str, os.PathLike] = DEFAULT_KYMOGRAM,
) -> list:
    """Synthetic 3D recordings with their ground truth, as ``cosserat synth`` writes them.

    Each is a rolling, twisting worm playing an excerpt of the kymogram (the omega turn), with
    Gaussian noise of ``noise_m`` per coordinate; everything follows from ``seed``.

    Returns
    -------
    A list of dicts: ``name``, ``roll_total_rad``, ``twist_per_m``, ``first_row``,
    ``noise_seed``, ``positions_m`` (frames × nodes × 3 [m]), and the truth per frame × node:
    ``d1``, ``d2``, ``d3`` (× 3), ``kappa_per_m`` (local curvature, × 3), ``roll_rad`` (per frame).
    """
    out = []
    with tempfile.TemporaryDirectory(prefix="cosserat-synth-") as tmp:
        settings = {
            "count": int(count),
            "frames": int(frames),
            "nodes": int(nodes),
            "length_m": float(length_m),
            "frame_interval_s": float(frame_interval_s),
            "noise_m": float(noise_m),
            "seed": int(seed),
            "max_roll_rad": float(max_roll_rad),
            "max_twist_per_m": float(max_twist_per_m),
        }
        entries = _native.write_corpus(tmp, os.fspath(kymogram), settings)
        for e in entries:
            x = np.load(os.path.join(tmp, e["name"] + ".npy"))
            t = np.load(os.path.join(tmp, e["name"] + ".truth.npy"))
            e.update(
                positions_m=x,
                d1=t[..., 0:3].copy(),
                d2=t[..., 3:6].copy(),
                d3=t[..., 6:9].copy(),
                kappa_per_m=t[..., 9:12].copy(),
                roll_rad=t[:, 0, 12].copy(),
            )
            out.append(e)
    return out


def read_compact(path: Union[str, os.PathLike]) -> Dict[str, np.ndarray]:
    """A clip's ``fields.npz`` (``cosserat run --output-format compact``) as arrays: ``frame``
    and every column of fields.csv and curvature.csv as frames × values, at full precision."""
    p = Path(path)
    if p.is_dir():
        p = p / "fields.npz"
    return _native.read_compact(os.fspath(p))
