"""The browser's requests to a ``TimeSeries`` and the kernel's replies.

A zoomed view asks for the samples in view (``window``: start, end, pixel
width) and the cursor's readout over an overview asks for the recorded
samples at its time (``exact``: a time only; everything else is the
kernel's). A request that is not well formed gets no reply: the page sent
it, and the kernel owns what is drawn. Replies carry their numbers as
float64 bytes in the message's buffers.
"""

from __future__ import annotations

import math

import numpy as np

from .timeseries_panels import checked_width, number
from .timeseries_rows import float64_bytes


def window_request(content: dict, default_width: int) -> tuple | None:
    """``(start, end, width, view)`` of a ``window`` request, or None when
    it is malformed (not finite start < end seconds, a width out of range)."""
    start, end = number(content.get("start")), number(content.get("end"))
    try:
        width = checked_width(content.get("width", default_width), "width")
    except ValueError:
        return None
    if not (np.isfinite(start) and np.isfinite(end) and start < end):
        return None
    return start, end, width, str(content.get("view", ""))


def window_reply(
    content: dict, view: str, start, end, width: int, shift: float, result
) -> tuple[dict, list[bytes]]:
    """The message and buffers answering a ``window`` request with ``result``
    (each panel's x and y, and whether each has every row)."""
    rows, full = result
    buffers: list[bytes] = []
    for x, y in rows:
        x_bytes, y_bytes = float64_bytes(x, y)
        buffers.append(x_bytes)
        buffers.extend(y_bytes)
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
    return reply, buffers


def exact_time(content: dict) -> float | None:
    """The time of an ``exact`` request, or None when it is not a finite number."""
    t = content.get("t")
    if isinstance(t, bool) or not isinstance(t, (int, float)) or not math.isfinite(t):
        return None
    return float(t)


def exact_reply(
    content: dict, view: str, t: float, shift: float, result
) -> tuple[dict, list[bytes]]:
    """The message and buffers answering an ``exact`` request: per panel, the
    nearest sample's time and values as one float64 buffer."""
    buffers = [
        np.asarray([x, *values], dtype=np.float64).tobytes() for x, values in result
    ]
    reply = {
        "type": "exact",
        "id": content.get("id"),
        "view": view,
        "t": t,
        "shift": shift,
    }
    return reply, buffers
