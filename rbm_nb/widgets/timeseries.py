"""A time-series plot whose cursor follows a Player.

The plot is drawn once with matplotlib (Agg) into a PNG; only a thin cursor
overlaid on it moves as the player plays. Each step therefore sends a few
bytes (the cursor's position as a percentage) instead of a new image, so the
plot keeps up with any playback speed.
"""

from __future__ import annotations

import io
from collections.abc import Mapping

import ipywidgets as widgets
import numpy as np

from ._time import DATETIME, time_as_seconds, timestamps_as_seconds

CURSOR_COLOR = "#d62728"


class _Series:
    """One panel of the plot: timestamps as seconds, values (n, k), labels."""

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
            components = list(source[2]) if len(source) == 3 else None
            self.units = ""
        else:
            if "time" not in getattr(source, "dims", ()):
                raise ValueError(
                    f"TimeSeries: series {label!r} must be a DataArray with a "
                    f"'time' dimension, got {type(source).__name__}"
                )
            source = source.transpose("time", ...)
            timestamps = source["time"].values
            values = np.asarray(source.values, dtype=float)
            other = [d for d in source.dims if d != "time"]
            components = [str(c) for c in source[other[0]].values] if other else None
            self.units = str(source.attrs.get("units", ""))
        self.seconds, self.kind = timestamps_as_seconds(
            timestamps, f"timestamps of series {label!r}"
        )
        if values.ndim not in (1, 2) or values.shape[0] != self.seconds.size:
            raise ValueError(
                f"TimeSeries: series {label!r} has values of shape {values.shape}, "
                f"expected ({self.seconds.size},) or ({self.seconds.size}, k)"
            )
        if values.ndim == 1:
            values = values[:, None]
        if components is not None and len(components) != values.shape[1]:
            raise ValueError(
                f"TimeSeries: series {label!r} has {values.shape[1]} columns but "
                f"{len(components)} component names"
            )
        self.values = values
        self.components = components

    def value_at(self, t: float) -> np.ndarray | None:
        """The latest sample at or before ``t`` (None before the first one)."""
        idx = int(np.searchsorted(self.seconds, t, side="right")) - 1
        return None if idx < 0 else self.values[idx]


class TimeSeries(widgets.VBox):
    """Stacked time-series panels with a cursor at the player's time.

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
        Link the cursor to this player right away.
    width, panel_height : int
        Size of the rendered image in pixels (it scales with the notebook).
    title : str, optional

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(0.0, 10.0, 0.5)
    >>> plot = TimeSeries({"speed": (t, np.ones_like(t))})
    >>> plot.set_time(5.0)
    >>> round(plot.cursor_fraction, 3) > 0
    True
    >>> plot.readout.value
    '<b>t = 5.00 s</b> &nbsp; speed: 1'
    """

    def __init__(
        self,
        series: Mapping,
        *,
        player=None,
        width: int = 900,
        panel_height: int = 150,
        title: str | None = None,
    ):
        if not isinstance(series, Mapping) or not series:
            raise ValueError(
                "TimeSeries: series must be a non-empty mapping of label -> "
                f"DataArray or (timestamps, values), got {type(series).__name__}"
            )
        self._series = [_Series(str(k), v) for k, v in series.items()]
        kinds = {s.kind for s in self._series}
        if len(kinds) > 1:
            raise ValueError(
                "TimeSeries: all series need the same kind of timestamps, got "
                "both datetime64 and float seconds"
            )
        self.timestamps_kind = kinds.pop()
        self._t0 = min(float(s.seconds[0]) for s in self._series)
        self._t1 = max(float(s.seconds[-1]) for s in self._series)
        png, self._x_span, self._y_span = self._render(width, panel_height, title)
        self.image = widgets.Image(
            value=png,
            format="png",
            layout=widgets.Layout(width="100%", grid_area="plot"),
        )
        self.cursor = widgets.HTML(layout=widgets.Layout(grid_area="plot"))
        self.readout = widgets.HTML()
        canvas = widgets.GridBox(
            [self.image, self.cursor],
            layout=widgets.Layout(
                grid_template_areas='"plot"', width="100%", max_width=f"{width}px"
            ),
        )
        super().__init__([canvas, self.readout])
        self.cursor_fraction: float | None = None
        self.time: float | None = None
        if player is not None:
            player.link(self)
            self.set_time(player.time)

    # -- drawing ----------------------------------------------------------------
    def _render(self, width: int, panel_height: int, title: str | None):
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        dpi = 100
        n = len(self._series)
        fig = Figure(figsize=(width / dpi, (panel_height * n + 40) / dpi), dpi=dpi)
        FigureCanvasAgg(fig)
        axes = fig.subplots(n, 1, sharex=True, squeeze=False)[:, 0]
        for ax, s in zip(axes, self._series, strict=True):
            lines = ax.plot(s.seconds - self._t0, s.values, linewidth=0.8)
            ax.set_ylabel(f"{s.label} ({s.units})" if s.units else s.label, fontsize=9)
            ax.grid(True, alpha=0.3)
            if s.components:
                ax.legend(
                    lines, s.components, loc="upper right", fontsize=8, ncol=len(lines)
                )
        axes[-1].set_xlim(0.0, self._t1 - self._t0)
        axes[-1].set_xlabel("time since start (s)", fontsize=9)
        if title:
            axes[0].set_title(title, fontsize=10)
        fig.tight_layout()
        fig.canvas.draw()
        # Where the time axis lies on the image, as fractions of its size: the
        # cursor is placed in percent so it stays aligned when the image scales.
        w, h = fig.canvas.get_width_height()
        x0 = axes[-1].transData.transform((0.0, 0.0))[0] / w
        x1 = axes[-1].transData.transform((self._t1 - self._t0, 0.0))[0] / w
        top = 1.0 - axes[0].get_window_extent().y1 / h
        bottom = 1.0 - axes[-1].get_window_extent().y0 / h
        buffer = io.BytesIO()
        fig.savefig(buffer, format="png", dpi=dpi)
        return buffer.getvalue(), (x0, x1), (top, bottom)

    # -- following the player -------------------------------------------------------
    def set_time(self, t) -> None:
        """Move the cursor to ``t``.

        ``t`` is float seconds (since the epoch for datetime64 data, which is
        what a Player passes) or a datetime64 value.
        """
        try:
            t = time_as_seconds(t, self.timestamps_kind)
        except ValueError as err:
            raise ValueError(f"TimeSeries.set_time: {err}") from None
        self.time = t
        span = max(self._t1 - self._t0, 1e-12)
        along = min(max((t - self._t0) / span, 0.0), 1.0)
        fraction = float(self._x_span[0] + along * (self._x_span[1] - self._x_span[0]))
        if self.cursor_fraction is None or abs(fraction - self.cursor_fraction) > 2e-4:
            self.cursor_fraction = fraction
            top, bottom = self._y_span
            self.cursor.value = (
                '<div style="position:relative;width:100%;height:100%;pointer-events:none">'
                f'<div style="position:absolute;left:{100 * fraction:.3f}%;'
                f"top:{100 * top:.2f}%;height:{100 * (bottom - top):.2f}%;"
                f'border-left:2px solid {CURSOR_COLOR}"></div></div>'
            )
        self.readout.value = self._readout(t)

    def _readout(self, t: float) -> str:
        if self.timestamps_kind == DATETIME:
            stamp = f"t = {t - self._t0:.2f} s since start"
        else:
            stamp = f"t = {t:.2f} s"
        parts = [f"<b>{stamp}</b>"]
        for s in self._series:
            value = s.value_at(t)
            if value is None:
                continue
            if s.components:
                shown = ", ".join(
                    f"{c} {v:.3g}" for c, v in zip(s.components, value, strict=True)
                )
            else:
                shown = ", ".join(f"{v:.3g}" for v in value)
            unit = f" {s.units}" if s.units else ""
            parts.append(f"{s.label}: {shown}{unit}")
        return " &nbsp; ".join(parts)

    def __repr__(self) -> str:
        labels = ", ".join(s.label for s in self._series)
        return f"<TimeSeries [{labels}] time={self.time}>"
