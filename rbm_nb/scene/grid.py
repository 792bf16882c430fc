"""The scene's ground grid: lines in the base's xy plane, spaced to fit the content.

meshcat's own grid is 1 m wide at the origin; this one spans the content's
box (one spacing beyond it) at a spacing of 1, 2 or 5 times a power of ten,
about ten lines across, and is redrawn only when the spacing or the box
changes. Its spacing is written in the legend.
"""

from __future__ import annotations

import math

import numpy as np

from . import commands
from .bounds import Bounds
from .commands import Message, color_int
from .state import ROOT, SceneState

GRID_PATH = f"{ROOT}/grid"
GRID_COLOR = "#5a5a5a"


def nice_step(span: float, lines: int = 10) -> float:
    """A 1, 2 or 5 times a power of ten close to ``span / lines`` (grid spacing)."""
    raw = max(float(span), 1e-9) / lines
    power = 10.0 ** math.floor(math.log10(raw))
    for factor in (1.0, 2.0, 5.0, 10.0):
        if raw <= factor * power * 1.0000001:
            return factor * power
    return 10.0 * power


def format_length(metres: float) -> str:
    """``0.5 m``, ``20 m``, ``2 km``, ``5 cm``."""
    if metres >= 1000:
        return f"{metres / 1000:g} km"
    if metres < 0.01:
        return f"{metres * 1000:g} mm"
    if metres < 1:
        return f"{metres * 100:g} cm"
    return f"{metres:g} m"


class Grid:
    """The grid of one scene (``enabled`` False: none is drawn)."""

    def __init__(self, enabled: bool):
        self.enabled = bool(enabled)
        self.step: float | None = None
        self._box: tuple[tuple, tuple] | None = None

    def refit(self, bounds: Bounds | None, state: SceneState) -> list[Message]:
        """The commands that redraw the grid around ``bounds`` (none when it fits)."""
        if not self.enabled or bounds is None:
            return []
        low, high = bounds.low[:2], bounds.high[:2]
        span = float(max(np.max(high - low), 1.0))
        step = nice_step(span)
        lo = np.floor(low / step) * step - step
        hi = np.ceil(high / step) * step + step
        box = (tuple(lo), tuple(hi))
        if self.step == step and self._box == box:
            return []
        self.step, self._box = step, box
        xs = np.arange(lo[0], hi[0] + step / 2, step)
        ys = np.arange(lo[1], hi[1] + step / 2, step)
        segments = []
        for x in xs:
            segments += [(x, lo[1], 0.0), (x, hi[1], 0.0)]
        for y in ys:
            segments += [(lo[0], y, 0.0), (hi[0], y, 0.0)]
        g = commands.meshcat_geometry()
        lines = g.LineSegments(
            g.PointsGeometry(
                np.ascontiguousarray(np.array(segments, dtype=np.float32).T)
            ),
            g.LineBasicMaterial(color=color_int(GRID_COLOR)),
        )
        return [state.set_object(GRID_PATH, lines)]

    def legend_row(self) -> dict | None:
        """``{"text", "color"}`` naming the spacing; None while no grid is drawn."""
        if not self.enabled or self.step is None:
            return None
        return {"text": f"grid {format_length(self.step)}", "color": GRID_COLOR}
