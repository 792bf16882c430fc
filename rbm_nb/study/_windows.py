"""Cutting a recording into time windows that are analysed independently.

A window reads ``margin`` seconds more on each side than it keeps, so that
interpolation, finite differences and filters near its edges see the same
neighbouring samples they would see in the whole recording; the margin is
trimmed from the result. Windows keep ``start <= time < stop`` except the
last, which also keeps ``time == stop``, so every sample lands in exactly
one window.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr

from .._engine.time import epoch_seconds, from_epoch_seconds


@dataclass(frozen=True)
class Window:
    """One window of a recording: kept span and read span."""

    start: Any
    stop: Any
    read_start: Any
    read_stop: Any
    last: bool

    def trim(self, result: xr.Dataset | xr.DataArray, recording: str):
        """The part of a window's result inside the kept span."""
        if "time" not in result.dims:
            raise ValueError(
                f"the analysis of recording {recording!r} returned no 'time' "
                f"dimension, so it cannot be cut into windows; pass window=None "
                f"for analyses that summarise a whole recording"
            )
        time = result["time"].values
        keep = (time >= self.start) & (
            (time <= self.stop) if self.last else (time < self.stop)
        )
        return result.isel(time=np.flatnonzero(keep))


def _seconds_as(reference: Any, seconds: float) -> Any:
    """``seconds`` in the unit of ``reference`` (timedelta64 for datetime64 times)."""
    if isinstance(reference, (np.datetime64,)) or (
        hasattr(reference, "dtype") and np.dtype(reference.dtype).kind == "M"
    ):
        return from_epoch_seconds(seconds, "timedelta64")[()]
    return seconds


def split(start: Any, stop: Any, length: float, margin: float) -> list[Window]:
    """Windows of ``length`` seconds covering ``[start, stop]``.

    Parameters
    ----------
    start, stop : float or numpy.datetime64
        Span of the recording.
    length : float
        Seconds kept per window (> 0).
    margin : float
        Seconds read beyond each edge (>= 0).
    """
    if not (isinstance(length, (int, float)) and math.isfinite(length) and length > 0):
        raise ValueError(f"window must be a positive number of seconds, got {length!r}")
    if not (isinstance(margin, (int, float)) and math.isfinite(margin) and margin >= 0):
        raise ValueError(
            f"margin must be a non-negative number of seconds, got {margin!r}"
        )
    start, stop = _as_scalar(start), _as_scalar(stop)
    step = _seconds_as(start, length)
    pad = _seconds_as(start, margin)
    span = stop - start
    count = max(1, math.ceil(_in_seconds(span) / length))
    windows = []
    for k in range(count):
        lo = start + k * step
        hi = stop if k == count - 1 else start + (k + 1) * step
        windows.append(Window(lo, hi, lo - pad, hi + pad, last=k == count - 1))
    return windows


def _as_scalar(value: Any) -> Any:
    value = getattr(value, "to_datetime64", lambda: value)()
    if isinstance(value, np.generic):
        return value
    return np.float64(value)


def _in_seconds(span: Any) -> float:
    return float(epoch_seconds(span, name="span"))
