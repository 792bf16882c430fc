"""One time base for every view: seconds from the recording's start.

Every widget (Player, time-series plot, frame tree) shows time the same way:
the recording's own time as seconds from its start, followed by the absolute
time where the data has one (datetime64 timestamps)::

    12.345 s · 2020-02-02 00:27:26.345

A :class:`TimeBase` is that start: ``t0_ns`` (absolute nanoseconds since the
epoch, for datetime64 data) or ``t0_s`` (the first float timestamp, for data
in plain seconds). The browser side formats with the same rules in
``formatTime`` of ``js/src/timeline.js``; ``tests/notebook/test_timebase.py`` checks both against each
other.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from decimal import ROUND_HALF_UP, Decimal

import numpy as np

#: Separator between the recording time and the absolute time in a readout.
SEPARATOR = " \u00b7 "


@dataclass(frozen=True)
class TimeBase:
    """Second 0 of a recording.

    Attributes
    ----------
    t0_ns : int or None
        Absolute time of second 0 in ns since the epoch, for datetime64 data.
    t0_s : float
        Timestamp value of second 0 for data in plain float seconds (0.0 for
        datetime64 data).
    """

    t0_ns: int | None = None
    t0_s: float = 0.0

    @classmethod
    def of(cls, timestamps) -> TimeBase:
        """The time base that puts second 0 at the first of ``timestamps``.

        Parameters
        ----------
        timestamps : array_like, shape (n,)
            datetime64 or float seconds, sorted (n >= 1).
        """
        arr = np.asarray(getattr(timestamps, "values", timestamps))
        if arr.ndim != 1 or arr.size == 0:
            raise ValueError(
                f"TimeBase.of: timestamps must be a non-empty 1-d array, got shape {arr.shape}"
            )
        if np.issubdtype(arr.dtype, np.datetime64):
            return cls(t0_ns=int(arr[:1].astype("datetime64[ns]").astype(np.int64)[0]))
        return cls(t0_s=float(arr[0]))

    @property
    def absolute(self) -> bool:
        """Whether the recording has an absolute (datetime) time."""
        return self.t0_ns is not None

    def seconds(self, timestamps, name: str = "timestamps") -> np.ndarray:
        """Timestamps as float64 seconds from second 0.

        datetime64 input is taken exactly as int64 ns before the subtraction,
        so no precision is lost to epoch-sized floats.

        Raises
        ------
        ValueError
            If datetime64 timestamps meet a time base without ``t0_ns`` or
            float timestamps one with it (the two cannot be lined up).
        """
        arr = np.asarray(getattr(timestamps, "values", timestamps))
        if np.issubdtype(arr.dtype, np.datetime64):
            if self.t0_ns is None:
                raise ValueError(
                    f"{name} are datetime64 but this time base is in plain seconds"
                )
            ns = arr.astype("datetime64[ns]").astype(np.int64)
            return (ns - self.t0_ns).astype(np.float64) / 1e9
        if self.t0_ns is not None:
            raise ValueError(
                f"{name} are plain seconds but this time base is absolute "
                "(datetime64); use datetime64 timestamps everywhere"
            )
        return np.asarray(arr, dtype=np.float64) - self.t0_s

    def format(self, t: float) -> str:
        """``t`` (seconds from second 0) as the shared readout."""
        return format_time(t, self.t0_ns)


def format_seconds(t: float) -> str:
    """Seconds from the start with millisecond digits: ``12.345 s``."""
    # Decimal(float) is the exact binary value; rounding it half away from zero
    # is what JavaScript's toFixed does, so both sides print the same digits
    exact = Decimal(float(t) + 0.0).quantize(Decimal("0.001"), rounding=ROUND_HALF_UP)
    return f"{exact} s"


def format_absolute(t: float, t0_ns: int) -> str:
    """The absolute time of ``t`` seconds after ``t0_ns``, to the millisecond.

    ``YYYY-MM-DD hh:mm:ss.mmm`` (the timestamps' own clock, usually UTC).
    """
    ms = math.floor(t0_ns / 1e6 + float(t) * 1e3 + 0.5)
    return str(np.datetime64(ms, "ms")).replace("T", " ")


def format_time(t: float | None, t0_ns: int | None = None) -> str:
    """The shared readout: ``12.345 s`` or ``12.345 s · 2020-02-02 00:27:26.345``.

    Parameters
    ----------
    t : float or None
        Seconds from the recording's start (None prints as an em dash).
    t0_ns : int, optional
        Absolute ns of second 0, when the recording has datetime timestamps.

    Examples
    --------
    >>> format_time(12.3456)
    '12.346 s'
    >>> t0 = int(np.datetime64("2020-02-02T00:27:14", "ns").astype(np.int64))
    >>> format_time(12.3456, t0)
    '12.346 s · 2020-02-02 00:27:26.346'
    """
    if t is None or not math.isfinite(t):
        return "\u2014"
    text = format_seconds(t)
    if t0_ns is not None:
        text += SEPARATOR + format_absolute(t, t0_ns)
    return text
