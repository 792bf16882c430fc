"""The frame tree's details: one frame's or a pair's pose at the time shown.

One time base for everything the details print: seconds from the linked
player's start, else from the earliest first sample of the tree's frames
(plus the date for datetime data). A pose that has no value at the time
shown says which moving frame's recording has no sample there, and why when
the caller knows (``missing_reasons``). The values are built here
(:class:`~rbm_nb.widgets.frame_details.FrameDetails`,
:class:`~rbm_nb.widgets.frame_details.PairDetails`); drawing them is
:mod:`rbm_nb.widgets.frame_details`' job.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._engine.time import TimeBase, as_track
from ..core import lookups
from ._timebase import format_time
from .frame_details import FrameDetails, PairDetails, pose_at
from .frame_facts import describe, path_to_root


def time_base(player, rows: dict) -> TimeBase:
    """Second 0: ``player``'s, else the earliest first sample of the ``rows``' frames."""
    if player is not None:
        return player.timebase
    first = None
    for row in rows.values():
        frame = row["frame"]
        if frame.timestamps is None:
            continue
        stamps = np.asarray(getattr(frame.timestamps, "values", frame.timestamps))
        seconds = row["info"]["start"]
        if first is None or seconds < first[0]:
            first = (seconds, stamps[:1])
    if first is None:
        return TimeBase(t0_s=0.0)
    return TimeBase.of(first[1])


def shown_seconds(
    time: float | None, exact: tuple[Any, float] | None, base: TimeBase
) -> float | None:
    """The time shown (data seconds) as seconds of ``base``; exact when
    ``set_time`` had a datetime (``exact``: what it had, and its data seconds)."""
    if time is None:
        return None
    try:
        if exact is not None and exact[1] == time:
            return base.at(exact[0])
        return base.at(time)
    except ValueError:  # a time of another kind than the tree's frames
        return time - base.origin


def readout(base: TimeBase):
    """Seconds of ``base`` -> the shared readout (with the date for datetime data)."""
    t0_ns = base.t0_ns if base.absolute else None
    return lambda seconds: format_time(seconds, t0_ns)


def seconds_on(base: TimeBase, timestamps, name: str) -> np.ndarray:
    """Sample times as seconds of ``base``, from exact keys.

    A frame whose times are of another kind than the base's (a tree mixing
    datetime64 and numeric frames) keeps its data seconds less second 0's.
    """
    track = as_track(timestamps, name, copy=False, repeats=True)
    if track.kind == base.kind:
        return base.seconds(track)
    return track.epoch_seconds() - base.origin


def missing_near(frame, at: float, base: TimeBase) -> bool:
    """Whether ``frame``'s sample at or before ``at``, or the next one, is NaN."""
    if frame.timestamps is None:
        return False
    seconds = seconds_on(base, frame.timestamps, f"timestamps of {frame.name!r}")
    i = int(np.searchsorted(seconds, at, side="right")) - 1
    rows = [j for j in (i, i + 1) if 0 <= j < len(seconds)]
    for values in (frame.translation, frame.rotation):
        values = np.asarray(values, dtype=float)
        picked = values[rows] if values.ndim == 2 else values
        if not np.isfinite(picked).all():
            return True
    return False


def missing_text(frames, at: float, base: TimeBase, reasons: dict[str, str]) -> str:
    """ "no sample of <frame> at <time> (missing: <why>)" for a NaN result at ``at``.

    Names the moving frames of ``frames`` whose own sample at or next to
    ``at`` has no value (the samples an interpolation there needs).
    """
    culprits = [f for f in frames if missing_near(f, at, base)]
    shown = readout(base)
    if not culprits:
        return f"no sample at {shown(at)} (missing)"
    names = ", ".join(f.name for f in culprits)
    why = [reasons[f.name] for f in culprits if f.name in reasons]
    said = "; ".join(dict.fromkeys(why)) or "the recording has no value there"
    return f"no sample of {names} at {shown(at)} (missing: {said})"


def single_details(
    frame,
    info: dict,
    in_tree,
    base: TimeBase | None,
    shown: float | None,
    reasons: dict[str, str],
) -> FrameDetails:
    """``frame``'s parent, children in the tree, path to the root and pose
    wrt its parent at ``shown`` (``base`` is None for the root)."""
    pose = None
    if frame.parent is not None and base is not None:
        seconds = None
        if frame.timestamps is not None:
            seconds = seconds_on(
                base, frame.timestamps, f"timestamps of {frame.name!r}"
            )
        pose = pose_at(
            f"wrt {frame.parent.name}",
            np.asarray(frame.translation, dtype=float),
            np.asarray(frame.rotation, dtype=float),
            seconds,
            shown,
            readout(base),
            lambda at: missing_text([frame], at, base, reasons),
        )
    return FrameDetails(
        name=frame.name,
        summary=describe(info),
        parent=None if frame.parent is None else frame.parent.name,
        children=tuple(c.name for c in frame.children if c.name in in_tree),
        path=tuple(f.name for f in path_to_root(frame)),
        pose=pose,
    )


def looked_up(a, b, cache: dict) -> tuple:
    """``lookup_transform(outof=a, into=b)`` as (t, r, track), kept in ``cache``."""
    key = (a.name, b.name, id(a), id(b))
    if key not in cache:
        t, r, ts = lookups.lookup_transform(outof=a, into=b, return_timestamps=True)
        track = (
            None
            if ts is None
            else as_track(ts, "transform timestamps", copy=False, repeats=True)
        )
        cache[key] = (np.asarray(t), np.asarray(r), track)
    return cache[key]


def pair_details(
    a,
    b,
    chain: tuple,
    looked: tuple,
    base: TimeBase,
    shown: float | None,
    reasons: dict[str, str],
) -> PairDetails:
    """The chain from ``a`` to ``b`` and the transform of ``a`` in ``b`` at
    ``shown`` (``looked``: :func:`looked_up`'s result)."""
    t, r, track = looked
    seconds = None if track is None else seconds_on(base, track, "transform timestamps")
    moving = [f for f in a.frames_between(b) if f.timestamps is not None]
    pose = pose_at(
        f"of {a.name} in {b.name}",
        t,
        r,
        seconds,
        shown,
        readout(base),
        lambda at: missing_text(moving, at, base, reasons),
    )
    return PairDetails(outof=a.name, into=b.name, chain=chain, pose=pose)
