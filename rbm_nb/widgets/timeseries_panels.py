"""What a ``TimeSeries`` is given, checked: each panel's samples and the options.

A panel comes as a DataArray with a ``time`` dimension or a ``(timestamps,
values[, component_names])`` tuple; :class:`PanelSamples` holds it without a
copy (the caller's arrays, as views) with its timestamps as exact keys to
search, and finds the rows of a time window. The checks of the widget's
numeric options name the option and what was expected.
"""

from __future__ import annotations

import math

import numpy as np

from .._engine.time import TimeBase, as_track

#: bounds of a view's pixel width in a request
WIDTH_RANGE = (10, 20_000)


class PanelSamples:
    """One panel: raw timestamps, values (n, k), component names and units.

    ``values`` and ``timestamps`` are the caller's arrays whenever they are
    already float64 / datetime64[ns] (no copy); ``raw`` is the timestamps as
    numbers to search (int64 ns, a view, or float seconds).
    """

    def __init__(self, label: str, source):
        self.label = label
        if isinstance(source, tuple):
            if len(source) not in (2, 3):
                raise ValueError(
                    f"TimeSeries: series {label!r} must be a DataArray or a "
                    f"(timestamps, values[, component_names]) tuple, got a tuple "
                    f"of {len(source)}"
                )
            timestamps, values = source[0], np.asarray(source[1], dtype=float)
            components = [str(c) for c in source[2]] if len(source) == 3 else None
            self.units = ""
        else:
            if "time" not in getattr(source, "dims", ()):
                raise ValueError(
                    f"TimeSeries: series {label!r} must be a DataArray with a "
                    f"'time' dimension, got {type(source).__name__}"
                )
            if source.ndim > 2:
                raise ValueError(
                    f"TimeSeries: series {label!r} has dims {source.dims}; expected "
                    "'time' and at most one other dimension"
                )
            source = source.transpose("time", ...)
            timestamps = source["time"].values
            values = np.asarray(source.values, dtype=float)
            other = [d for d in source.dims if d != "time"]
            if other and other[0] in source.coords:
                components = [str(c) for c in source[other[0]].values]
            elif other:
                components = [f"{other[0]} {i}" for i in range(source.shape[1])]
            else:
                components = None
            self.units = str(source.attrs.get("units", ""))
        # validated (1-d, finite, sorted, no NaT) by the one time rule; its
        # exact keys (int64 ns for datetime64) are what is searched, so
        # datetime64 data is re-based exactly
        track = as_track(
            timestamps, f"timestamps of series {label!r}", copy=False, repeats=True
        )
        self.kind = track.kind
        self.raw = track.key
        self.timestamps = (
            track.values
            if track.kind == "numeric"
            else track.key.view(f"{track.kind}[ns]")
        )
        n = self.raw.size
        if values.ndim not in (1, 2) or values.shape[0] != n:
            raise ValueError(
                f"TimeSeries: series {label!r} has values of shape {values.shape}, "
                f"expected ({n},) or ({n}, k)"
            )
        if values.ndim == 1:
            values = values[:, None]
        if components is not None and len(components) != values.shape[1]:
            raise ValueError(
                f"TimeSeries: series {label!r} has {values.shape[1]} columns but "
                f"{len(components)} component names"
            )
        self.values = values
        self.components = components or [label]
        # a DataArray may name its components' colours (attrs["colors"], one
        # CSS colour per component), so a plot matches the 3D view's
        attrs = getattr(source, "attrs", {})
        colors = attrs.get("colors")
        self.colors = (
            [str(c) for c in colors]
            if isinstance(colors, (list, tuple)) and len(colors) == values.shape[1]
            else None
        )
        # and the longest pause its samples bridge (seconds): longer ones are
        # gaps, drawn without a NaN row stored in the series
        self.max_gap = checked_max_gap(attrs.get("max_gap"), label)

    def raw_of(self, base: TimeBase, t: float, side: str) -> int | float:
        """``t`` seconds of ``base`` in raw units (ns rounded outward by ``side``)."""
        if self.kind != "numeric":
            ns = t * 1e9
            return (base.t0_ns or 0) + int(
                math.floor(ns) if side == "high" else math.ceil(ns)
            )
        return base.t0_s + t

    def rows_in(self, base: TimeBase, start: float, end: float) -> tuple[int, int]:
        """Rows ``i0:i1`` shown in ``[start, end]`` (seconds of ``base``) and one each side."""
        lo, hi = self.raw_of(base, start, "low"), self.raw_of(base, end, "high")
        i0 = max(int(np.searchsorted(self.raw, lo, side="left")) - 1, 0)
        i1 = min(int(np.searchsorted(self.raw, hi, side="right")) + 1, self.raw.size)
        return i0, i1


def checked_max_gap(value, label: str) -> float | None:
    if value is None:
        return None
    if isinstance(value, bool) or not 0 < number(value) < math.inf:
        raise ValueError(
            f"TimeSeries: series {label!r} has attrs['max_gap'] = {value!r}; expected "
            "a positive number of seconds"
        )
    return float(value)


#: bounds of a panel's height in pixels
PANEL_HEIGHT = (40, 4000)


def number(value) -> float:
    """``value`` as a float, or NaN when it is not a number (then refused by name)."""
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def checked_panel_height(value) -> int:
    """``value`` as a panel height in pixels, or a ValueError naming panel_height."""
    low, high = PANEL_HEIGHT
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, float, np.integer, np.floating))
        or not np.isfinite(value)
        or int(value) != value
        or not low <= value <= high
    ):
        raise ValueError(
            f"TimeSeries: panel_height must be a whole number of pixels in "
            f"[{low}, {high}], got {value!r}"
        )
    return int(value)


def checked_width(value, name: str) -> int:
    """``value`` as a number of pixel columns, or a ValueError naming ``name``."""
    low, high = WIDTH_RANGE
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, float, np.integer, np.floating))
        or not np.isfinite(value)
        or not low <= value <= high
    ):
        raise ValueError(
            f"TimeSeries: {name} must be a number of pixel columns in "
            f"[{low}, {high}], got {value!r}"
        )
    return int(value)


def checked_max_points(max_points) -> int | None:
    """``max_points`` as an int >= 10 (None stays None), or a ValueError."""
    if max_points is not None and (
        isinstance(max_points, bool)
        or not isinstance(max_points, (int, float, np.integer, np.floating))
        or not np.isfinite(max_points)
        or int(max_points) != max_points
        or max_points < 10
    ):
        raise ValueError(
            f"TimeSeries: max_points must be an integer >= 10, got {max_points!r}"
        )
    return None if max_points is None else int(max_points)


def checked_gap(gap) -> float | None:
    """``gap`` as positive seconds (None stays None), or a ValueError."""
    if gap is not None and not (number(gap) > 0):
        raise ValueError(
            f"TimeSeries: gap must be a positive number of seconds, got {gap}"
        )
    return None if gap is None else float(gap)
