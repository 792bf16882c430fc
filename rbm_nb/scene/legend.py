"""The scene's colour legend: what each colour drawn means.

One row for the frames' axes (x red, y green, z blue) when any triad is
drawn, one per coloured object (its name), and the grid's spacing. The view
shows the rows in a corner; :meth:`Scene.legend` returns them.
"""

from __future__ import annotations

from .commands import color_int
from .handles import FrameHandle

AXIS_COLORS = ["#ff0000", "#00ff00", "#0000ff"]


def legend_rows(handles, grid_row: dict | None) -> list[dict]:
    """``{"text", "color"}`` rows (colour a hex string or a list) for ``handles``
    and the grid's row (None: no grid)."""
    handles = list(handles)
    rows: list[dict] = []
    if any(isinstance(h, FrameHandle) for h in handles):
        rows.append({"text": "frame axes x, y, z", "color": AXIS_COLORS})
    for handle in handles:
        if isinstance(handle, FrameHandle) or "color" not in handle.style:
            continue
        color = f"#{color_int(handle.style['color']):06x}"
        rows.append({"text": handle.name.replace("_", " "), "color": color})
    if grid_row is not None:
        rows.append(grid_row)
    return rows
