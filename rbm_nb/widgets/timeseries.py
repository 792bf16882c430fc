"""An interactive time-series plot (uPlot in the browser) sharing the Player's time.

The samples go to the browser once, as binary buffers over the widget comm
(x as float64 seconds from the recording's start, values as float64, so the
browser shows what the kernel reads out: 1e300 stays finite, millimetre steps
on 5e6 stay apart); zoom, pan, hover values, click-to-seek and the cursor all run in the browser
(``js/src/timeseries.js``). The cursor listens to the linked Player's ``time``
in the browser, so it keeps following playback while the kernel is busy.

Gaps are drawn as gaps: NaN values break the line, and so does a pause in the
timestamps longer than ``gap``, or than a series' own ``attrs["max_gap"]``
(a NaN row is inserted there before sending; the series is not changed).

A panel longer than ``max_points`` rows goes as its min/max (M4) overview at
``overview_width`` pixel columns (``_decimate.py``): only recorded samples,
per column the first, last, each component's extremes and first missing one,
so it draws exactly as the full series would at that width, and its bytes do
not grow with the recording. A view of another width asks for an overview at
its own width; a zoom asks the kernel for the samples in view (a custom comm
message answered with binary buffers): every sample when there are at most
``WINDOW_POINTS``, else their M4 at the view's width. Requests are computed on
a worker thread (``_latest_only.py``), and a newer request from the same view
cancels the older ones in the kernel (skipped, or stopped between steps); the
browser keeps the latest answers.

The readout under the mouse shows the recording's own sample nearest the
cursor's time. Where the browser holds every sample (a short panel, a zoomed
window at full resolution) it reads its own; over an overview it marks the
kept sample it has with "≈" and asks the kernel (an ``exact`` comm message
carrying only the time, latest-only on its own worker, cached in the page),
which answers from the full series (:meth:`TimeSeries.nearest_samples`).

The kernel holds no copy of a series: values and timestamps are the caller's
arrays (views), pauses in the timestamps are kept as row numbers, and seconds
are computed only for the rows that are sent.

Each sample is sent once. Linking a Player later (or any change of time base:
the eye clock of the example starts 0.7 ms before the head's) sends only the
new second 0 and ``x_shift``, the seconds the browser adds to the x it already
holds, never the samples again.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import anywidget
import numpy as np
import traitlets
from ipywidgets import Widget, widget_serialization

from .._engine.time import TIE, TimeBase, as_track, check_compatible
from ._decimate import GAP_FACTOR as GAP_FACTOR  # re-exported: the docs name it here
from ._decimate import Cancelled, gathered, m4_rows, pause_rows, pause_sides
from ._frontend import FrontendGuard
from ._latest_only import LatestOnly
from ._timebase import format_time
from .player import bundle

#: Line colours of a panel's components, in order (matplotlib's tab10).
COLORS = (
    "#1f77b4",
    "#ff7f0e",
    "#2ca02c",
    "#d62728",
    "#9467bd",
    "#8c564b",
    "#e377c2",
    "#7f7f7f",
    "#bcbd22",
    "#17becf",
)
#: A zoomed view gets every sample in view when a panel has at most this many
#: there (or ``max_points``, if larger): a minute of 340 Hz eye data, 0.16 MB
#: per component; more than that comes as their M4 at the view's width (which
#: draws the same). Also the default ``max_points``.
WINDOW_POINTS = 20_000
#: Pixel columns of the overview sent with the widget (a view of another width
#: asks for its own): about a notebook's plot width.
OVERVIEW_WIDTH = 1000
#: bounds of a view's pixel width in a request
WIDTH_RANGE = (10, 20_000)


class _Series:
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
        self.max_gap = _max_gap(attrs.get("max_gap"), label)

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


def _max_gap(value, label: str) -> float | None:
    if value is None:
        return None
    if isinstance(value, bool) or not 0 < _number(value) < math.inf:
        raise ValueError(
            f"TimeSeries: series {label!r} has attrs['max_gap'] = {value!r}; expected "
            "a positive number of seconds"
        )
    return float(value)


#: bounds of a panel's height in pixels
PANEL_HEIGHT = (40, 4000)


def _number(value) -> float:
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


class TimeSeries(FrontendGuard, anywidget.AnyWidget):
    """Stacked time-series panels with zoom, hover values and click-to-seek.

    Parameters
    ----------
    series : mapping of str to DataArray or tuple
        One panel per entry. A DataArray needs a ``time`` dimension (and at
        most one other, whose coordinate labels the lines; ``units`` in its
        attrs label the axis). A tuple is ``(timestamps, values)`` or
        ``(timestamps, values, component_names)`` with values of shape (n,) or
        (n, k). Timestamps are float seconds or datetime64, the same kind for
        every series.
    player : Player, optional
        The cursor follows this player's ``time`` and clicks seek it. Any
        widget with ``time`` (seconds from the start) and ``t0_ns`` traits
        works.
    panel_height : int, default 150
        Height of each panel in pixels (the width follows the notebook).
    title : str, optional
    gap : float, optional
        Pauses in the timestamps longer than this (seconds) are drawn as gaps.
        Default: ``GAP_FACTOR`` times each panel's median sample interval.
        ``numpy.inf`` joins every pause. A DataArray whose ``attrs["max_gap"]``
        (seconds) is shorter has its longer pauses drawn as gaps too (the
        explorer's gaze series say so instead of storing a NaN row in each).
    max_points : int or None, default ``WINDOW_POINTS``
        A panel with more samples than this goes as its min/max overview at
        ``overview_width`` pixel columns (per column: its first and last
        sample, each component's minimum and maximum and first missing one;
        recorded samples only, so it draws as the full series does at that
        width), and zooming in fetches the samples in view from the kernel.
        None: every sample, whatever the length.
    overview_width : int, default ``OVERVIEW_WIDTH``
        Pixel columns of the overview sent with the widget; a view of another
        width asks the kernel for an overview at its own width.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(0.0, 10.0, 0.5)
    >>> plot = TimeSeries({"speed": (t, np.ones_like(t))})
    >>> plot.set_time(5.0)
    >>> plot.readout()
    't = 5.000 s   speed: 1'
    """

    # the browser seeks and zooms; the data, panels and time base are the kernel's
    _frontend_settable = frozenset({"time", "x_range"})

    _esm = traitlets.Unicode("", help="The bundle js/src/timeseries.js.").tag(sync=True)

    panels = traitlets.List(
        traitlets.Dict(), help="label, units, components, colors of each panel."
    ).tag(sync=True)
    data = traitlets.List(
        traitlets.Dict(),
        help="Per panel: x (float64 bytes) and y (float64 bytes each).",
    ).tag(sync=True)
    t0_ns = traitlets.Int(
        None,
        allow_none=True,
        help="Absolute ns of second 0 (datetime64 data), or None.",
    ).tag(sync=True)
    x_shift = traitlets.Float(
        0.0,
        help="Seconds the browser adds to the sent x: the data went in one time "
        "base, the axis shows another (a Player linked later).",
    ).tag(sync=True)
    time = traitlets.Float(
        0.0, help="Cursor time in seconds from the start, when no player is linked."
    ).tag(sync=True)
    x_range = traitlets.List(
        traitlets.Float(), help="Shown time range [start, end] in seconds; [] = all."
    ).tag(sync=True)
    player = traitlets.Instance(
        Widget, allow_none=True, help="The Player the cursor follows."
    ).tag(sync=True, **widget_serialization)
    panel_height = traitlets.Int(150, help="Height of each panel in pixels.").tag(
        sync=True
    )
    title = traitlets.Unicode("", help="Title above the panels.").tag(sync=True)
    overview_width = traitlets.Int(
        OVERVIEW_WIDTH,
        help="Pixel columns of the min/max overview sent with the widget (panels "
        "longer than max_points); a view of another width asks for its own.",
    ).tag(sync=True)
    detail = traitlets.Bool(
        False,
        help="Whether a zoom fetches the samples in view from the kernel "
        "(a panel was sent as its min/max overview: longer than max_points).",
    ).tag(sync=True)

    def __init__(
        self,
        series: Mapping,
        *,
        player=None,
        panel_height: int = 150,
        title: str | None = None,
        gap: float | None = None,
        max_points: int | None = WINDOW_POINTS,
        overview_width: int = OVERVIEW_WIDTH,
    ):
        if not isinstance(series, Mapping) or not series:
            raise ValueError(
                "TimeSeries: series must be a non-empty mapping of label -> "
                f"DataArray or (timestamps, values), got {type(series).__name__}"
            )
        if gap is not None and not (_number(gap) > 0):
            raise ValueError(
                f"TimeSeries: gap must be a positive number of seconds, got {gap}"
            )
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
        self._max_points = None if max_points is None else int(max_points)
        self._overview_width = self._checked_width(overview_width, "overview_width")
        panel_height = checked_panel_height(panel_height)
        self._series = [_Series(str(k), v) for k, v in series.items()]
        check_compatible([s.kind for s in self._series], "TimeSeries: series")
        self.timestamps_kind = self._series[0].kind
        self._gap = None if gap is None else float(gap)
        self.gaps: list[float | None] = []
        first = min((s.timestamps[:1] for s in self._series), key=lambda a: a[0])
        self._own_base = self._base = TimeBase.of(first)
        if player is not None:
            # checked here, before the samples are encoded in its time base
            self._valid_player({"value": player})
            self._base = self._base_of(player)
        # the samples go in the comm's open message, in the player's time base,
        # so linking the player below changes nothing that was sent
        self._data_base = self._base
        self._pauses: list[np.ndarray] = []
        self._windows = LatestOnly("rbm-timeseries-window")
        # the cursor's exact values: their own worker, so a long window job
        # never holds up the readout
        self._exact = LatestOnly("rbm-timeseries-exact")
        encoded = self._encoded()
        super().__init__(
            _esm=bundle("timeseries"),
            panel_height=int(panel_height),
            title=title or "",
            detail=any(p["reduced"] for p in encoded["panels"]),
            overview_width=self._overview_width,
            **encoded,
        )
        self.on_msg(self._on_message)
        if player is not None:
            self.player = player

    # -- data to the browser ---------------------------------------------------
    def _encoded(self) -> dict:
        """``t0_ns``, ``panels`` and ``data`` in the data's time base."""
        panels, data, self.gaps, self._pauses = [], [], [], []
        for s in self._series:
            gap = self._gap
            if gap is not None and s.kind != "numeric":
                gap *= 1e9  # raw units: ns
            pauses, used = pause_rows(s.raw, gap)
            if s.max_gap is not None:
                limit = s.max_gap * (1.0 if s.kind == "numeric" else 1e9)
                if used is None or limit < used:
                    # the series bridges no pause longer than its own max_gap
                    pauses, used = pause_rows(s.raw, limit)
            if used is not None and s.kind != "numeric":
                used /= 1e9
            self._pauses.append(pauses)
            self.gaps.append(used)
            reduced = self._max_points is not None and s.raw.size > self._max_points
            first = self._data_base.seconds(s.timestamps[:1])[0]
            last = self._data_base.seconds(s.timestamps[-1:])[0]
            x, y, _ = self._rows(
                len(self._pauses) - 1,
                first,
                last,
                self._overview_width if reduced else None,
            )
            panels.append(
                {
                    "label": s.label,
                    "units": s.units,
                    "components": s.components,
                    "colors": s.colors
                    or [COLORS[i % len(COLORS)] for i in range(len(s.components))],
                    "samples": int(s.raw.size),
                    "reduced": bool(reduced),
                }
            )
            data.append(
                {
                    "x": np.ascontiguousarray(x, dtype=np.float64).tobytes(),
                    "y": [
                        np.ascontiguousarray(y[:, k], dtype=np.float64).tobytes()
                        for k in range(y.shape[1])
                    ],
                }
            )
        t0_ns = self._data_base.t0_ns if self._data_base.absolute else None
        return {"t0_ns": t0_ns, "panels": panels, "data": data}

    def _rows(
        self,
        panel: int,
        start: float,
        end: float,
        width: int | None,
        cancelled=lambda: False,
    ) -> tuple[np.ndarray, np.ndarray, bool]:
        """Panel rows shown in ``[start, end]`` (data seconds), one each side.

        Every row when ``width`` is None or there are at most ``WINDOW_POINTS``
        (or ``max_points``), else their M4 at ``width`` columns. Returns x (data
        seconds), y (m, k) with a NaN row in each visible pause, and whether
        every row is there.
        """
        s = self._series[panel]
        i0, i1 = s.rows_in(self._data_base, start, end)
        limit = max(WINDOW_POINTS, self._max_points or 0)
        raw, values = s.raw[i0:i1], s.values[i0:i1]
        pauses = self._pauses[panel]
        pauses = pauses[(pauses >= i0) & (pauses < i1)] - i0
        if width is None or i1 - i0 <= limit:
            rows = np.arange(i1 - i0)
            full = True
        else:
            lo = float(s.raw_of(self._data_base, start, "low"))
            hi = float(max(s.raw_of(self._data_base, end, "high"), lo + 1))
            rows = m4_rows(raw, values, lo, hi, width, cancelled)
            # each column's first pause with both its sides: drawn as a gap
            rows = np.union1d(rows, pause_sides(raw, pauses, lo, hi, width))
            full = False
        x = self._data_base.seconds(s.timestamps[i0:i1][rows])
        return (*gathered(x, values, rows, pauses), full)

    def window(
        self, start: float, end: float, width: int | None = None
    ) -> list[tuple[np.ndarray, np.ndarray]]:
        """Each panel's rows shown in ``[start, end]`` seconds of the axis.

        The rows in the window and one on each side (so the line runs to the
        edges): every one when they are at most ``WINDOW_POINTS`` (or
        ``max_points``, if larger), else their M4 at ``width`` pixel columns
        (default ``overview_width``); x in the data's time base (as the
        overview was sent), a NaN row in each pause.
        """
        start, end = float(start), float(end)
        if not (np.isfinite(start) and np.isfinite(end) and start < end):
            raise ValueError(
                f"TimeSeries.window: need finite start < end in seconds, got {start}, {end}"
            )
        width = self._checked_width(
            self._overview_width if width is None else width, "width"
        )
        return self._window_rows(start, end, width)[0]

    def _window_rows(self, start, end, width, cancelled=lambda: False):
        lo, hi = start - self.x_shift, end - self.x_shift
        out, full = [], []
        for panel in range(len(self._series)):
            if cancelled():
                raise Cancelled
            x, y, every = self._rows(panel, lo, hi, width, cancelled)
            out.append((x, y))
            full.append(every)
        return out, full

    @staticmethod
    def _checked_width(value, name: str) -> int:
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

    def _on_message(self, _widget, content, _buffers) -> None:
        """Queue a browser's request for the samples in view (answered off-thread).

        A newer request from the same view cancels this one in the kernel.
        """
        if not isinstance(content, dict):
            return
        if content.get("type") == "exact":
            self._on_exact_request(content)
            return
        if content.get("type") != "window":
            return
        start, end = _number(content.get("start")), _number(content.get("end"))
        width = content.get("width", self._overview_width)
        try:
            width = self._checked_width(width, "width")
        except ValueError:
            return  # a malformed request from the page: nothing to draw, no reply
        if not (np.isfinite(start) and np.isfinite(end) and start < end):
            return
        shift = self.x_shift
        view = str(content.get("view", ""))

        def job(cancelled):
            return self._window_rows(start, end, width, cancelled)

        def done(result):
            rows, full = result
            buffers: list[bytes] = []
            for x, y in rows:
                buffers.append(np.ascontiguousarray(x, dtype=np.float64).tobytes())
                buffers.extend(
                    np.ascontiguousarray(y[:, k], dtype=np.float64).tobytes()
                    for k in range(y.shape[1])
                )
            reply = {
                "type": "window",
                "id": content.get("id"),
                "view": view,
                "start": start,
                "end": end,
                "width": width,
                "shift": shift,
                "rows": [int(x.size) for x, _ in rows],
                "full": full,
                "whole": bool(content.get("whole")),
            }
            self.send(reply, buffers=buffers)

        self._last_request = self._windows.submit(view, job, done)

    def _on_exact_request(self, content: dict) -> None:
        """Queue a browser's request for the recording's samples at its cursor.

        The request carries only a time (seconds of the axis); anything else
        is the kernel's. A time that is not a finite number gets no reply. A
        newer request from the same view cancels this one in the kernel.
        """
        t = content.get("t")
        if (
            isinstance(t, bool)
            or not isinstance(t, (int, float))
            or not math.isfinite(t)
        ):
            return
        t = float(t)
        shift = self.x_shift
        view = str(content.get("view", ""))

        def job(cancelled):
            return self._nearest_in_data(t - shift)

        def done(result):
            buffers = [
                np.asarray([x, *values], dtype=np.float64).tobytes()
                for x, values in result
            ]
            self.send(
                {
                    "type": "exact",
                    "id": content.get("id"),
                    "view": view,
                    "t": t,
                    "shift": shift,
                },
                buffers=buffers,
            )

        self._last_exact = self._exact.submit(view, job, done)

    def nearest_samples(self, t: float | None = None) -> dict:
        """The recorded sample nearest ``t`` of every panel, and its time.

        What the cursor's readout shows in the browser: the recording's own
        sample (never one of a decimated overview), read from the full series.

        Parameters
        ----------
        t : float, optional
            Seconds of the axis; default the cursor's time.

        Returns
        -------
        dict of str to (float, ndarray of shape (k,))
            Per panel, the sample's time in seconds of the axis and its values
            (NaN where the recording has none). The earlier sample wins a tie.
        """
        t = self.current_time if t is None else self._seconds(t)
        shift = self.x_shift
        return {
            s.label: (x + shift, values)
            for s, (x, values) in zip(
                self._series, self._nearest_in_data(t - shift), strict=True
            )
        }

    def _nearest_in_data(self, t: float) -> list[tuple[float, np.ndarray]]:
        """Per panel: (seconds of the data's base, values) of the row nearest ``t``."""
        out = []
        for s in self._series:
            first = float(self._data_base.seconds(s.timestamps[:1])[0])
            last = float(self._data_base.seconds(s.timestamps[-1:])[0])
            # past either end the end row is the nearest; clamping also keeps
            # a huge time from overflowing the ns arithmetic
            at = min(max(t, first), last)
            lo = s.raw_of(self._data_base, at, "low")
            i = int(np.searchsorted(s.raw, lo, side="left"))
            if i >= s.raw.size or (
                i > 0
                and float(self._data_base.seconds(s.timestamps[i - 1 : i])[0])
                >= 2 * at - float(self._data_base.seconds(s.timestamps[i : i + 1])[0])
            ):
                i -= 1
            x = float(self._data_base.seconds(s.timestamps[i : i + 1])[0])
            out.append((x, np.array(s.values[i], dtype=np.float64)))
        return out

    @property
    def window_requests(self) -> dict:
        """Window requests answered and cancelled in the kernel so far."""
        return {
            "answered": self._windows.answered,
            "cancelled": self._windows.cancelled,
        }

    def close(self) -> None:
        for name in ("_windows", "_exact"):
            worker = getattr(self, name, None)  # None: the constructor failed
            if worker is not None:
                worker.close()
        super().close()

    def _shift_to(self, base: TimeBase) -> float:
        """Seconds from ``base``'s second 0 to the data's: what the browser adds."""
        return self._data_base.shift_to(base)

    @traitlets.validate("time")
    def _valid_time(self, proposal):
        value = float(proposal["value"])
        if not np.isfinite(value):
            raise traitlets.TraitError(f"TimeSeries.time must be finite, got {value}")
        return value

    @traitlets.validate("x_range")
    def _valid_x_range(self, proposal):
        value = list(proposal["value"])
        if value and not (
            len(value) == 2
            and all(np.isfinite(v) for v in value)
            and value[0] < value[1]
        ):
            raise traitlets.TraitError(
                "TimeSeries.x_range must be [] or [start, end] with finite "
                f"start < end (seconds), got {value}"
            )
        return value

    @traitlets.validate("panel_height")
    def _valid_panel_height(self, proposal):
        try:
            return checked_panel_height(proposal["value"])
        except ValueError as err:
            raise traitlets.TraitError(str(err)) from None

    @traitlets.validate("player")
    def _valid_player(self, proposal):
        player = proposal["value"]
        if player is not None and not (
            player.has_trait("time") and player.has_trait("t0_ns")
        ):
            raise traitlets.TraitError(
                "TimeSeries.player must be a Player (a widget with 'time' and "
                f"'t0_ns' traits), got {type(player).__name__}"
            )
        if player is not None:
            try:
                check_compatible(
                    [self.timestamps_kind, self._base_of(player)], "TimeSeries.player"
                )
            except ValueError as err:
                raise traitlets.TraitError(str(err)) from None
        return player

    def _base_of(self, player) -> TimeBase:
        """Second 0 of the axis when following ``player`` (None: the series')."""
        if player is None:
            return self._own_base
        base = getattr(player, "timebase", None)
        if isinstance(base, TimeBase):
            return base
        if player.t0_ns is not None:
            return TimeBase(t0_ns=int(player.t0_ns))
        # a Player on float seconds starts at its first timestamp; the player
        # tells which when it can, else the series' own start
        t0_s = getattr(player, "t0_s", None)
        return TimeBase(t0_s=float(t0_s)) if t0_s is not None else self._own_base

    @traitlets.observe("player")
    def _on_player(self, change) -> None:
        base = self._base_of(change["new"])
        if base != self._base:
            self._base = base
            # the browser shifts the x it holds: the samples are not sent again
            with self.hold_sync():
                self.x_shift = self._shift_to(base)
                self.t0_ns = base.t0_ns if base.absolute else None

    # -- time ----------------------------------------------------------------
    @property
    def timebase(self) -> TimeBase:
        """Second 0 of the x axis."""
        return self._base

    @property
    def current_time(self) -> float:
        """The cursor's time (seconds from the start): the player's, if linked."""
        return float(self.player.time) if self.player is not None else float(self.time)

    def set_time(self, t) -> None:
        """Move the cursor (or the linked player) to ``t``.

        ``t`` is seconds from the start, or a datetime64 value for datetime
        data.
        """
        target = self.player if self.player is not None else self
        target.time = self._seconds(t)

    def _seconds(self, t) -> float:
        if isinstance(t, (np.datetime64, np.timedelta64)) or hasattr(
            t, "to_datetime64"
        ):
            try:
                return self._base.at(t, "t")
            except ValueError as err:
                raise ValueError(f"TimeSeries.set_time: {err}") from None
        value = float(t)
        if not np.isfinite(value):
            raise ValueError(f"TimeSeries.set_time: time must be finite, got {t}")
        return value

    def zoom(self, start: float | None = None, end: float | None = None) -> None:
        """Show ``[start, end]`` seconds (both None: everything)."""
        if start is None and end is None:
            self.x_range = []
            return
        if start is None or end is None or not float(start) < float(end):
            raise ValueError(
                f"TimeSeries.zoom: need start < end in seconds, got {start}, {end}"
            )
        self.x_range = [float(start), float(end)]

    # -- values at a time ------------------------------------------------------
    def values_at(self, t: float | None = None) -> dict:
        """The latest sample at or before ``t`` of every panel.

        Parameters
        ----------
        t : float, optional
            Seconds from the start; default the cursor's time.

        Returns
        -------
        dict of str to ndarray, shape (k,)
            Panels with no sample yet at ``t`` are left out.
        """
        t = self.current_time if t is None else self._seconds(t)
        out = {}
        for s in self._series:
            # searched in the raw stamps: no seconds array of the whole series
            at = self._base.key(t)  # exact: int ns rounded, or float
            if s.kind == "numeric":
                at += TIE
            idx = int(np.searchsorted(s.raw, at, side="right")) - 1
            if idx >= 0:
                out[s.label] = s.values[idx]
        return out

    def readout(self, t: float | None = None) -> str:
        """The time and the values at ``t`` as one line of text."""
        t = self.current_time if t is None else self._seconds(t)
        parts = [
            f"t = {format_time(t, self._base.t0_ns if self._base.absolute else None)}"
        ]
        values = self.values_at(t)
        for s in self._series:
            if s.label not in values:
                continue
            shown = ", ".join(
                f"{c} {v:.3g}" if len(s.components) > 1 else f"{v:.3g}"
                for c, v in zip(s.components, values[s.label], strict=True)
            )
            unit = f" {s.units}" if s.units else ""
            parts.append(f"{s.label}: {shown}{unit}")
        return "   ".join(parts)

    def __repr__(self) -> str:
        labels = ", ".join(s.label for s in self._series)
        return f"<TimeSeries [{labels}] time={self.current_time:.3f}>"
