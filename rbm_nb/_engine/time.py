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
times (a frame's or an array's samples); with ``repeats=True`` it accepts
repeated times but no step back (the notebook layer's plots and players of
data logged with repeated stamps); :func:`requested_times` accepts any
order and repeats (the times a caller asks a lookup at). Whatever is
computed, timestamps handed back are slices (or the sorted union) of the
original values, in their original dtype.

The notebook layer (widgets, scene, ROS transformer, studies) uses the same
rule and keeps the same exact keys, plus a :class:`TimeBase`: second 0 of a
view. Seconds from second 0 are computed from the keys (int64 subtraction
before any float), so two datetimes 1 ns apart stay two samples at any
epoch. Floats counted from the Unix epoch exist only where a value crosses
to JavaScript or to a caller that asked for one (``TimeBase.epoch``).
:func:`latest_index` is the one search for "the sample shown at a time":
a time within :data:`TIE` of a sample is that sample.
"""

from __future__ import annotations

import math
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
    "TimeBase",
    "latest_index",
    "TIE",
    "epoch_seconds",
    "ns_keys",
    "from_epoch_seconds",
    "time_key",
    "key_seconds",
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

    def epoch_seconds(self) -> np.ndarray:
        """The times as float data seconds (since the Unix epoch for datetime64).

        ~0.25 µs coarse at today's epochs: only for views whose axis is
        still counted from the epoch (see :func:`epoch_seconds`).
        """
        if self.kind == "numeric":
            return self.key
        return self.key / _NS_PER_S


def _first_unordered(key: np.ndarray, repeats: bool = False) -> int:
    """Index of the first key below (or, unless ``repeats``, equal to) its predecessor, or -1."""
    bad = np.flatnonzero(key[1:] < key[:-1] if repeats else key[1:] <= key[:-1])
    return int(bad[0]) + 1 if bad.size else -1


def _ordered_keys(
    values: np.ndarray, name: str, repeats: bool = False
) -> tuple[np.ndarray, str]:
    """:func:`_keys` of increasing times; raises naming the first fault.

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
    i = _first_unordered(key, repeats)
    if i >= 0:
        what = "a duplicate of" if key[i] == key[i - 1] else "earlier than"
        rule = "sorted (repeats allowed)" if repeats else "strictly increasing"
        raise ValueError(
            f"{name} must be {rule}: {name}[{i}] = {values[i]} is "
            f"{what} {name}[{i - 1}] = {values[i - 1]}"
        )
    return key, kind


def as_track(
    timestamps: Any,
    name: str = "timestamps",
    length: int | None = None,
    copy: bool = True,
    repeats: bool = False,
) -> Track:
    """Validate increasing timestamps and wrap them in a :class:`Track`.

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
    repeats : bool, default False
        Accept repeated times (non-decreasing). Frames and the core's arrays
        need strictly increasing times; plots and players of logged data may
        repeat a stamp (see the module docstring).

    Raises
    ------
    ValueError
        If the timestamps are not one-dimensional, not numeric or datetime64,
        empty, of the wrong length, contain NaN/inf/NaT, or are not strictly
        increasing (non-decreasing with ``repeats``; the message names the
        first offending index).
    """
    if isinstance(timestamps, Track) and length is None:
        if repeats or _first_unordered(timestamps.key) < 0:
            return timestamps
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
    key, kind = _ordered_keys(values, name, repeats)
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


def check_compatible(tracks: Any, what: str | None = None) -> None:
    """Raise if different kinds of time (numbers, datetime64, timedelta64) meet.

    ``tracks`` holds :class:`Track`, :class:`TimeBase` or kind names
    (``"numeric"``, ``"datetime64"``, ``"timedelta64"``); None is skipped.
    ``what`` (e.g. ``"link(Scene 'head')"``) starts the message.
    """
    kinds = sorted(
        {t if isinstance(t, str) else t.kind for t in tracks if t is not None}
    )
    if len(kinds) > 1:
        where = f"{what}: " if what else ""
        raise ValueError(
            f"{where}cannot match {kinds[0]} timestamps with {kinds[1]} timestamps; "
            f"convert one of them (e.g. numeric seconds since the first sample)"
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


#: Seconds within which a time is the sample it is compared with. Half a
#: nanosecond: keys in ns are integers, so a time rounded to the ns is
#: exact, and float times that went through JavaScript (or ``0.1 * 3``)
#: still find their sample.
TIE = 0.5e-9

# one time value of a user: pandas scalars carry their numpy twin
_SCALAR_DTYPES = ("to_datetime64", "to_timedelta64")


def _scalar(t: Any, name: str) -> tuple[Any, str]:
    """One time value as a numpy scalar and its kind; refuses NaT, NaN, inf."""
    for method in _SCALAR_DTYPES:
        if hasattr(t, method):
            t = getattr(t, method)()
            break
    arr = np.asarray(t)
    if arr.ndim != 0 and arr.size != 1:
        raise ValueError(f"{name} must be one time, got shape {arr.shape}")
    arr = arr.reshape(1)
    if arr.dtype.kind in "mM" and np.isnat(arr[0]):
        raise ValueError(f"{name} is NaT; a time must be a valid date")
    if arr.dtype.kind in "fc" and not np.isfinite(arr[0]):
        raise ValueError(f"{name} is {arr[0]}; a time must be a finite number")
    key, kind = _keys(arr, name)
    return key[0], kind


class TimeBase:
    """Second 0 of a view: the exact key every time of the view counts from.

    Parameters
    ----------
    t0_ns : int, optional
        Second 0 in int64 nanoseconds (since the Unix epoch for datetime64
        data, since zero for timedelta64 data).
    t0_s : float, default 0.0
        Second 0 of numeric timestamps (ignored when ``t0_ns`` is given).
    elapsed : bool, default False
        Whether ``t0_ns`` counts a timedelta64 (no date to show).
    """

    __slots__ = ("t0_ns", "t0_s", "elapsed")

    def __init__(
        self, t0_ns: int | None = None, t0_s: float = 0.0, elapsed: bool = False
    ) -> None:
        self.t0_ns = None if t0_ns is None else int(t0_ns)
        self.t0_s = 0.0 if t0_ns is not None else float(t0_s)
        self.elapsed = bool(elapsed) and t0_ns is not None

    @classmethod
    def of(cls, timestamps: Any, name: str = "timestamps") -> TimeBase:
        """The time base whose second 0 is the earliest of ``timestamps``.

        ``timestamps`` is a :class:`Track` or anything :func:`as_track`
        accepts (validated with ``repeats=True``).
        """
        track = as_track(timestamps, name, copy=False, repeats=True)
        first = track.key[0]
        if track.kind == "numeric":
            return cls(t0_s=float(first))
        return cls(t0_ns=int(first), elapsed=track.kind == "timedelta64")

    @property
    def kind(self) -> str:
        """``"datetime64"``, ``"timedelta64"`` or ``"numeric"`` (as :class:`Track`)."""
        if self.t0_ns is None:
            return "numeric"
        return "timedelta64" if self.elapsed else "datetime64"

    @property
    def absolute(self) -> bool:
        """Whether second 0 is a date (datetime64 data)."""
        return self.kind == "datetime64"

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, TimeBase):
            return NotImplemented
        return (self.t0_ns, self.t0_s, self.elapsed) == (
            other.t0_ns,
            other.t0_s,
            other.elapsed,
        )

    def __hash__(self) -> int:
        return hash((self.t0_ns, self.t0_s, self.elapsed))

    def __repr__(self) -> str:
        if self.t0_ns is None:
            return f"TimeBase(t0_s={self.t0_s!r})"
        return f"TimeBase(t0_ns={self.t0_ns}{', elapsed=True' if self.elapsed else ''})"

    def seconds(self, timestamps: Any, name: str = "timestamps") -> np.ndarray:
        """Timestamps (a :class:`Track` or an array) as float64 seconds from second 0.

        ns keys are subtracted as int64 before the division, so nothing is
        lost to epoch-sized floats.
        """
        if isinstance(timestamps, Track):
            key, kind = timestamps.key, timestamps.kind
        else:
            arr = np.asarray(getattr(timestamps, "values", timestamps)).reshape(-1)
            key, kind = _keys(arr, name)
        check_compatible([self.kind, kind], name)
        if self.t0_ns is None:
            return np.asarray(key, dtype=np.float64) - self.t0_s
        return (key - self.t0_ns) / _NS_PER_S

    def at(self, t: Any, name: str = "time") -> float:
        """One time as seconds from second 0.

        ``t`` is of the data's kind (datetime64 or a pandas Timestamp for
        datetime data, timedelta64 for elapsed times, a number otherwise);
        a number for datetime data is taken as seconds since the Unix epoch
        (what :meth:`epoch` hands out).
        """
        key, kind = _scalar(t, name)
        if kind == "numeric" and self.t0_ns is not None:
            return float(key) - self.t0_ns / _NS_PER_S
        check_compatible([self.kind, kind], name)
        if self.t0_ns is None:
            return float(key) - self.t0_s
        return float(int(key) - self.t0_ns) / _NS_PER_S

    def key(self, t: float) -> int | float:
        """``t`` seconds from second 0 as an exact key (int ns, rounded; or float)."""
        if self.t0_ns is None:
            return self.t0_s + float(t)
        return self.t0_ns + round(float(t) * _NS_PER_S)

    def value(self, t: float) -> Any:
        """``t`` seconds from second 0 in the data's own kind (datetime64[ns] exact to the ns)."""
        if self.t0_ns is None:
            return self.t0_s + float(t)
        unit = "timedelta64" if self.elapsed else "datetime64"
        return np.array(self.key(t), dtype=np.int64).view(f"{unit}[ns]")[()]

    @property
    def origin(self) -> float:
        """Second 0 as float seconds (since the epoch for datetime data).

        Only for JavaScript and callers of :meth:`epoch`: ~0.25 µs coarse at
        today's epochs.
        """
        return self.t0_s if self.t0_ns is None else self.t0_ns / _NS_PER_S

    def epoch(self, t: float) -> float:
        """``t`` seconds from second 0 as float data seconds (``origin + t``)."""
        return self.origin + float(t)

    def shift_to(self, other: TimeBase) -> float:
        """Seconds from ``other``'s second 0 to this one's (exact for ns bases)."""
        check_compatible([self.kind, other.kind], "time bases")
        if self.t0_ns is not None and other.t0_ns is not None:
            return (self.t0_ns - other.t0_ns) / _NS_PER_S
        return self.t0_s - other.t0_s


def latest_index(track: Track, base: TimeBase, t: float) -> int:
    """Index of the latest sample of ``track`` at or before ``t`` seconds of ``base``.

    -1 before the first sample. A time within :data:`TIE` of a sample is
    that sample.
    """
    if track.kind == "numeric":
        at = base.key(t)
        return int(np.searchsorted(track.key, at + TIE, side="right")) - 1
    check_compatible([track.kind, base.kind], "time")
    ns = base.key(t)  # rounded to the ns: exact
    return int(np.searchsorted(track.key, ns, side="right")) - 1


def epoch_seconds(t: Any, kind: str | None = None, name: str = "time") -> Any:
    """Times as float data seconds (since the Unix epoch for datetime64).

    The door out to callers that asked for float epoch seconds (the
    tf2-style :class:`~rbm_nb.ros.transformer.Transformer`, whose API is
    tf2's; ``Scene.time``): ~0.25 µs coarse at today's epochs. Every view
    counts from exact keys and a :class:`TimeBase`; :func:`time_key` is the
    way back in.
    ``t`` is one time (returns a float) or an array in any order (returns
    float64 values); NaT, NaN and inf are refused naming the index. ``kind``
    is the kind of the data ``t`` is compared with (None: any); numbers are
    taken as data seconds whatever the kind.
    """
    values = np.asarray(getattr(t, "values", t))
    if values.ndim == 0:
        key, t_kind = _scalar(t, name)
        if t_kind == "numeric":
            return float(key)
        check_compatible([kind, t_kind], name)
        return int(key) / _NS_PER_S
    keys, t_kind = _keys(values, name)
    if t_kind == "numeric":
        return keys
    check_compatible([kind, t_kind], name)
    return keys / _NS_PER_S


def from_epoch_seconds(seconds: Any, kind: str) -> np.ndarray:
    """Float data seconds back to the data's kind (datetime64[ns] rounded to the ns)."""
    seconds = np.asarray(seconds, dtype=np.float64)
    if kind == "numeric":
        return seconds
    ns = np.round(seconds * _NS_PER_S).astype(np.int64)
    return ns.view(f"{kind}[ns]")


def sort_keys(values: Any, name: str = "timestamps") -> np.ndarray:
    """Exact sort keys of one-dimensional times, in any order.

    int64 nanoseconds for datetime64/timedelta64, float64 for numbers: the
    keys :class:`Track` orders by, for code that matches times without making
    a track of them. NaT, NaN, inf and other dtypes are refused naming
    ``name`` and the first offending index.
    """
    arr = np.asarray(getattr(values, "values", values))
    return _keys(arr, name)[0]


def ns_keys(values: Any, name: str = "timestamps") -> np.ndarray:
    """int64 nanoseconds of datetime64/timedelta64 values, in any order.

    For writers that store exact stamps (a ROS bag's sec/nsec). Refuses NaT
    and numbers, naming the argument.
    """
    arr = np.asarray(getattr(values, "values", values))
    key, kind = _keys(arr, name)
    if kind == "numeric":
        raise ValueError(
            f"{name} must be datetime64 or timedelta64, got dtype {arr.dtype}"
        )
    return key


# the ns keys a number of seconds may reach (NaT, the int64 minimum, excluded)
_KEY_RANGE = (int(_NAT) + 1, int(np.iinfo(np.int64).max))
_TWO_63 = 2.0**63


def time_key(t: Any, kind: str | None, name: str = "time") -> int | float:
    """One time as the exact key of data of ``kind``: where a time enters a view.

    ``kind`` is that of the data the time is compared with (a
    :class:`Track`'s). For ``"datetime64"``/``"timedelta64"`` data the key
    is int nanoseconds: a datetime64 (or pandas Timestamp) exactly; a number
    is float seconds since the epoch (what JavaScript and
    :func:`epoch_seconds` hand out), which stands for every nanosecond that
    rounds to it (~0.24 µs of them today, as :data:`TIE` for float seconds):
    its key is the last of them, so "the latest sample at or before" a
    sample's own epoch float is that sample. Kept within int64. For numeric
    data (or ``kind`` None) a number is its own key. NaT, NaN, inf and mixed
    kinds are refused naming ``name``.
    """
    key, t_kind = _scalar(t, name)
    if t_kind == "numeric":
        if kind is None or kind == "numeric":
            return float(key)
        low, high = _KEY_RANGE
        seconds = float(key)
        if not -_TWO_63 < seconds * _NS_PER_S < _TWO_63:  # beyond int64: its ends
            return high if seconds > 0 else low
        # whole seconds apart from the fraction: the nearest ns of the
        # float's exact value (``seconds * 1e9`` alone is 256 ns coarse
        # today), then the last ns of its half-ulp
        whole = math.floor(seconds)
        ns = whole * 1_000_000_000 + round((seconds - whole) * _NS_PER_S)
        ns += int(math.ulp(seconds) / 2 * _NS_PER_S)
        return min(max(ns, low), high)
    check_compatible([kind, t_kind], name)
    return int(key)


def key_seconds(key: Any, kind: str | None) -> Any:
    """Keys of data of ``kind`` as float data seconds (epoch seconds for datetime64).

    The other way of :func:`time_key`: for a value that leaves the exact
    world (a public float time, a message to JavaScript).
    """
    if kind is None or kind == "numeric":
        return np.asarray(key, dtype=np.float64)[()] if np.ndim(key) else float(key)
    if np.ndim(key):
        return np.asarray(key, dtype=np.int64) / _NS_PER_S
    return int(key) / _NS_PER_S
