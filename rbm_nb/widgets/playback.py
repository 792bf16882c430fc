"""The Player's playback model: time arithmetic with no widget and no clock of its own.

A :class:`Playback` knows the time axis (float seconds, sorted), the current
time as seconds from its first sample, whether it plays, at what speed and
whether it loops. The wall clock is passed in (``now``, seconds): in the
notebook the clock is the browser's ``requestAnimationFrame`` and the same
arithmetic runs in ``js/src/lib/clock.js``; here it is what tests and
:class:`~rbm_nb.widgets.Player` use to answer questions about time without a
browser.

While playing, the time is ``anchor_time + (now - anchor_wall) * speed``; every
change of speed, seek or pause re-anchors, so the time never jumps.
"""

from __future__ import annotations

import math

import numpy as np

from .._engine.time import TIE

#: Two times closer than this (seconds) are the same sample. The Player hands
#: seconds from its first sample computed from exact keys, so half a
#: nanosecond is enough (the time module's one rule, :data:`~rbm_nb._engine.time.TIE`).
TOLERANCE = TIE


class SampleTimes:
    """Seconds from the first sample, counted from exact keys when asked.

    A Player over hours of samples used to keep three per-sample arrays (a
    copy of its timestamps, their float seconds, and those seconds again from
    the first sample). This keeps only the keys it is given (int64 ns, or
    float seconds) and computes the seconds of the samples it is asked about,
    with the very arithmetic those arrays were made with, so every answer is
    the same to the last bit.

    Parameters
    ----------
    key : ndarray, shape (n,)
        Sorted exact keys: int64 nanoseconds or float64 seconds.
    scale : float
        Keys per second (1e9 for ns keys, 1.0 for seconds).
    """

    __slots__ = ("key", "_origin", "_scale")

    def __init__(self, key: np.ndarray, scale: float) -> None:
        self.key = key
        self._origin = key[0]
        self._scale = float(scale)

    def __len__(self) -> int:
        return int(self.key.shape[0])

    def at(self, index: int) -> float:
        """Seconds from the first sample of sample ``index``."""
        return float((self.key[index] - self._origin) / self._scale)

    def array(self) -> np.ndarray:
        """Every sample's seconds from the first (a new array: for callers that ask)."""
        return (self.key - self._origin) / self._scale

    def last_at_or_before(self, t: float) -> int:
        """Index of the last sample whose seconds are at most ``t`` (-1: none).

        The keys are searched near ``t``'s own key, then the answer is made
        exact against :meth:`at` (a step over a run of repeated keys at most).
        """
        n, t = len(self), float(t)
        if math.isnan(t) or t == math.inf:
            return n - 1  # as searchsorted on the seconds puts them
        if t == -math.inf:
            return -1
        guess = float(self._origin) + t * self._scale
        if self.key.dtype.kind in "iu":
            # clamped: a far time must not overflow the int64 keys
            guess = min(max(guess, -9.2e18), 9.2e18)
            target: float | int = math.floor(guess)
        else:
            target = guess
        i = int(np.searchsorted(self.key, target, side="right")) - 1
        while i + 1 < n and self.at(i + 1) <= t:
            i = int(np.searchsorted(self.key, self.key[i + 1], side="right")) - 1
        while i >= 0 and self.at(i) > t:
            i = int(np.searchsorted(self.key, self.key[i], side="left")) - 1
        return i


class Playback:
    """Time on an axis of samples, played by an external clock.

    Parameters
    ----------
    seconds : array_like, shape (n,)
        Sorted float seconds of the samples (any origin).
    speed : float, default 1.0
    loop : bool, default False

    Attributes
    ----------
    time : float
        Seconds from the first sample, in ``[0, duration]``.
    playing : bool
    """

    def __init__(self, seconds, *, speed: float = 1.0, loop: bool = False) -> None:
        if isinstance(seconds, SampleTimes):
            # the Player's keys, validated by the time rule: no float copy
            self.origin = 0.0
            self.samples = seconds
        else:
            seconds = np.ascontiguousarray(seconds, dtype=np.float64)
            if seconds.ndim != 1 or seconds.size == 0:
                raise ValueError(
                    "Playback: seconds must be a non-empty 1-D array, got shape "
                    f"{seconds.shape}"
                )
            if not np.isfinite(seconds).all() or (np.diff(seconds) < 0).any():
                raise ValueError("Playback: seconds must be finite and sorted")
            self.origin = float(seconds[0])
            self.samples = SampleTimes(seconds - self.origin, 1.0)
        self.duration = self.samples.at(len(self.samples) - 1)
        self.speed = check_speed(speed, "Playback")
        self.loop = bool(loop)
        self.playing = False
        self.time = 0.0
        self._anchor_time = 0.0
        self._anchor_wall = 0.0

    # -- samples ------------------------------------------------------------------
    @property
    def n(self) -> int:
        return len(self.samples)

    @property
    def relative(self) -> np.ndarray:
        """Every sample's seconds from the first (computed on each call)."""
        return self.samples.array()

    def clamp(self, t: float) -> float:
        """``t`` limited to ``[0, duration]``; refuses non-finite times."""
        t = float(t)
        if not np.isfinite(t):
            raise ValueError(f"time must be finite, got {t}")
        return min(max(t, 0.0), self.duration)

    def index_at(self, t: float) -> int:
        """Index of the latest sample at or before ``t`` (seconds from the start; 0 before it)."""
        i = self.samples.last_at_or_before(t + TOLERANCE)
        return min(max(i, 0), self.n - 1)

    def time_of(self, index: int) -> float:
        """Seconds from the start of sample ``index`` (clipped to the axis)."""
        return self.samples.at(int(np.clip(index, 0, self.n - 1)))

    @property
    def index(self) -> int:
        """Index of the sample shown at the current time."""
        return self.index_at(self.time)

    @property
    def mean_interval(self) -> float:
        """Mean seconds between samples (0 for one sample)."""
        return self.duration / (self.n - 1) if self.n > 1 else 0.0

    # -- clock --------------------------------------------------------------------
    def _anchor(self, now: float) -> None:
        self._anchor_time = self.time
        self._anchor_wall = float(now)

    def play(self, now: float) -> None:
        """Start playing at wall time ``now``; from the start when at the end."""
        if self.playing or self.duration <= 0:
            return
        if self.time >= self.duration:
            self.time = 0.0
        self.playing = True
        self._anchor(now)

    def pause(self, now: float) -> None:
        """Stop at the time due at ``now``."""
        if self.playing:
            self.advance(now)
            self.playing = False

    def seek(self, t: float, now: float) -> float:
        """Go to ``t`` seconds from the start (clamped); playing goes on from there."""
        self.time = self.clamp(t)
        self._anchor(now)
        return self.time

    def skip(self, seconds: float, now: float) -> float:
        """Jump by ``seconds`` (negative: back); wraps around when looping."""
        self.advance(now)
        target = self.time + float(seconds)
        if self.loop and self.duration > 0 and not 0 <= target <= self.duration:
            target %= self.duration
        return self.seek(target, now)

    def step(self, samples: int, now: float) -> float:
        """Go ``samples`` samples forward (negative: back) from the current one."""
        self.advance(now)
        return self.seek(self.time_of(self.index + int(samples)), now)

    def set_speed(self, speed: float, now: float) -> None:
        """Change the speed without a jump in time."""
        self.advance(now)
        self.speed = check_speed(speed, "Playback")
        self._anchor(now)

    def advance(self, now: float) -> float:
        """The time at wall time ``now``; stops at the end or wraps when looping."""
        if not self.playing:
            return self.time
        t = self._anchor_time + (float(now) - self._anchor_wall) * self.speed
        if t >= self.duration:
            if self.loop and self.duration > 0:
                t %= self.duration
                self.time = t
                self._anchor(now)
                return t
            self.time = self.duration
            self.playing = False
            return self.time
        self.time = max(t, 0.0)
        return self.time


def check_speed(speed, owner: str) -> float:
    """A positive finite float, else a ValueError naming ``owner``."""
    try:
        value = float(speed)
    except (TypeError, ValueError):
        raise ValueError(
            f"{owner}: speed must be a positive number, got {speed!r}"
        ) from None
    if isinstance(speed, bool) or not (np.isfinite(value) and value > 0):
        raise ValueError(f"{owner}: speed must be a positive number, got {speed!r}")
    return value
