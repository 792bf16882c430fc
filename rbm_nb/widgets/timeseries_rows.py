"""What a ``TimeSeries`` sends of a panel: its rows in a window, as bytes.

Every row of a window when there are at most ``WINDOW_POINTS`` (or the
widget's ``max_points``), else their M4 at the view's pixel width
(:mod:`rbm_nb.widgets._decimate`); a NaN row in each pause longer than the
panel's gap, so the browser draws a gap; x as float64 seconds of the data's
time base and each component as float64 bytes. Also the recorded sample
nearest a time, which the cursor's readout shows.
"""

from __future__ import annotations

import numpy as np

from .._engine.time import TimeBase
from ._decimate import gathered, m4_rows, pause_rows, pause_sides
from .timeseries_panels import PanelSamples

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


def pauses_of(s: PanelSamples, gap: float | None) -> tuple[np.ndarray, float | None]:
    """Rows after which ``s`` pauses longer than ``gap`` seconds (or its own
    ``max_gap``, if shorter), and the threshold used in seconds."""
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
    return pauses, used


def rows_in_view(
    s: PanelSamples,
    pauses: np.ndarray,
    base: TimeBase,
    start: float,
    end: float,
    width: int | None,
    max_points: int | None,
    cancelled=lambda: False,
) -> tuple[np.ndarray, np.ndarray, bool]:
    """Panel rows shown in ``[start, end]`` (seconds of ``base``), one each side.

    Every row when ``width`` is None or there are at most ``WINDOW_POINTS``
    (or ``max_points``), else their M4 at ``width`` columns. Returns x (seconds
    of ``base``), y (m, k) with a NaN row in each visible pause, and whether
    every row is there.
    """
    i0, i1 = s.rows_in(base, start, end)
    limit = max(WINDOW_POINTS, max_points or 0)
    raw, values = s.raw[i0:i1], s.values[i0:i1]
    pauses = pauses[(pauses >= i0) & (pauses < i1)] - i0
    if width is None or i1 - i0 <= limit:
        rows = np.arange(i1 - i0)
        full = True
    else:
        lo = float(s.raw_of(base, start, "low"))
        hi = float(max(s.raw_of(base, end, "high"), lo + 1))
        rows = m4_rows(raw, values, lo, hi, width, cancelled)
        # each column's first pause with both its sides: drawn as a gap
        rows = np.union1d(rows, pause_sides(raw, pauses, lo, hi, width))
        full = False
    x = base.seconds(s.timestamps[i0:i1][rows])
    return (*gathered(x, values, rows, pauses), full)


def panel_of(s: PanelSamples, reduced: bool) -> dict:
    """The ``panels`` entry of ``s``: what the browser labels and colours."""
    return {
        "label": s.label,
        "units": s.units,
        "components": s.components,
        "colors": s.colors
        or [COLORS[i % len(COLORS)] for i in range(len(s.components))],
        "samples": int(s.raw.size),
        "reduced": bool(reduced),
    }


def float64_bytes(x: np.ndarray, y: np.ndarray) -> tuple[bytes, list[bytes]]:
    """x, and each column of y, as the float64 bytes the browser reads."""
    return (
        np.ascontiguousarray(x, dtype=np.float64).tobytes(),
        [
            np.ascontiguousarray(y[:, k], dtype=np.float64).tobytes()
            for k in range(y.shape[1])
        ],
    )


def nearest_row(s: PanelSamples, base: TimeBase, t: float) -> tuple[float, np.ndarray]:
    """(seconds of ``base``, values) of the row of ``s`` nearest ``t``.

    The earlier row wins a tie.
    """
    first = float(base.seconds(s.timestamps[:1])[0])
    last = float(base.seconds(s.timestamps[-1:])[0])
    # past either end the end row is the nearest; clamping also keeps
    # a huge time from overflowing the ns arithmetic
    at = min(max(t, first), last)
    lo = s.raw_of(base, at, "low")
    i = int(np.searchsorted(s.raw, lo, side="left"))
    if i >= s.raw.size or (
        i > 0
        and float(base.seconds(s.timestamps[i - 1 : i])[0])
        >= 2 * at - float(base.seconds(s.timestamps[i : i + 1])[0])
    ):
        i -= 1
    x = float(base.seconds(s.timestamps[i : i + 1])[0])
    return x, np.array(s.values[i], dtype=np.float64)
