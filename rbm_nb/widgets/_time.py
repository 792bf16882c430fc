"""Timestamps as float seconds, whatever they came in as.

The notebook layer compares times across objects recorded at different rates,
so everything is reduced to one float64 axis: seconds (since the epoch for
datetime64 input). ``kind`` remembers which it was; the readout itself is
``_timebase.format_time`` (seconds from the start, then the absolute time).
"""

from __future__ import annotations

import numpy as np

DATETIME = "datetime"
FLOAT = "float"


def timestamps_as_seconds(
    timestamps, name: str = "timestamps"
) -> tuple[np.ndarray, str]:
    """Convert timestamps to float64 seconds.

    Parameters
    ----------
    timestamps : array_like, shape (n,)
        Float seconds, datetime64 or timedelta64 values (numpy, pandas or
        xarray containers).
    name : str
        Name used in error messages.

    Returns
    -------
    seconds : ndarray, shape (n,)
        Contiguous float64 seconds, non-decreasing.
    kind : {"datetime", "float"}
        ``"datetime"`` when the input was datetime64.

    Raises
    ------
    ValueError
        If the timestamps are empty, not one-dimensional, not finite or not
        sorted.
    """
    values = getattr(timestamps, "values", timestamps)
    arr = np.asarray(values)
    if arr.ndim != 1:
        raise ValueError(f"{name} must be one-dimensional, got shape {arr.shape}")
    if arr.size == 0:
        raise ValueError(f"{name} must contain at least one timestamp, got none")
    if np.issubdtype(arr.dtype, np.datetime64):
        ns = arr.astype("datetime64[ns]")
        if np.isnat(ns).any():
            raise ValueError(
                f"{name} contains NaT at index {int(np.argmax(np.isnat(ns)))}"
            )
        seconds = ns.astype(np.int64).astype(np.float64) / 1e9
        kind = DATETIME
    elif np.issubdtype(arr.dtype, np.timedelta64):
        ns = arr.astype("timedelta64[ns]")
        if np.isnat(ns).any():
            raise ValueError(
                f"{name} contains NaT at index {int(np.argmax(np.isnat(ns)))}"
            )
        seconds = ns.astype(np.int64).astype(np.float64) / 1e9
        kind = FLOAT
    else:
        try:
            seconds = arr.astype(np.float64)
        except (TypeError, ValueError):
            raise ValueError(
                f"{name} must be numbers or datetime64 values, got dtype {arr.dtype}"
            ) from None
        kind = FLOAT
        bad = ~np.isfinite(seconds)
        if bad.any():
            raise ValueError(
                f"{name} must be finite, found {seconds[bad][0]} at index {int(np.argmax(bad))}"
            )
    seconds = np.ascontiguousarray(seconds)
    if seconds.size > 1:
        drops = np.diff(seconds) < 0
        if drops.any():
            i = int(np.argmax(drops)) + 1
            raise ValueError(
                f"{name} must be sorted, but index {i} is earlier than index {i - 1}"
            )
    return seconds, kind


def time_as_seconds(t, kind: str | None = None) -> float:
    """One time value (float seconds or datetime64) as float seconds."""
    if isinstance(t, (np.datetime64,)) or (
        hasattr(t, "dtype") and np.issubdtype(np.asarray(t).dtype, np.datetime64)
    ):
        if kind == FLOAT:
            raise ValueError(
                f"got the datetime {t} but these timestamps are plain seconds"
            )
        return float(np.asarray(t).astype("datetime64[ns]").astype(np.int64)) / 1e9
    if hasattr(t, "to_datetime64"):  # pandas Timestamp
        return time_as_seconds(t.to_datetime64(), kind)
    value = float(t)
    if not np.isfinite(value):
        raise ValueError(f"time must be finite, got {t}")
    return value


def seconds_to_datetime64(seconds: np.ndarray) -> np.ndarray:
    """Float seconds since the epoch back to datetime64[ns]."""
    return np.round(np.asarray(seconds) * 1e9).astype(np.int64).astype("datetime64[ns]")


def check_kinds(kind_a: str | None, kind_b: str | None, what: str) -> None:
    """Refuse to compare datetime timestamps with plain seconds."""
    if kind_a is not None and kind_b is not None and kind_a != kind_b:
        raise ValueError(
            f"{what}: cannot synchronise {kind_a} timestamps with {kind_b} timestamps "
            "(use datetime64 everywhere or float seconds everywhere)"
        )
