"""ctcal from Python: event-camera readers, statistics, threshold estimates, the fit and
reports, as the ``ctcal`` command computes them.

Every function calls the Rust library (``ctcal._ctcal``) with the GIL released. Results are
plain dicts with the JSON keys of ``ctcal ... --json`` (``../shared/CLI.md``); a value the
data do not determine is ``None`` with the reason under ``why``. Errors raise
:class:`CtcalError` (a ``ValueError``) carrying the message the command prints.

``report(inputs, out, client=...)`` with a ``dask.distributed.Client`` runs one task per
recording on the cluster's workers; the results are merged into one report by the same
library code as ``ctcal report``.
"""

from __future__ import annotations

import json
import os
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _ctcal
from ._ctcal import CtcalError

__all__ = [
    "CtcalError",
    "EVENT_DTYPE",
    "FIT_PIXELS",
    "FIT_EVENTS",
    "read",
    "read_frames",
    "info",
    "stats",
    "estimate",
    "fit",
    "simulate",
    "config",
    "report",
]

__version__: str = _ctcal.__version__

PathLike = Union[str, "os.PathLike[str]"]

#: The most pixels ``fit`` and ``estimate(method="aps")`` measure unless told otherwise (a
#: 346x260 sensor's), and the most events: the command's defaults (``ctcal_io::fit_region``).
FIT_PIXELS: int = _ctcal.FIT_PIXELS
FIT_EVENTS: int = _ctcal.FIT_EVENTS

#: The events' dtype: time in microseconds, pixel column and row, polarity (1 = ON), as
#: tonic and faery use it.
EVENT_DTYPE = np.dtype([("t", "<i8"), ("x", "<u2"), ("y", "<u2"), ("p", "u1")])


def _path(p: PathLike) -> str:
    return os.fspath(p)


def _events(t: np.ndarray, x: np.ndarray, y: np.ndarray, p: np.ndarray) -> np.ndarray:
    events = np.empty(len(t), dtype=EVENT_DTYPE)
    events["t"] = t
    events["x"] = x
    events["y"] = y
    events["p"] = p
    return events


def read(
    path: PathLike,
    *,
    start: Optional[float] = None,
    end: Optional[float] = None,
    format: Optional[str] = None,
    sensor: Optional[str] = None,
) -> np.ndarray:
    """The events of a recording as a structured array (``EVENT_DTYPE``), time-ordered.

    ``start``/``end``: seconds after the first event; ``format``: read as this format
    (``ijrr``, ``h5``, ``aedat4``, ``evt2``, ``evt3``, ``dat``, ``bag``) instead of detecting
    it; ``sensor``: ``"WxH"`` overriding the file's metadata.
    """
    return _events(*_ctcal.read(_path(path), start, end, format, sensor))


def read_frames(
    path: PathLike, *, format: Optional[str] = None, sensor: Optional[str] = None
) -> Tuple[np.ndarray, np.ndarray]:
    """The grey frames of a recording: times (int64 µs) and pixels (uint8, ``[N, H, W]``)."""
    times, pixels, h, w = _ctcal.read_frames(_path(path), format, sensor)
    return times, pixels.reshape(len(times), h, w)


def info(path: PathLike, *, format: Optional[str] = None, sensor: Optional[str] = None) -> Dict[str, Any]:
    """``ctcal info PATH --json -``: format, sensor, events, time span, frames."""
    return json.loads(_ctcal.info(_path(path), format, sensor))


def stats(
    path_or_events: Union[PathLike, np.ndarray],
    sensor: Optional[str] = None,
    *,
    start: Optional[float] = None,
    end: Optional[float] = None,
    window_s: float = 0.01,
    support_window_s: float = 0.01,
    format: Optional[str] = None,
) -> Dict[str, Any]:
    """``ctcal stats PATH --json -`` of a recording (``start``/``end`` seconds after its
    first event, ``window_s`` the rate timeline's window, ``support_window_s`` the
    background rate's), or the statistics of events in memory (a structured array with
    fields ``t``, ``x``, ``y``, ``p``, time-ordered); ``sensor`` ``"WxH"`` overrides the
    file's size, or for events gives it (else the events' extent is taken)."""
    if isinstance(path_or_events, np.ndarray):
        e = path_or_events
        text = _ctcal.stats_events(
            np.ascontiguousarray(e["t"], dtype=np.int64),
            np.ascontiguousarray(e["x"], dtype=np.uint16),
            np.ascontiguousarray(e["y"], dtype=np.uint16),
            np.ascontiguousarray(e["p"], dtype=np.uint8),
            sensor,
            window_s,
            support_window_s,
        )
    else:
        text = _ctcal.stats(
            _path(path_or_events), start, end, window_s, support_window_s, format, sensor
        )
    return json.loads(text)


def estimate(
    path: PathLike,
    method: str = "aps",
    *,
    start: Optional[float] = None,
    end: Optional[float] = None,
    max_frames: int = 120,
    max_pixels: int = FIT_PIXELS,
    max_events: int = FIT_EVENTS,
    seed: int = 2020,
    roi: Optional[str] = None,
    mask: Optional[PathLike] = None,
    format: Optional[str] = None,
    sensor: Optional[str] = None,
    stimulus: Optional[PathLike] = None,
) -> Dict[str, Any]:
    """``ctcal estimate METHOD PATH --json -`` with the command's defaults: contrast
    thresholds from grey frames (``aps``), event rate (``eppps``) or a recording of an
    on-screen stimulus (``screen``; ``stimulus`` is its folder, else ``stimulus.txt``
    beside the recording). ``aps`` of a window with more than ``max_events`` events (or
    a sensor of more than ``max_pixels`` pixels) is measured on its busiest region of
    that many, named in ``assumptions`` (0: no limit)."""
    return json.loads(
        _ctcal.estimate(
            _path(path),
            method,
            start,
            end,
            max_frames,
            max_pixels,
            max_events,
            seed,
            roi,
            None if mask is None else _path(mask),
            format,
            sensor,
            None if stimulus is None else _path(stimulus),
        )
    )


def fit(
    path: PathLike,
    *,
    start: Optional[float] = None,
    end: Optional[float] = None,
    max_frames: int = 120,
    max_pixels: int = FIT_PIXELS,
    max_events: int = FIT_EVENTS,
    seed: int = 2020,
    roi: Optional[str] = None,
    mask: Optional[PathLike] = None,
    format: Optional[str] = None,
    sensor: Optional[str] = None,
) -> Dict[str, Any]:
    """``ctcal fit PATH --json -`` with the command's defaults: every simulator parameter
    fitted, the effects the residuals call for added. A sensor with more than ``max_pixels``
    pixels is fitted on its busiest region of that size, a window with more than
    ``max_events`` events on its busiest region holding about that many (0: no limit)."""
    return json.loads(
        _ctcal.fit(
            _path(path),
            start,
            end,
            max_frames,
            max_pixels,
            max_events,
            seed,
            roi,
            None if mask is None else _path(mask),
            format,
            sensor,
        )
    )


def simulate(
    frames: np.ndarray,
    times_us: Sequence[int],
    params: Union[Mapping[str, Any], str, PathLike],
) -> np.ndarray:
    """Events of ``frames`` (uint8 ``[N, H, W]`` grey levels at ``times_us``) through the
    pixel model ``params`` (a PARAMS.toml as a dict, its text, or its path), as a
    structured array (``EVENT_DTYPE``). Deterministic for a given ``params["seed"]``."""
    frames = np.ascontiguousarray(frames, dtype=np.uint8)
    if frames.ndim != 3:
        raise CtcalError(f"frames must be [N, H, W] grey levels, not of shape {frames.shape}")
    times = np.ascontiguousarray(times_us, dtype=np.int64)
    text = _params_toml(params)
    n, h, w = frames.shape
    return _events(*_ctcal.simulate(frames.reshape(-1), n, h, w, times, text))


def _params_toml(params: Union[Mapping[str, Any], str, PathLike]) -> str:
    if isinstance(params, Mapping):
        return json.dumps(dict(params))
    p = os.fspath(params)
    if "\n" not in p and os.path.isfile(p):
        with open(p, encoding="utf-8") as f:
            return f.read()
    return p


def config(fit: Union[Mapping[str, Any], PathLike], format: str = "ctcal") -> str:
    """``ctcal config FIT --format FORMAT``: a simulator configuration (``esim``,
    ``esim-generator``, ``v2e``, ``ctcal``) from a fit result (a dict of :func:`fit`, a fit
    JSON file or a report folder)."""
    if isinstance(fit, Mapping):
        text = json.dumps(dict(fit))
    else:
        p = os.fspath(fit)
        if os.path.isdir(p):
            p = os.path.join(p, "results.json")
        with open(p, encoding="utf-8") as f:
            text = f.read()
    return _ctcal.config(text, format)


_Input = Tuple[str, str, Optional[str], str]


def _report_options(opts: Mapping[str, Any], fit: bool) -> str:
    known = {"start", "end", "max_frames", "max_pixels", "max_events", "seed", "screen", "roi", "mask", "force"}
    unknown = set(opts) - known
    if unknown:
        raise CtcalError(
            f"unknown report option(s) {sorted(unknown)}\n  fix: use {sorted(known)}"
        )
    options = {k: (os.fspath(v) if k in ("screen", "mask") and v is not None else v) for k, v in opts.items()}
    options["fit"] = fit
    return json.dumps(options)


def _sequence_task(item: _Input, options: str) -> Tuple[bool, str, List[Tuple[str, bytes]]]:
    """One recording of a report, as a cluster's task (module level so that it pickles)."""
    from . import _ctcal as native

    return native.report_sequence(tuple(item), options)


def report(
    inputs: Union[PathLike, Sequence[PathLike]],
    out: PathLike,
    client: Any = None,
    fit: bool = True,
    *,
    datasets: Optional[Mapping[str, PathLike]] = None,
    **opts: Any,
) -> Dict[str, Any]:
    """``ctcal report INPUT... --out OUT``: the report folder of some recordings (or
    folders of them; ``datasets`` names more: ``{name: folder}``), returned as the dict of
    its ``results.json``.

    Options as the command's: ``start``, ``end``, ``max_frames``, ``max_pixels``, ``max_events``, ``seed``, ``screen`` (a
    screen model TOML), ``roi``, ``mask``, ``force``; ``fit=False`` leaves the fit out.

    ``client``: a ``dask.distributed.Client``; each recording is then one task on its workers
    (``ctcal`` installed there), and the results are merged here into one report by the
    same library code as the command's. Without one, the recordings are processed on this
    machine's threads.
    """
    if isinstance(inputs, (str, os.PathLike)):
        inputs = [inputs]
    paths = [_path(p) for p in inputs]
    named = [(name, _path(p)) for name, p in (datasets or {}).items()]
    options = _report_options(opts, fit)
    items: List[_Input] = _ctcal.report_inputs(paths, named)
    protected = paths + [p for _, p in named]
    if opts.get("screen") is not None:
        protected.append(os.fspath(opts["screen"]))
    out = _path(out)
    # what made it, in the command's terms (the page and results.json show it)
    command_line = ["ctcal.report", *paths]
    for name, p in named:
        command_line += ["--dataset", f"{name}={p}"]
    command_line += ["--out", out]
    if client is not None:
        command_line += ["--client", type(client).__name__]
    if client is None:
        text = _ctcal.report_local(out, items, options, command_line, protected)
    else:
        futures = client.map(_sequence_task, items, options=options, pure=False)
        outcomes = client.gather(futures)
        text = _ctcal.report_merge(
            out,
            items,
            [(ok, payload, [(p, bytes(b)) for p, b in files]) for ok, payload, files in outcomes],
            options,
            command_line,
            protected,
        )
    return json.loads(text)
