"""Timestamps as the user gave them, plus the numbers the kernels compute with.

Two kinds of timestamps are supported, never mixed in one operation:

* numeric (int or float, any unit; velocities assume seconds): the kernels
  use the values themselves as float64, so results equal the reference's;
* ``datetime64``: compared exactly as int64 nanoseconds, and interpolated in
  float seconds counted from the first timestamp of each series. Converting
  whole epochs to float (as the reference does) loses ~0.25 µs, which is
  5e-5 of a 200 Hz sample period.

Whatever is computed, the timestamps handed back are slices (or the sorted
union) of the original arrays, in their original dtype.
"""

from __future__ import annotations

import numpy as np

from ._kernels.resample import first_unordered

_NS_PER_S = 1e9


class Track:
    """Validated, strictly increasing timestamps of one frame or array.

    Attributes
    ----------
    values : ndarray, shape (n,)
        A private copy of the timestamps as given, original dtype.
    key : ndarray, shape (n,)
        Exact sort keys: int64 nanoseconds for datetime64, else float64.
    base : ndarray, shape (n,)
        float64 times for interpolation: seconds since ``origin`` for
        datetime64, else the values themselves.
    origin : int
        int64 nanoseconds of ``values[0]`` for datetime64, else 0.
    is_datetime : bool
    """

    __slots__ = ("values", "key", "base", "origin", "is_datetime")

    def __init__(self, values, key, base, origin, is_datetime):
        self.values = values
        self.key = key
        self.base = base
        self.origin = origin
        self.is_datetime = is_datetime

    def __len__(self) -> int:
        return self.values.shape[0]

    def slice(self, lo: int, hi: int) -> Track:
        """The timestamps ``lo:hi`` (same origin, so bases stay comparable)."""
        return Track(
            self.values[lo:hi],
            self.key[lo:hi],
            self.base[lo:hi],
            self.origin,
            self.is_datetime,
        )

    def base_in(self, origin: int) -> np.ndarray:
        """``base`` expressed on another track's origin (datetime64 only)."""
        if not self.is_datetime or origin == self.origin:
            return self.base
        return self.base + (self.origin - origin) / _NS_PER_S

    def seconds(self) -> np.ndarray:
        """Times in seconds for finite differences (the reference's units)."""
        return self.base


def as_track(
    timestamps, name: str = "timestamps", length: int | None = None, copy: bool = True
) -> Track:
    """Validate timestamps and wrap them in a :class:`Track`.

    Parameters
    ----------
    timestamps : array_like, shape (n,)
        Numeric or datetime64 timestamps (a DataArray, pandas index or list).
    name : str
        How the argument is called in error messages.
    length : int, optional
        The required number of timestamps.
    copy : bool, default True
        Keep a private copy of the values (frames do; a transient track for
        one call does not need to).

    Raises
    ------
    ValueError
        If the timestamps are not one-dimensional, not numeric or datetime64,
        empty, of the wrong length, contain NaN/inf/NaT, or are not strictly
        increasing (the message names the first offending index).
    """
    values = getattr(timestamps, "values", timestamps)
    values = np.asarray(values)
    if copy:
        # callers may change their array later; frames must not change with it
        # (key and base below may be views of this private copy)
        values = np.array(values, copy=True)
    if values.ndim != 1:
        raise ValueError(f"{name} must be one-dimensional, got shape {values.shape}")
    if values.shape[0] == 0:
        raise ValueError(f"{name} must not be empty")
    if length is not None and values.shape[0] != length:
        raise ValueError(
            f"{name} has {values.shape[0]} entries but the data has {length} samples"
        )
    kind = values.dtype.kind
    if kind == "M":
        key = values.astype("datetime64[ns]", copy=False).view(np.int64)
        if np.any(np.isnat(values)):
            bad = int(np.flatnonzero(np.isnat(values))[0])
            raise ValueError(f"{name}[{bad}] is NaT; timestamps must be valid dates")
        origin = int(key[0])
        base = (key - origin) / _NS_PER_S
        is_datetime = True
    elif kind in "iuf":
        key = np.asarray(values, dtype=np.float64)
        finite = np.isfinite(key)
        if not finite.all():
            bad = int(np.flatnonzero(~finite)[0])
            raise ValueError(
                f"{name}[{bad}] is {values[bad]}; timestamps must be finite numbers"
            )
        origin = 0
        base = key
        is_datetime = False
    else:
        raise ValueError(
            f"{name} must be numeric or datetime64, got dtype {values.dtype}"
        )
    i = first_unordered(np.ascontiguousarray(key))
    if i >= 0:
        what = "a duplicate of" if key[i] == key[i - 1] else "earlier than"
        raise ValueError(
            f"{name} must be strictly increasing: {name}[{i}] = {values[i]} is "
            f"{what} {name}[{i - 1}] = {values[i - 1]}"
        )
    key = np.ascontiguousarray(key)
    base = key if base is key else np.ascontiguousarray(base, dtype=np.float64)
    return Track(values, key, base, origin, is_datetime)


def check_compatible(tracks, names=None) -> None:
    """Raise if datetime64 and numeric timestamps meet in one operation."""
    kinds = {t.is_datetime for t in tracks if t is not None}
    if len(kinds) > 1:
        raise ValueError(
            "cannot match datetime64 timestamps with numeric timestamps; "
            "convert one of them (e.g. seconds since the first sample)"
        )


def union(tracks) -> Track:
    """Sorted union of several tracks' timestamps (for discrete-only chains)."""
    values = np.unique(np.concatenate([t.values for t in tracks]))
    return as_track(values)
