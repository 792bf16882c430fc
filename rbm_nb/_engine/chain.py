"""Timestamp matching: which times a chain of frames and arrays is defined at.

The rules are those of the reference package, so results line up with it:

1. The range: every continuous moving frame and every timestamped array
   contributes its first and last timestamp; the range is the intersection.
   Discrete frames do not limit it (they hold their value before the first
   and after the last event).
2. The sampling: the first timestamped array (or, without arrays, the first
   continuous moving frame along the chain) defines the timestamps, kept
   where they fall inside the range. With only discrete frames, the sorted
   union of their events is used. With nothing timestamped the result is
   static.
3. Everything else is resampled onto those timestamps: translations and
   arrays linearly, rotations and quaternion arrays by squad, discrete
   frames by holding the last event.

Unlike the reference, an empty intersection is an error rather than an
empty result, and datetime64 timestamps are never mixed with numbers.

Frames arrive here resolved (objects, not names) and are read through
their one immutable value (:class:`~rbm_nb._engine.frame_data.FrameData`,
``frame.data``), which the frames validated once when they were built. The
chains between two values are cached here, keyed by the pair of values: a
frame that changes makes new values, so an entry made before the change is
never found after it.
"""

from __future__ import annotations

import weakref
from typing import Any

import numpy as np

from .._kernels import quaternion as kq
from .._kernels import resample as kr
from .._kernels import squad_walk as ksw
from .._kernels._arrays import kernel_array
from . import fused as _fused
from . import time as _time
from .frame_data import FrameData, Samples

_IDENTITY_T = np.zeros((1, 3))
_IDENTITY_R = np.array([[1.0, 0.0, 0.0, 0.0]])


class Target:
    """The timestamps a matched operation produces (``None`` track: static)."""

    __slots__ = ("track", "source")

    def __init__(self, track, source=None):
        self.track = track
        # the Track the timestamps were sliced from: resampling it is a slice
        self.source = source

    @property
    def timestamps(self):
        """The timestamps for the caller (a copy: tracks belong to frames)."""
        return None if self.track is None else self.track.values.copy()

    def __len__(self) -> int:
        return 0 if self.track is None else len(self.track)


class Chain(list):
    """The steps from one frame value to another, and what is kept about them.

    The list holds the steps: (FrameData, inverse) pairs, upward steps
    (a frame to its parent, ``False``) from ``outof`` to the common
    ancestor, then downward steps (``True``: the frame's transform
    inverted) down to ``into``. ``static`` is the composed transform
    (t (1, 3), r (1, 4)) when no frame of the chain moves, ``rows`` its rows
    t (3,) and r (4,), kept for lookup_transform's copies; ``plan`` is the
    fused plan (:func:`fused_plan`), made at the first call that needs it;
    ``covered`` what the door found of the chain's times
    (:func:`rbm_nb._door.coverage.chain_samples`), kept with it, and
    ``sampled`` whether it found the chain's matched timestamps fit for a
    velocity (:func:`rbm_nb._door.coverage.velocity_intervals`).
    (A list, so that the loops over a chain run at list speed.)
    """

    __slots__ = ("static", "rows", "plan", "covered", "sampled")

    def __init__(self, steps: list) -> None:
        super().__init__(steps)
        self.static: Any = None
        self.rows: Any = None
        self.plan: Any = _UNPLANNED
        self.covered: Any = None
        self.sampled = False
        if all(f.track is None for f, _ in steps):
            self.static = compose(steps, Target(None))
            self.rows = self.static[0][0], self.static[1][0]


_UNPLANNED = object()

# Chains per pair of frame values. Keys are values, which never change, so
# an entry is right for as long as it exists; forget() only lets go of the
# values (and their samples) of frames that may have gone.
_CHAINS: dict[tuple[FrameData, FrameData], Chain] = {}
_MAX_CACHED = 4096


def forget() -> None:
    """Drop every cached chain (called when a frame makes a new value).

    Not needed for correct results (keys are immutable values): it keeps
    the cache from holding the samples of frames that changed or went.
    """
    _CHAINS.clear()


def _cached(outof, into) -> Chain:
    key = (outof.data, into.data)
    entry = _CHAINS.get(key)
    if entry is None:
        if len(_CHAINS) >= _MAX_CACHED:
            _CHAINS.clear()
        entry = _CHAINS[key] = Chain(_steps(*key))
    return entry


def cached_chain(outof, into) -> Chain | None:
    """The pair's chain if it has been built (and is still cached), else None."""
    return _CHAINS.get((outof.data, into.data))


def chain(outof, into) -> Chain:
    """The steps from ``outof`` to ``into`` (frames or their values), cached.

    Returns
    -------
    Chain
        Iterates (FrameData, bool) pairs: upward steps (frame -> its parent,
        ``False``) from ``outof`` to the common ancestor, then downward steps
        (``True``: the frame's transform inverted) from there to ``into``.
        Cached per pair of values (do not modify it).
    """
    return _cached(outof, into)


def static_transform(outof, into):
    """(t, r) of shapes (1, 3) and (1, 4) if no frame of the chain moves, else None.

    Composed once per pair of frame values and cached with the chain.
    """
    return _cached(outof, into).static


def _steps(outof: FrameData, into: FrameData) -> list:
    up = outof.path_to_root()
    down = into.path_to_root()
    if up[-1] is not down[-1]:
        # the door refuses such a pair first (_door.coverage.connected); this
        # guards the package's own callers that build chains directly
        raise ValueError(
            f"frames {outof.name!r} and {into.name!r} are in different trees "
            f"(roots {up[-1].name!r} and {down[-1].name!r}); no transform connects them"
        )
    # drop the shared part above (and including) the common ancestor
    i, j = len(up), len(down)
    while i > 0 and j > 0 and up[i - 1] is down[j - 1]:
        i -= 1
        j -= 1
    return [(f, False) for f in up[:i]] + [(f, True) for f in reversed(down[:j])]


# Spline coefficients per frame's samples, made at the first resampling that
# needs them; weak keys: they go with the samples.
_COEFFICIENTS: weakref.WeakKeyDictionary[Samples, tuple] = weakref.WeakKeyDictionary()


def _squad_coefficients(frame: FrameData):
    coefficients = _COEFFICIENTS.get(frame.samples)
    if coefficients is None:
        assert frame.track is not None  # (splines are for moving frames)
        r = frame.r  # (made from the kept rotations: once here)
        a_coef, b_coef = kq.squad_coefficients(r, frame.track.base)
        seg = kq.squad_segments(r, a_coef, b_coef)
        coefficients = _COEFFICIENTS.setdefault(frame.samples, (a_coef, b_coef, seg))
    return coefficients


def match(frames, arrays=(), arrays_first=True) -> Target:
    """Find the timestamps a set of frames and arrays is matched to.

    Parameters
    ----------
    frames : sequence of FrameData
        The frames of the chain (direction does not matter here).
    arrays : sequence of Track or None
        Timestamps of the arrays taking part (None: not timestamped).
    arrays_first : bool
        Whether arrays take precedence over frames in defining the sampling.

    The door refused participants of different kinds of time or whose time
    ranges share no sample of the sampling track
    (:func:`rbm_nb._door.coverage.samples`): nothing is checked here.
    """
    array_tracks = [a for a in arrays if a is not None]
    continuous = [f.track for f in frames if f.track is not None and not f.discrete]
    discrete = [f.track for f in frames if f.track is not None and f.discrete]
    ranged = continuous + array_tracks

    ordered = array_tracks + continuous if arrays_first else continuous + array_tracks
    if not ordered:
        if discrete:
            return Target(_time.union(discrete) if len(discrete) > 1 else discrete[0])
        return Target(None)

    source = ordered[0]
    if len(ranged) == 1:
        return Target(source, source)
    first = max(t.key[0] for t in ranged)
    last = min(t.key[-1] for t in ranged)
    lo = int(np.searchsorted(source.key, first, side="left"))
    hi = int(np.searchsorted(source.key, last, side="right"))
    assert hi > lo, "a call the door lets through covers some time (_door.coverage)"
    if lo == 0 and hi == len(source):
        return Target(source, source)
    return Target(source.slice(lo, hi), source)


def _same_times(track, target_track) -> slice | None:
    """The slice of ``track`` equal to the target's timestamps, if there is one."""
    n = len(target_track)
    if track is target_track:
        return slice(0, n)  # an array's own times as the target: nothing to compare
    if len(track) < n:
        return None
    lo = int(np.searchsorted(track.key, target_track.key[0], side="left"))
    if lo + n > len(track):
        return None
    if (
        track.key[lo] == target_track.key[0]
        and track.key[lo + n - 1] == target_track.key[-1]
    ):
        run = track.key[lo : lo + n]
        if _same_memory(run, target_track.key) or np.array_equal(run, target_track.key):
            return slice(lo, lo + n)
    return None


def _same_memory(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two arrays are views of the same elements (a target that is a
    slice of an array's own times: no need to compare them)."""
    return (
        a.__array_interface__["data"][0] == b.__array_interface__["data"][0]
        and a.strides == b.strides
        and a.dtype == b.dtype
    )


def resample_frame(frame, target: Target):
    """A frame's translation (n|1, 3) and rotation (n|1, 4) at the target times.

    ``frame`` is a :class:`FrameData`.
    """
    track = frame.track
    if track is None:
        return frame.t, frame.rotation
    tt = target.track
    # (a target is static only where no frame of the chain has times)
    assert tt is not None, f"frame {frame.name!r} is timestamped; the target is not"
    same = _same_times(track, tt)
    if same is not None:
        # the stored values, with their signs (the reference returns them),
        # NaN only where the sample itself is missing
        return frame.samples.rows(same)
    if frame.discrete:
        # float seconds on one origin keep the order of the exact keys
        t_out = tt.base_in(track.origin)
        return (
            kr.hold_last(track.base, frame.t, t_out),
            kr.hold_last(track.base, frame.rotation, t_out),
        )
    t_out = tt.base_in(track.origin)
    if len(track) < 2:
        return frame.t, frame.rotation
    a_coef, b_coef, seg = _squad_coefficients(frame)
    r = frame.r  # (a moving frame's is made at each read: once per call)
    rot = kq.squad_evaluate(r, track.base, a_coef, b_coef, seg, t_out)
    # the rotations as kept, without the missing rows' NaN: r is NaN in
    # those rows, so their products are NaN and never negative, as with the
    # masked rotations (one masked copy less per call)
    stored_signs(rot, r, frame.samples.stored_rotation, track.base, t_out)
    trans = kr.interp_linear(track.base, frame.t, t_out)
    if frame.max_gap is not None:
        in_gap = in_long_gap(track.base, t_out, frame.max_gap)
        trans[in_gap] = np.nan
        rot[in_gap] = np.nan
    return trans, rot


def in_long_gap(t_in, t_out, max_gap: float) -> np.ndarray:
    """Which ``t_out`` fall strictly inside a gap of ``t_in`` longer than max_gap.

    Times equal to a sample are never inside a gap.
    """
    right = np.searchsorted(t_in, t_out, side="left")
    inside = (right > 0) & (right < len(t_in))
    idx = np.clip(right, 1, len(t_in) - 1)
    gap = t_in[idx] - t_in[idx - 1]
    exact = t_in[np.clip(right, 0, len(t_in) - 1)] == t_out
    return inside & (gap > max_gap) & ~exact


def stored_signs(out, unflipped, stored, t_in, t_out) -> None:
    """Give interpolated quaternions the sign of the stored sample they start from.

    Interpolation runs on the sign-continuous series (``unflip``); the value
    between samples i and i+1 is then negated wherever the stored sample i
    has the other sign, which is what SQUAD on the stored samples gives (and
    what rigid-body-motion returns). ``out`` (m, 4) is changed in place.
    """
    n = len(t_in)
    if n < 2:
        return
    with np.errstate(invalid="ignore"):
        flipped = np.einsum("ij,ij->i", unflipped, stored) < 0.0
    if not flipped.any():
        return
    seg = np.searchsorted(t_in, t_out, side="right") - 1
    np.clip(seg, 0, n - 2, out=seg)
    out[flipped[seg]] *= -1.0


def compose(steps, target: Target):
    """Translation (n|1, 3) and rotation (n|1, 4) of a chain at the target times."""
    t_acc, r_acc = _IDENTITY_T, _IDENTITY_R
    for k, (frame, inverse) in enumerate(steps):
        t, r = resample_frame(frame, target)
        if k == 0 and not inverse:
            t_acc, r_acc = t, r  # identity followed by (t, r) is (t, r)
        else:
            t_acc, r_acc = kr.chain_step(t_acc, r_acc, t, r, inverse)
    return t_acc, r_acc


def held(steps, target: Target):
    """A chain whose moving frames are all discrete, as (t, r, idx), or None.

    Such a transform is piecewise constant: it changes only at the events.
    Composing it once per event (e rows) and indexing each target time into
    those events is exact and avoids one transform per time step. Returns
    None if the chain has a continuous moving frame (or nothing moves).
    """
    tracks = []
    for frame, _ in steps:
        if frame.track is not None:
            if not frame.discrete:
                return None
            tracks.append(frame.track)
    if not tracks or target.track is None:
        return None
    events = _time.union(tracks) if len(tracks) > 1 else tracks[0]
    t, r = compose(steps, Target(events))
    if t.shape[0] != len(events):
        t = np.repeat(t, len(events), axis=0)
    if r.shape[0] != len(events):
        r = np.repeat(r, len(events), axis=0)
    return t, r, kr.hold_index(events.base, target.track.base_in(events.origin))


def resample_array(data: np.ndarray, track, target: Target, quaternions: bool):
    """An array of shape (n, k, c) at the target times.

    Static arrays (``track`` None) come back unchanged (shape (1, k, c)) and
    broadcast; timestamped ones are sliced when their timestamps are the
    target's, else interpolated (squad for quaternions, c == 4).
    """
    if track is None:
        return data
    tt = target.track
    # (a timestamped array makes the target timestamped: see match)
    assert tt is not None, "a timestamped array was matched to a static target"
    same = _same_times(track, tt)
    if same is not None:
        return data[same]
    t_out = tt.base_in(track.origin)
    n, k, c = data.shape
    out = np.empty((len(t_out), k, c))
    for j in range(k):
        column = kernel_array(data[:, j, :])
        if quaternions:
            if n < 2:
                out[:, j, :] = column[0]
            else:
                # unflip, squad and stored_signs in one pass
                out[:, j, :] = ksw.squad_walk(column, track.base, t_out)
        else:
            out[:, j, :] = kr.interp_linear(track.base, column, t_out)
    return out


def _compose_static(run):
    return compose(run, Target(None))


def fused_plan(steps, target: Target):
    """The fused plan of a moving chain and its ``own`` runs, or (None, None).

    ``own[k]`` is 1 + the index of the first target time among slot k's
    samples when the target times are a run of them, else 0.

    Chains with moving frames (up to ``_kernels.fused.SLOTS`` of them) are
    evaluated in one pass by :mod:`rbm_nb._engine.fused`, with the rules of
    :func:`resample_frame` and :func:`compose`.
    """
    if target.track is None:
        return None, None
    if type(steps) is Chain:
        plan = steps.plan
        if plan is _UNPLANNED:
            plan = steps.plan = _fused.plan(steps, _compose_static)
    else:
        plan = _fused.plan(steps, _compose_static)
    if plan is None:
        return None, None
    runs = [_same_times(f.track, target.track) for f in plan.frames]
    return plan, [0 if run is None else run.start + 1 for run in runs]


def rates_plan(frame, to_frame):
    """(plan, own, target) for :func:`rbm_nb._engine.fused.body_rates`, or None.

    None where the chain kernel does not apply and the lookup's own route
    is taken: a static chain, fewer than 4 target times (the spline's
    minimum), no fused plan, target times that are every moving frame's
    own samples (which the lookup composes without evaluating anything), or
    a frame with missing rotations (the kernel would stop at the first row
    that reads one).
    """
    steps = chain(frame, to_frame)
    target = match([f for f, _ in steps])
    if target.track is None or len(target) < 4:
        return None
    plan, own = fused_plan(steps, target)
    if plan is None or all(own) or any(f.missing_rotations for f in plan.frames):
        return None
    return plan, own, target


def apply(kind: str, steps, target: Target, data: np.ndarray) -> np.ndarray:
    """Apply a chain's transform to (n|1, k, c) data at the target times.

    ``kind`` is "points", "vectors" or "quaternions".
    """
    plan, own = fused_plan(steps, target)
    if plan is not None:
        return _fused.transform(plan, target, own, data, kind)
    discrete = held(steps, target)
    if discrete is not None:
        t, r, idx = discrete
        if kind == "quaternions":
            return kr.qmul_blocks_held(r, idx, data)
        return kr.transform_blocks_held(r, t, idx, data, kind == "points")
    t, r = compose(steps, target)
    if kind == "quaternions":
        return kr.qmul_blocks(r, data)
    return kr.transform_blocks(r, t, data, kind == "points")


def evaluate(steps, target: Target, rotation_only: bool = False):
    """Translation (n|1, 3) and rotation (n|1, 4) of a chain at the target times.

    The fused kernels where the chain has something to interpolate (squad
    coefficients computed only for the segments read); at their own times
    frames are slices, which :func:`compose` composes without evaluating
    anything. ``rotation_only`` as for :func:`lookup`.
    """
    plan, own = fused_plan(steps, target)
    if plan is not None and not all(own):
        return _fused.lookup(plan, target, own, rotation_only)
    return compose(steps, target)


def lookup(frame, to_frame, rotation_only: bool = False):
    """Translation (n|1, 3), rotation (n|1, 4) and Target from frame to to_frame.

    ``rotation_only``: the caller needs the rotation alone, so the fused
    kernels may skip the translations (then ``t`` may have 0 rows).
    """
    steps = chain(frame, to_frame)
    target = match([f for f, _ in steps])
    t, r = evaluate(steps, target, rotation_only)
    if len(steps) == 1:
        # a frame into its parent at its own times is its samples themselves
        # (views); the caller gets copies, never the frame's memory (which
        # may be the user's own read-only arrays, see core/frames.py)
        kept = steps[0][0].samples
        if np.may_share_memory(t, kept.stored_t):
            t = t.copy()
        if np.may_share_memory(r, kept.stored_rotation) or (
            kept.unit is not None and np.may_share_memory(r, kept.unit)
        ):
            r = r.copy()
    n = len(target)
    # composed rows of a chain that does not move here, once (r: the fused
    # kernels' t has no rows when rotation_only)
    if target.track is not None and r.shape[0] != n:
        t = np.repeat(t, n, axis=0)
        r = np.repeat(r, n, axis=0)
    return t, r, target


def lookup_transform(frame, to_frame):
    """Translation, rotation and timestamps (None if static) from frame to to_frame.

    Static transforms come back with shapes (3,) and (4,), moving ones with
    (n, 3) and (n, 4).
    """
    rows = _cached(frame, to_frame).rows
    if rows is not None:
        # copies: the cached transform is shared by every later call
        return rows[0].copy(), rows[1].copy(), None
    t, r, target = lookup(frame, to_frame)
    return t, r, target.timestamps
