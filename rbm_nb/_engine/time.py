"""Time, converted once: exact sort keys plus float seconds from a reference.

Every timestamp argument of the core (frames, arrays, requested lookup times,
estimators, ``qinterp``) goes through this module, so there is one rule for
what a time is and how it is ordered:

* numeric timestamps (int or float, any unit; velocities assume seconds) are
  compared and interpolated as float64 values, so results equal the
  reference package's;
* ``datetime64`` and ``timedelta64`` are compared exactly as int64
  nanoseconds and interpolated in float64 seconds counted from a reference
  time (the first timestamp of each series). Converting whole epochs to
  float (as the reference does) loses ~0.25 µs, 5e-5 of a 200 Hz period;
* the two kinds never meet in one operation (nor datetime64 with
  timedelta64).

The ordering rule is explicit: :func:`as_track` requires strictly increasing
times (a frame's or an array's samples); :func:`requested_times` accepts any
order and repeats (the times a caller asks a lookup at). Whatever is
computed, timestamps handed back are slices (or the sorted union) of the
original values, in their original dtype.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._kernels._arrays import kernel_array, read_only
from .._kernels.times import float_key_faults, ns_key_faults, seconds_since

__all__ = [
    "Track",
    "as_track",
    "requested_times",
    "check_compatible",
    "union",
    "seconds",
    "seconds_pair",
]

_NS_PER_S = 1e9
_NAT = np.iinfo(np.int64).min  # NaT as an int64 key

# dtype kind -> name of the kind of time (numeric kinds share one name)
_KINDS = {"M": "datetime64", "m": "timedelta64"}
_DATETIME_NS = np.dtype("datetime64[ns]")
_TIMEDELTA_NS = np.dtype("timedelta64[ns]")


def _keys(values: np.ndarray, name: str) -> tuple[np.ndarray, str]:
    """Exact sort keys of one-dimensional times, and their kind.

    Returns int64 nanoseconds for datetime64/timedelta64 and float64 values
    for numbers; raises for NaT, NaN/inf and other dtypes, naming the first
    offending index.
    """
    kind = values.dtype.kind
    if kind in _KINDS:
        nat = np.isnat(values)
        if nat.any():
            bad = int(np.flatnonzero(nat)[0])
            raise ValueError(f"{name}[{bad}] is NaT; timestamps must be valid dates")
        unit = "datetime64[ns]" if kind == "M" else "timedelta64[ns]"
        return values.astype(unit, copy=False).view(np.int64), _KINDS[kind]
    if kind in "iufb":
        key = np.asarray(values, dtype=np.float64)
        finite = np.isfinite(key)
        if not finite.all():
            bad = int(np.flatnonzero(~finite)[0])
            raise ValueError(
                f"{name}[{bad}] is {values[bad]}; timestamps must be finite numbers"
            )
        return key, "numeric"
    raise ValueError(f"{name} must be numeric or datetime64, got dtype {values.dtype}")


class Track:
    """Validated, strictly increasing timestamps of one frame or array.

    Attributes
    ----------
    values : ndarray, shape (n,)
        The timestamps as given, original dtype.
    key : ndarray, shape (n,)
        Exact sort keys: int64 nanoseconds for datetime64/timedelta64, else
        float64.
    base : ndarray, shape (n,)
        C-contiguous float64 times for the kernels: seconds since ``origin``
        for datetime64/timedelta64, else the values themselves.
    origin : int
        int64 nanoseconds of ``values[0]`` for datetime64/timedelta64, else 0.
    kind : {"numeric", "datetime64", "timedelta64"}
    """

    __slots__ = ("values", "key", "base", "origin", "kind")

    def __init__(
        self,
        values: np.ndarray,
        key: np.ndarray,
        base: np.ndarray,
        origin: int,
        kind: str,
    ) -> None:
        self.values = values
        self.key = key
        self.base = base
        self.origin = origin
        self.kind = kind

    @property
    def is_datetime(self) -> bool:
        """Whether the keys are int64 nanoseconds (datetime64 or timedelta64)."""
        return self.kind != "numeric"

    def __len__(self) -> int:
        return int(self.values.shape[0])

    def slice(self, lo: int, hi: int) -> Track:
        """The timestamps ``lo:hi`` (same origin, so bases stay comparable)."""
        return Track(
            self.values[lo:hi],
            self.key[lo:hi],
            self.base[lo:hi],
            self.origin,
            self.kind,
        )

    def base_in(self, origin: int) -> np.ndarray:
        """``base`` counted from another track's origin (nanosecond kinds only)."""
        if self.kind == "numeric" or origin == self.origin:
            return self.base
        return self.base + (self.origin - origin) / _NS_PER_S

    def seconds(self) -> np.ndarray:
        """Times in seconds for finite differences (the reference's units)."""
        return self.base


def _first_unordered(key: np.ndarray) -> int:
    """Index of the first key not greater than its predecessor, or -1."""
    bad = np.flatnonzero(key[1:] <= key[:-1])
    return int(bad[0]) + 1 if bad.size else -1


def _ordered_keys(values: np.ndarray, name: str) -> tuple[np.ndarray, str]:
    """:func:`_keys` of strictly increasing times; raises naming the first fault.

    The usual case, datetime64[ns] or float64 times without a fault, takes
    one counting kernel (two vectorised passes) instead of numpy's four
    passes and temporaries; any fault found there, or any other input,
    goes through the numpy checks, which name it.
    """
    dtype = values.dtype
    if dtype in (_DATETIME_NS, _TIMEDELTA_NS):
        key = values.view(np.int64)
        view = read_only(key)
        if view is not None and ns_key_faults(view) == (0, 0):
            return key, _KINDS[dtype.kind]
    elif dtype == np.float64:
        view = read_only(values)
        if view is not None and float_key_faults(view) == (0, 0):
            return values, "numeric"
    key, kind = _keys(values, name)
    i = _first_unordered(key)
    if i >= 0:
        what = "a duplicate of" if key[i] == key[i - 1] else "earlier than"
        raise ValueError(
            f"{name} must be strictly increasing: {name}[{i}] = {values[i]} is "
            f"{what} {name}[{i - 1}] = {values[i - 1]}"
        )
    return key, kind


def as_track(
    timestamps: Any,
    name: str = "timestamps",
    length: int | None = None,
    copy: bool = True,
) -> Track:
    """Validate strictly increasing timestamps and wrap them in a :class:`Track`.

    Parameters
    ----------
    timestamps : array_like, shape (n,)
        Numeric, datetime64 or timedelta64 times (a DataArray, pandas index
        or list).
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
    values = np.asarray(getattr(timestamps, "values", timestamps))
    if copy:
        # callers may change their array later; frames must not change with it
        values = np.array(values, copy=True)
    if values.ndim != 1:
        raise ValueError(f"{name} must be one-dimensional, got shape {values.shape}")
    if values.shape[0] == 0:
        raise ValueError(f"{name} must not be empty")
    if length is not None and values.shape[0] != length:
        raise ValueError(
            f"{name} has {values.shape[0]} entries but the data has {length} samples"
        )
    key, kind = _ordered_keys(values, name)
    if kind == "numeric":
        key = kernel_array(key)  # the kernels interpolate on it directly
        return Track(values, key, key, 0, kind)
    origin = int(key[0])
    view = read_only(key)
    if view is not None:
        return Track(values, key, seconds_since(view, origin), origin, kind)
    return Track(values, key, (key - origin) / _NS_PER_S, origin, kind)


def requested_times(
    time: Any, name: str = "time"
) -> tuple[Track, np.ndarray, bool, np.ndarray]:
    """Times a caller asks for: any order, repeats allowed.

    Returns
    -------
    track : Track
        The sorted unique times.
    inverse : ndarray of int, shape (n,)
        Position of each requested time in ``track``.
    scalar : bool
        Whether a single time (0-d) was requested.
    values : ndarray, shape (n,)
        The requested times as given (for returning them).
    """
    values = np.asarray(getattr(time, "values", time))
    scalar = values.ndim == 0
    values = values.reshape(-1) if scalar else values
    if values.ndim != 1:
        raise ValueError(
            f"{name} must be a scalar or one-dimensional, got shape {values.shape}"
        )
    if values.size == 0:
        raise ValueError(f"{name} must not be empty")
    if values.dtype.kind not in "iufMm":
        raise ValueError(
            f"{name} must be numeric or datetime64 (like the frames' timestamps), "
            f"got dtype {values.dtype}"
        )
    key, kind = _keys(values, name)
    if key.shape[0] == 1:
        # one time (a widget's, the tf2-style Transformer's): the Track
        # as_track would make, without checking its order again
        return _one_time(values, key, kind), np.zeros(1, np.intp), scalar, values
    if bool((key[1:] > key[:-1]).all()):
        # one time, or times already sorted without repeats (a widget's or
        # a resampling's): no sort, and as_track finds them ordered
        return as_track(values, name), np.arange(key.shape[0]), scalar, values
    _, first, inverse = np.unique(key, return_index=True, return_inverse=True)
    track = as_track(values[first], name)
    return track, inverse.reshape(-1), scalar, values


def _one_time(values: np.ndarray, key: np.ndarray, kind: str) -> Track:
    """The Track of one valid time (``key`` and ``kind`` from :func:`_keys`)."""
    values = np.array(values, copy=True)
    if kind == "numeric":
        key = np.array(key, dtype=np.float64, copy=True)  # not the caller's array
        return Track(values, key, key, 0, kind)
    key = np.array(key, copy=True)
    return Track(values, key, np.zeros(1), int(key[0]), kind)


def check_compatible(tracks: Any) -> None:
    """Raise if different kinds of time (numbers, datetime64, timedelta64) meet."""
    kinds = sorted({t.kind for t in tracks if t is not None})
    if len(kinds) > 1:
        raise ValueError(
            f"cannot match {kinds[0]} timestamps with {kinds[1]} timestamps; convert "
            f"one of them (e.g. numeric seconds since the first sample)"
        )


def union(tracks: Any) -> Track:
    """Sorted union of several tracks' timestamps (for discrete-only chains)."""
    values = np.unique(np.concatenate([t.values for t in tracks]))
    return as_track(values)


def seconds(timestamps: Any, n: int, name: str = "timestamps") -> np.ndarray:
    """Strictly increasing timestamps of ``n`` samples as float64 seconds.

    datetime64/timedelta64 count from the first sample (see the module
    docstring); numbers are taken as seconds.

    Returns
    -------
    ndarray, shape (n,), C-contiguous float64
    """
    values = np.asarray(getattr(timestamps, "values", timestamps))
    if values.dtype.kind not in "iufbMm":
        raise ValueError(
            f"{name} must be numbers or datetime64, got dtype {values.dtype}"
        )
    if values.ndim != 1 or values.shape[0] != n:
        raise ValueError(
            f"{name} must be one-dimensional with one entry per sample ({n}), "
            f"got shape {values.shape}"
        )
    return as_track(values, name, copy=False).base


def _raw_seconds(values: np.ndarray, origin: int | None) -> tuple[np.ndarray, int]:
    """Seconds from ``origin`` (default: the first value); NaT becomes NaN."""
    unit = "datetime64[ns]" if values.dtype.kind == "M" else "timedelta64[ns]"
    key = values.astype(unit, copy=False).view(np.int64).reshape(-1)
    view = read_only(key)
    if view is None:
        view = read_only(np.array(key, order="C"))  # the kernel's one layout
    if origin is None:
        origin = int(key[0]) if key.size and key[0] != _NAT else 0
    return seconds_since(view, origin).reshape(values.shape), origin


def seconds_pair(
    t_in: Any, t_out: Any, names: tuple[str, str] = ("t_in", "t_out")
) -> tuple[np.ndarray, np.ndarray]:
    """Two time arrays as float64 seconds from one reference (``t_in[0]``).

    Numbers are taken as they are; datetime64/timedelta64 are converted
    exactly as in :class:`Track`. Nothing else is checked here (NaT becomes
    NaN): the caller checks order and finiteness as its rules need. Mixed
    kinds raise.
    """
    a = np.asarray(getattr(t_in, "values", t_in))
    b = np.asarray(getattr(t_out, "values", t_out))
    kinds = {_KINDS.get(a.dtype.kind, "numeric"), _KINDS.get(b.dtype.kind, "numeric")}
    if len(kinds) > 1:
        raise ValueError(
            f"{names[0]} and {names[1]} must both be datetimes or both be numbers, "
            f"got dtypes {a.dtype} and {b.dtype}"
        )
    if kinds == {"numeric"}:
        for arr, name in ((a, names[0]), (b, names[1])):
            if arr.dtype.kind not in "iufb":
                raise ValueError(f"{name} must be numeric, got dtype {arr.dtype}")
        return kernel_array(a), kernel_array(b)
    sa, origin = _raw_seconds(a, None)
    sb, _ = _raw_seconds(b, origin)
    return sa, sb
