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

The widget is a facade over three parts: ``timeseries_panels`` (each panel's
samples and the options, checked), ``timeseries_rows`` (a panel's rows in a
window, as the bytes sent) and ``timeseries_requests`` (the browser's
requests and the replies).
"""

from __future__ import annotations

from collections.abc import Mapping

import anywidget
import numpy as np
import traitlets
from ipywidgets import Widget, widget_serialization

from .._engine.time import TIE, TimeBase, check_compatible
from ._decimate import GAP_FACTOR as GAP_FACTOR  # re-exported: the docs name it here
from ._decimate import Cancelled
from ._frontend import FrontendGuard
from ._latest_only import LatestOnly
from ._timebase import format_time
from .player import bundle
from .timeseries_panels import PANEL_HEIGHT as PANEL_HEIGHT  # documented here before
from .timeseries_panels import WIDTH_RANGE as WIDTH_RANGE  # documented here before
from .timeseries_panels import (
    PanelSamples,
    checked_gap,
    checked_max_points,
    checked_panel_height,
    checked_width,
)
from .timeseries_requests import exact_reply, exact_time, window_reply, window_request
from .timeseries_rows import COLORS as COLORS  # documented here before
from .timeseries_rows import (
    OVERVIEW_WIDTH,
    WINDOW_POINTS,
    float64_bytes,
    nearest_row,
    panel_of,
    pauses_of,
    rows_in_view,
)


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
        gap = checked_gap(gap)
        self._max_points = checked_max_points(max_points)
        self._overview_width = checked_width(overview_width, "overview_width")
        panel_height = checked_panel_height(panel_height)
        self._series = [PanelSamples(str(k), v) for k, v in series.items()]
        check_compatible([s.kind for s in self._series], "TimeSeries: series")
        self.timestamps_kind = self._series[0].kind
        self._gap = gap
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
            pauses, used = pauses_of(s, self._gap)
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
            panels.append(panel_of(s, reduced))
            x_bytes, y_bytes = float64_bytes(x, y)
            data.append({"x": x_bytes, "y": y_bytes})
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
        """Panel rows shown in ``[start, end]`` (data seconds), one each side
        (:func:`~rbm_nb.widgets.timeseries_rows.rows_in_view`)."""
        return rows_in_view(
            self._series[panel],
            self._pauses[panel],
            self._data_base,
            start,
            end,
            width,
            self._max_points,
            cancelled,
        )

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
        width = checked_width(self._overview_width if width is None else width, "width")
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
        request = window_request(content, self._overview_width)
        if request is None:
            return  # a malformed request from the page: nothing to draw, no reply
        start, end, width, view = request
        shift = self.x_shift

        def job(cancelled):
            return self._window_rows(start, end, width, cancelled)

        def done(result):
            reply, buffers = window_reply(
                content, view, start, end, width, shift, result
            )
            self.send(reply, buffers=buffers)

        self._last_request = self._windows.submit(view, job, done)

    def _on_exact_request(self, content: dict) -> None:
        """Queue a browser's request for the recording's samples at its cursor.

        The request carries only a time (seconds of the axis); anything else
        is the kernel's. A time that is not a finite number gets no reply. A
        newer request from the same view cancels this one in the kernel.
        """
        t = exact_time(content)
        if t is None:
            return
        shift = self.x_shift
        view = str(content.get("view", ""))

        def job(cancelled):
            return self._nearest_in_data(t - shift)

        def done(result):
            reply, buffers = exact_reply(content, view, t, shift, result)
            self.send(reply, buffers=buffers)

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
        return [nearest_row(s, self._data_base, t) for s in self._series]

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
