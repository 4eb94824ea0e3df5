"""Type stubs of the `cosserat` package (see its module docstring)."""
import os
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str
DEFAULT_KYMOGRAM: str

Progress = Callable[[int, int], Any]

class Cancel:
    """A stop request for the calls it is passed to (``cancel=``); ``set()`` from any thread."""
    def __init__(self) -> None: ...
    def set(self) -> None: ...
    def is_set(self) -> bool: ...

class Cancelled(Exception):
    """A call stopped by its :class:`Cancel`."""
Overrides = Union[Mapping[str, Any], Sequence[Tuple[str, Any]], None]

def recording_case(
    *,
    nodes: int,
    frame_interval_s: float,
    file: str,
    body_length_m: Optional[float] = ...,
    weights: Union[str, Mapping[str, Any]] = ...,
    noise_m: Optional[float] = ...,
    name: str = ...,
) -> str: ...
def reconstruct(
    positions_m: npt.ArrayLike,
    *,
    frame_interval_s: float,
    body_length_m: Optional[float] = ...,
    weights: Union[str, Mapping[str, Any]] = ...,
    noise_m: Optional[float] = ...,
    progress: Optional[Progress] = ...,
    cancel: Optional[Cancel] = ...,
) -> Dict[str, Any]: ...
def run_case(
    case: Union[str, os.PathLike[str]],
    *,
    overrides: Overrides = ...,
    engine: str = ...,
    progress: Optional[Progress] = ...,
    cancel: Optional[Cancel] = ...,
    out: Union[str, os.PathLike[str], None] = ...,
    force: bool = ...,
    output_format: str = ...,
) -> Dict[str, Any]: ...
def compare(
    case: Union[str, os.PathLike[str]],
    *,
    overrides: Overrides = ...,
    short: bool = ...,
    frames: Union[int, str, None] = ...,
    cancel: Optional[Cancel] = ...,
) -> List[Dict[str, Any]]: ...
def synth(
    *,
    count: int = ...,
    frames: int = ...,
    nodes: int = ...,
    length_m: float = ...,
    frame_interval_s: float = ...,
    noise_m: float = ...,
    seed: int = ...,
    max_roll_rad: float = ...,
    max_twist_per_m: float = ...,
    kymogram: Union[str, os.PathLike[str]] = ...,
) -> List[Dict[str, Any]]: ...
def read_compact(path: Union[str, os.PathLike[str]]) -> Dict[str, np.ndarray]: ...
