"""Shared fixtures: a small synthetic recording (the omega-turn kymogram of
scripts/fetch_worm_data.sh) and the repository's paths."""
import os
from pathlib import Path

import numpy as np
import pytest

import cosserat

ROOT = Path(__file__).resolve().parents[2]
KYMOGRAM = ROOT / "data" / "elegansbot" / "kymogram_omega-turn.npy"


@pytest.fixture(scope="session")
def recording():
    """One synthetic 3D recording: 12 frames × 33 nodes of a 1 mm worm, 0.5 µm noise."""
    assert KYMOGRAM.is_file(), f"{KYMOGRAM} is missing: run scripts/fetch_worm_data.sh"
    (entry,) = cosserat.synth(count=1, frames=12, nodes=33, noise_m=5e-7, seed=3, kymogram=KYMOGRAM)
    return entry


@pytest.fixture(scope="session")
def reconstructed(recording):
    return cosserat.reconstruct(recording["positions_m"], frame_interval_s=0.04)


def cli_binary() -> Path:
    """The `cosserat` binary: $COSSERAT_BIN, else the one `cargo test` or `cargo build` made."""
    env = os.environ.get("COSSERAT_BIN")
    candidates = [Path(env)] if env else [ROOT / "target" / "debug" / "cosserat", ROOT / "target" / "release" / "cosserat"]
    for c in candidates:
        if c.is_file():
            return c
    raise AssertionError(f"no cosserat binary among {candidates}: run `cargo build` (or set COSSERAT_BIN)")
