"""Type stubs of ctcal (see ``__init__.py``)."""

import os
from typing import Any, Dict, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

PathLike = Union[str, os.PathLike[str]]

__version__: str
EVENT_DTYPE: np.dtype[Any]
FIT_PIXELS: int
FIT_EVENTS: int

class CtcalError(ValueError): ...

def read(
    path: PathLike,
    *,
    start: Optional[float] = ...,
    end: Optional[float] = ...,
    format: Optional[str] = ...,
    sensor: Optional[str] = ...,
) -> npt.NDArray[np.void]: ...
def read_frames(
    path: PathLike, *, format: Optional[str] = ..., sensor: Optional[str] = ...
) -> Tuple[npt.NDArray[np.int64], npt.NDArray[np.uint8]]: ...
def info(
    path: PathLike, *, format: Optional[str] = ..., sensor: Optional[str] = ...
) -> Dict[str, Any]: ...
def stats(
    path_or_events: Union[PathLike, npt.NDArray[np.void]],
    sensor: Optional[str] = ...,
    *,
    start: Optional[float] = ...,
    end: Optional[float] = ...,
    window_s: float = ...,
    support_window_s: float = ...,
    format: Optional[str] = ...,
) -> Dict[str, Any]: ...
def estimate(
    path: PathLike,
    method: str = ...,
    *,
    start: Optional[float] = ...,
    end: Optional[float] = ...,
    max_frames: int = ...,
    max_pixels: int = ...,
    max_events: int = ...,
    seed: int = ...,
    roi: Optional[str] = ...,
    mask: Optional[PathLike] = ...,
    format: Optional[str] = ...,
    sensor: Optional[str] = ...,
    stimulus: Optional[PathLike] = ...,
) -> Dict[str, Any]: ...
def fit(
    path: PathLike,
    *,
    start: Optional[float] = ...,
    end: Optional[float] = ...,
    max_frames: int = ...,
    max_pixels: int = ...,
    max_events: int = ...,
    seed: int = ...,
    roi: Optional[str] = ...,
    mask: Optional[PathLike] = ...,
    format: Optional[str] = ...,
    sensor: Optional[str] = ...,
) -> Dict[str, Any]: ...
def simulate(
    frames: npt.ArrayLike,
    times_us: Sequence[int],
    params: Union[Mapping[str, Any], str, PathLike],
) -> npt.NDArray[np.void]: ...
def config(fit: Union[Mapping[str, Any], PathLike], format: str = ...) -> str: ...
def report(
    inputs: Union[PathLike, Sequence[PathLike]],
    out: PathLike,
    client: Any = ...,
    fit: bool = ...,
    *,
    datasets: Optional[Mapping[str, PathLike]] = ...,
    **opts: Any,
) -> Dict[str, Any]: ...
