"""The times a call covers, refused at the door when its frames share none.

The engine matches a chain's frames and the arrays of a call
(:func:`rbm_nb._engine.chain.match`): the range is the intersection of every
continuous moving frame's and timestamped array's span, and the first
array (or the first continuous frame) samples it. Where that leaves no
sample there is nothing to compute; the door has the frames (their first
and last keys, their sample counts, the chain), so it refuses such a call
here, before any engine call, and the engine's matching assumes a covered
call.

:func:`samples` is the check of one matching and the number of samples
its result has (which the velocity lookups' filter needs);
:func:`velocity_transform` follows the matchings of a change of a
velocity's reference or moving frame, whose terms are lookups of their own.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .._engine import chain as _chain
from .._engine import time as _time
from .series import check_intervals, enough_samples, velocity_options

__all__ = [
    "samples",
    "chain_samples",
    "connected",
    "velocity_intervals",
    "velocity_samples",
    "velocity_transform",
    "velocity_terms",
    "combined",
]


def samples(frames: Sequence[Any], arrays: Sequence[Any] = ()) -> int:
    """How many samples matching ``frames`` (FrameData) and ``arrays`` (Tracks
    or None) gives (0: static); raises where the spans leave none.

    Raises
    ------
    ValueError
        If datetime64 and numeric timestamps meet, or the time ranges of
        the participants share no sample of the one that samples them.
    """
    array_tracks = [a for a in arrays if a is not None]
    continuous = [f.track for f in frames if f.track is not None and not f.discrete]
    ranged = continuous + array_tracks
    if len(ranged) <= 1:
        discrete = [f.track for f in frames if f.track is not None and f.discrete]
        if discrete or ranged:
            _time.check_compatible(ranged + discrete)
        if ranged:
            return len(ranged[0])
        return len(_chain.match(frames)) if discrete else 0
    _time.check_compatible(
        ranged + [f.track for f in frames if f.track is not None and f.discrete]
    )
    source = array_tracks[0] if array_tracks else continuous[0]
    first = max(t.key[0] for t in ranged)
    last = min(t.key[-1] for t in ranged)
    lo = int(np.searchsorted(source.key, first, side="left"))
    hi = int(np.searchsorted(source.key, last, side="right"))
    if hi <= lo:
        if first <= last:
            raise ValueError(_no_sample_message(frames, arrays, source, first, last))
        raise ValueError(_no_overlap_message(frames, arrays))
    return hi - lo


def connected(outof: Any, into: Any) -> None:
    """Refuse two resolved frames of different trees: no transform connects them.

    Checked before the engine builds the pair's chain; once built (cached),
    the pair is known to be connected and this is one dictionary look-up.
    """
    if _chain.cached_chain(outof, into) is not None:
        return
    up, down = outof.data.path_to_root()[-1], into.data.path_to_root()[-1]
    if up is not down:
        raise ValueError(
            f"frames {outof.name!r} and {into.name!r} are in different trees "
            f"(roots {up.name!r} and {down.name!r}); no transform connects them"
        )


def chain_samples(outof: Any, into: Any, arrays: Sequence[Any] = ()) -> int:
    """:func:`samples` of the chain from ``outof`` to ``into`` (resolved frames)
    and ``arrays`` (Tracks or None).

    The chain's own part (its samples, the span of its continuous frames,
    their kinds of time) is found once and kept with the cached chain, so
    that a lookup checks in a look-up and one array inside that span in a
    few comparisons; anything else takes :func:`samples`' whole rule.
    """
    connected(outof, into)
    steps = _chain.chain(outof, into)
    covered = steps.covered
    if covered is None:
        frames = [f for f, _ in steps]
        # the whole rule first: its message names the arrays too
        count = samples(frames, arrays)
        try:
            steps.covered = _chain_part(frames)
        except ValueError:
            # frames without a sample of their own in their common span
            # may still be sampled by an array inside it: not kept
            pass
        return count
    count, first, last, kinds = covered
    if not arrays:
        return count
    if len(arrays) == 1:
        track = arrays[0]
        if track is None:
            return count
        if not kinds or kinds == (track.kind,):
            if first is None:
                # no continuous frame: the array samples, unlimited
                return len(track)
            key = track.key
            if key[0] >= first and key[-1] <= last:
                # the array (which samples) lies inside the frames' span
                return len(track)
    return samples([f for f, _ in steps], arrays)


def _chain_part(frames: Sequence[Any]) -> tuple[int, Any, Any, tuple]:
    """(samples, first and last key of the continuous frames' common span or
    None, the kinds of time) of a chain's frames, checked by :func:`samples`."""
    count = samples(frames)
    continuous = [f.track for f in frames if f.track is not None and not f.discrete]
    kinds = tuple(sorted({f.track.kind for f in frames if f.track is not None}))
    if not continuous:
        return count, None, None, kinds
    first = max(t.key[0] for t in continuous)
    last = min(t.key[-1] for t in continuous)
    return count, first, last, kinds


def _track(outof: Any, into: Any, arrays: Sequence[Any] = ()) -> Any:
    """The Track the engine's matching of that chain gives (checked first)."""
    chain_samples(outof, into, arrays)
    return _chain.match([f for f, _ in _chain.chain(outof, into)], arrays).track


def velocity_samples(n: int, outlier_thresh: Any = None, cutoff: Any = None) -> None:
    """Refuse a velocity estimated from ``n`` samples the engine cannot use:
    too few for the low-pass filter, or fewer than two."""
    velocity_options(outlier_thresh, cutoff, n)
    enough_samples(n)


def velocity_intervals(frame: Any, reference: Any) -> None:
    """Refuse a looked-up velocity whose timestamps (the chain's matching)
    are too close for its formulas; checked once per chain."""
    steps = _chain.chain(frame, reference)
    if steps.sampled:
        return
    track = _chain.match([f for f, _ in steps]).track
    if track is not None:
        check_intervals(
            track.seconds(), f"timestamps of {frame.name!r} wrt {reference.name!r}"
        )
    steps.sampled = True


def _velocity_track(
    moving: Any, reference: Any, outlier_thresh: Any, cutoff: Any
) -> Any:
    """The Track of a looked-up velocity term (None: a static chain's zeros)."""
    track = _track(moving, reference)
    if track is not None:
        velocity_samples(len(track), outlier_thresh, cutoff)
        velocity_intervals(moving, reference)
    return track


def velocity_transform(
    frame: Any,
    to_frame: Any,
    track: Any,
    what: str,
    linear: bool,
    moving_frame: Any = None,
    reference_frame: Any = None,
    outlier_thresh: Any = None,
    cutoff: Any = None,
) -> None:
    """Refuse a change of the ``what`` frame of velocities (at ``track``, the
    array's Track or None) that the engine could not compute.

    The engine (:func:`rbm_nb._engine.twist.velocity_terms` and
    :func:`~rbm_nb._engine.twist.velocity_parts`) looks up the terms of the
    three-term formulas, each a matching of its own, then matches the array
    with them all: the same matchings are checked here in the same order,
    with the messages they would give, and each velocity term's samples.
    """
    if what == "representation_frame":
        chain_samples(frame, to_frame, [track])
        return
    terms = velocity_terms(
        frame, to_frame, what, linear, moving_frame, reference_frame,
        outlier_thresh, cutoff,
    )  # fmt: skip
    combined(frame, to_frame, track, terms)


def combined(frame: Any, to_frame: Any, track: Any, terms: Sequence[Any]) -> None:
    """Refuse an array at ``track`` whose times, matched with the chain's,
    share no sample with the terms' Tracks (the matchings of
    :func:`rbm_nb._engine.twist.velocity_parts`)."""
    target = _track(frame, to_frame, [track])
    samples([], [target] + list(terms))


def velocity_terms(
    frame: Any,
    to_frame: Any,
    what: str,
    linear: bool,
    moving_frame: Any = None,
    reference_frame: Any = None,
    outlier_thresh: Any = None,
    cutoff: Any = None,
) -> list[Any]:
    """The Tracks of the terms :func:`rbm_nb._engine.twist.velocity_terms`
    looks up for a change of the ``what`` frame (not "representation_frame"),
    each lookup checked; the lazy path checks them once, before its graph."""
    if not linear:
        # w_M/R' = w_M/R + w_R/R'  or  w_M'/R = w_M/R + w_M'/M
        pair = (frame, to_frame) if what == "reference_frame" else (to_frame, frame)
        terms = [_velocity_track(*pair, None, cutoff)]
    elif what == "reference_frame":
        # v_M/R' = v_M/R + v_R/R' + w_R/R' x t_M/R
        if moving_frame is None:
            raise ValueError(
                "moving_frame must be given to transform the reference frame of a "
                "linear velocity (its position enters the three-term formula)"
            )
        twist = _velocity_track(frame, to_frame, outlier_thresh, cutoff)
        lever = _track(frame, to_frame, [_track(moving_frame, frame)])
        terms = [twist, twist, lever]
    else:
        # v_M'/R = v_M/R + v_M'/M + w_M/R x t_M'/M
        if reference_frame is None:
            raise ValueError(
                "reference_frame must be given to transform the moving frame of a "
                "linear velocity (its angular velocity enters the three-term formula)"
            )
        moved = _velocity_track(to_frame, frame, outlier_thresh, cutoff)
        turned = _velocity_track(frame, reference_frame, None, cutoff)
        if (
            turned is not None
            and to_frame is not frame
            and to_frame is not reference_frame
        ):
            # represented in to_frame by a transform of its own
            turned = _track(frame, to_frame, [turned])
        lever = _track(frame, to_frame, [_track(to_frame, frame)])
        terms = [moved, turned, lever]
    return terms


# ---------------------------------------------------------------------------
# the messages (tests/bad_input_cases.py holds them)
# ---------------------------------------------------------------------------


def _spans(frames: Sequence[Any], arrays: Sequence[Any]) -> list[str]:
    parts = []
    for f in frames:
        if f.track is not None and not f.discrete:
            parts.append(f"frame {f.name!r}: {_span(f.track)}")
    for k, a in enumerate(arrays):
        if a is not None:
            parts.append(f"array {k}: {_span(a)}")
    return parts


def _no_overlap_message(frames: Sequence[Any], arrays: Sequence[Any]) -> str:
    parts = _spans(frames, arrays)
    return (
        "the time ranges do not overlap, so there is no time at which the "
        "transformation and the data are both defined (" + "; ".join(parts) + ")"
    )


def _no_sample_message(
    frames: Sequence[Any], arrays: Sequence[Any], source: Any, first: Any, last: Any
) -> str:
    """The ranges overlap, but the sampling track has no sample inside."""
    names = [f"frame {f.name!r}" for f in frames if f.track is source]
    names += [f"array {k}" for k, a in enumerate(arrays) if a is source]
    who = names[0] if names else "the sampling"
    lo = int(np.searchsorted(source.key, first, side="left"))
    around = []
    if lo > 0:
        around.append(f"the last one before is {source.values[lo - 1]}")
    if lo < len(source):
        around.append(f"the first one after is {source.values[lo]}")
    return (
        f"the time ranges overlap only from {_value(source, first)} to "
        f"{_value(source, last)}, and none of the {len(source)} samples of {who} "
        f"(which defines the timestamps of the result) falls within it "
        f"({'; '.join(around)}); nothing can be returned ("
        + "; ".join(_spans(frames, arrays))
        + ")"
    )


def _value(track: Any, key: Any) -> Any:
    """A sort key as the user's kind of time (datetime64 or a number)."""
    if track.kind == "datetime64":
        return np.datetime64(int(key), "ns")
    if track.kind == "timedelta64":
        return np.timedelta64(int(key), "ns")
    return key


def _span(track: Any) -> str:
    return f"{track.values[0]} to {track.values[-1]}"
