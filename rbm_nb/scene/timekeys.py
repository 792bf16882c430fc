"""The scene's times: the core's exact keys, and seconds only for the browser.

A scene keeps every time as the core keeps a frame's
(:mod:`rbm_nb._engine.time`): int64 nanoseconds for datetime64/timedelta64
timestamps (a Python int for one time), float seconds for numbers. Tracks
are searched by key, the scene's second 0 is a
:class:`~rbm_nb._engine.time.TimeBase` at the earliest key, and seconds
from it are counted by int64 subtraction before any division, so samples
1 ns apart stay two samples at any epoch (a float epoch second is ~0.24 µs
coarse today). Floats exist where a message to the browser is packed
(:func:`seconds_from`) and where a time enters from outside (the browser's
clock through the Player, a float epoch second from the user:
:func:`~rbm_nb._engine.time.time_key`, once).
"""

from __future__ import annotations

import numpy as np

from .._engine.time import TIE, TimeBase

__all__ = ["KEYS_PER_SECOND", "at_or_before", "base_of", "seconds_from", "key_after"]

#: keys per second of each kind of time (ns keys: 1e9)
KEYS_PER_SECOND = {"numeric": 1.0, "datetime64": 1e9, "timedelta64": 1e9}

# the int64 range ns keys may take (NaT, the minimum, excluded)
_INT64 = np.iinfo(np.int64)


def at_or_before(key: int | float, kind: str | None) -> int | float:
    """The key searched (``side="right"``) for the latest sample at or before ``key``.

    The core's rule (:func:`rbm_nb._engine.time.latest_index`): ns keys are
    exact; a float time within :data:`~rbm_nb._engine.time.TIE` of a sample
    is that sample, so ``0.3`` finds the sample stored as
    ``0.30000000000000004``.
    """
    if kind is None or kind == "numeric":
        return float(key) + TIE
    return key


def base_of(first: int | float | None, kind: str | None) -> TimeBase:
    """Second 0 at key ``first`` (the earliest sample); second 0 of 0.0 when
    nothing moves."""
    if first is None or kind is None or kind == "numeric":
        return TimeBase(t0_s=0.0 if first is None else float(first))
    return TimeBase(t0_ns=int(first), elapsed=kind == "timedelta64")


def seconds_from(base: TimeBase, keys: np.ndarray) -> np.ndarray:
    """Float64 seconds of ``keys`` from ``base``'s second 0 (what the browser gets).

    ns keys: int64 difference, then one division (exact to the float
    rounding of the difference); float keys: the difference.
    """
    if base.t0_ns is None:
        return np.asarray(keys, dtype=np.float64) - base.t0_s
    return (np.asarray(keys, dtype=np.int64) - base.t0_ns) / 1e9


def key_after(base: TimeBase, seconds: float) -> int | float:
    """The key ``seconds`` after ``base``'s second 0 (ns keys rounded to the
    ns and kept within int64, so a far chunk boundary cannot overflow)."""
    if base.t0_ns is None:
        return base.t0_s + float(seconds)
    key = base.t0_ns + round(float(seconds) * 1e9)
    return min(max(key, int(_INT64.min) + 1), int(_INT64.max))
