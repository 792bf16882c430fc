"""What the frame tree says of one frame: its kind, samples, span and rate.

Read from the frame as registered, with the one time rule
(:func:`rbm_nb._engine.time.as_track`); nothing here draws.
"""

from __future__ import annotations

from typing import Any

from .._engine.time import as_track


def frame_kind(frame) -> str:
    """``root``, ``static``, ``moving`` or ``discrete``."""
    if frame.parent is None:
        return "root"
    if frame.timestamps is None:
        return "static"
    return "discrete" if getattr(frame, "discrete", False) else "moving"


def frame_info(frame) -> dict:
    """Kind, sample count, time span and mean rate of a frame.

    Returns
    -------
    dict
        ``kind``, ``samples`` (1 for static frames), ``start`` / ``end`` (float
        seconds, None if static), ``span`` (seconds), ``rate`` (Hz, None
        unless moving with at least two samples) and ``time_kind``.
    """
    kind = frame_kind(frame)
    info: dict[str, Any] = {
        "kind": kind,
        "samples": 1,
        "start": None,
        "end": None,
        "span": 0.0,
        "rate": None,
        "time_kind": None,
    }
    if frame.timestamps is not None:
        track = as_track(frame.timestamps, f"timestamps of {frame.name!r}", copy=False)
        seconds, time_kind = track.epoch_seconds(), track.kind
        info.update(
            samples=len(seconds),
            start=float(seconds[0]),
            end=float(seconds[-1]),
            time_kind=time_kind,
        )
        info["span"] = float(seconds[-1] - seconds[0])
        if len(seconds) > 1 and info["span"] > 0:
            info["rate"] = (len(seconds) - 1) / info["span"]
    return info


def describe(info: dict) -> str:
    """The row's text: kind, sample count, time span and mean rate."""
    if info["kind"] in ("root", "static"):
        return info["kind"]
    unit = "events" if info["kind"] == "discrete" else "samples"
    text = f"{info['kind']} \u00b7 {info['samples']} {unit} \u00b7 {info['span']:.3g} s"
    if info["rate"] is not None:
        text += f" \u00b7 {info['rate']:.4g} Hz"
    return text


def path_to_root(frame) -> list:
    """``frame``, its parent, ... up to the root."""
    out = [frame]
    while out[-1].parent is not None:
        out.append(out[-1].parent)
    return out
