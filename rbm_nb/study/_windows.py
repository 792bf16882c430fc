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

from .._engine.time import TimeBase


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
    # the time rule's second 0 at the start: window edges are counted from
    # it in seconds and made exact keys (datetime64[ns] rounded to the ns)
    # by the time module, so no edge drifts with k and no epoch float is made
    base = TimeBase.of(np.array([start]), "start")
    span = base.at(stop, "stop")  # seconds, from the int64 difference
    count = max(1, math.ceil(span / length))
    windows = []
    for k in range(count):
        last = k == count - 1
        lo, hi = k * length, span if last else (k + 1) * length
        windows.append(
            Window(
                base.value(lo) if k else start,
                stop if last else base.value(hi),
                base.value(lo - margin),
                base.value(hi + margin),
                last=last,
            )
        )
    return windows


def _as_scalar(value: Any) -> Any:
    value = getattr(value, "to_datetime64", lambda: value)()
    if isinstance(value, np.generic):
        return value
    return np.float64(value)
