"""One time base for every view: seconds from the recording's start.

Every widget (Player, time-series plot, frame tree) shows time the same way:
the recording's own time as seconds from its start, followed by the absolute
time where the data has one (datetime64 timestamps)::

    12.345 s · 2020-02-02 00:27:26.345

Second 0 is a :class:`~rbm_nb._engine.time.TimeBase` (``t0_ns``, absolute
nanoseconds since the epoch for datetime64 data, or ``t0_s``, the first
float timestamp): what a time is, and how seconds from second 0 are counted
exactly, is :mod:`rbm_nb._engine.time`'s; this module only prints them.
The browser side formats with the same rules in
``formatTime`` of ``js/src/timeline.js``; ``tests/notebook/test_timebase.py`` checks both against each
other.
"""

from __future__ import annotations

import math
from decimal import ROUND_HALF_UP, Decimal

import numpy as np

from .._engine.time import TimeBase

__all__ = ["TimeBase", "SEPARATOR", "format_time", "format_seconds", "format_absolute"]

#: Separator between the recording time and the absolute time in a readout.
SEPARATOR = " \u00b7 "


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
