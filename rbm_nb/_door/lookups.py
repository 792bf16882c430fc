"""The lookups' one door call each: frames resolved, options checked.

The frames' registry lives above the door (:mod:`rbm_nb.core.frames`), so the
facade hands its ``resolve_frame`` in, as the transforms do
(:func:`rbm_nb._door.inputs.arguments`). What comes back is a frozen value
with the frames resolved in the order the messages name them (the target
first, as ``tf2`` does) and the options checked; its methods shape the
engine's answer (a Dataset, a DataArray).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple

from .._engine import at_time as _at_time
from . import coverage as _coverage
from . import xarray as _xarray
from .at_times import requested_at
from .series import velocity_options

__all__ = [
    "Frames",
    "frames",
    "pose_frames",
    "transform_frames",
    "VelocityFrames",
    "velocity_frames",
    "method_velocity_frames",
    "reference_or_parent",
]


class Frames(NamedTuple):
    """Two resolved frames: the transform maps points wrt ``outof`` to ``into``;
    ``at``: the times asked for, checked (None: the frames' own times)."""

    outof: Any
    into: Any
    at: _at_time.Requested | None = None

    def dataset(self, t: Any, r: Any, timestamps: Any, pose: bool = False) -> Any:
        """The transform (or pose) as a Dataset, wrt ``outof`` (a pose: ``into``)."""
        frame = self.into if pose else self.outof
        if pose:
            return _xarray.transform_dataset(t, r, frame.name, timestamps, pose=True)
        return _xarray.transform_dataset(t, r, frame.name, timestamps)


def frames(resolve: Callable, outof: Any, into: Any) -> tuple[Any, Any]:
    """``(outof, into)`` resolved, ``into`` first: ``lookup_transform``'s common
    call, a few µs in all, so a plain pair rather than a :class:`Frames`."""
    to_frame = resolve(into, "into")
    outof = resolve(outof, "outof")
    _coverage.chain_samples(outof, to_frame)
    return outof, to_frame


def pose_frames(resolve: Callable, frame: Any, reference: Any) -> Frames:
    """``lookup_pose``'s frames: ``reference`` resolved first."""
    to_frame = resolve(reference, "reference")
    pair = Frames(resolve(frame, "frame"), to_frame)
    _coverage.chain_samples(pair.outof, pair.into)
    return pair


def transform_frames(
    resolve: Callable,
    outof: Any,
    into: Any,
    as_matrix: bool,
    as_transform: bool,
    as_dataset: bool,
    time: Any = None,
) -> Frames:
    """:func:`frames` for ``lookup_at``, after its result options (at most one);
    at the frames' own times (``time`` None) their spans must share a sample."""
    if (as_matrix or as_transform) and (as_dataset or (as_matrix and as_transform)):
        chosen = [k for k, v in (("as_matrix", as_matrix), ("as_transform", as_transform),
                                 ("as_dataset", as_dataset)) if v]  # fmt: skip
        raise ValueError(f"choose at most one of {', '.join(chosen)}")
    to_frame = resolve(into, "into")
    from_frame = resolve(outof, "outof")
    if time is None:
        _coverage.chain_samples(from_frame, to_frame)
        return Frames(from_frame, to_frame)
    return Frames(from_frame, to_frame, requested_at(from_frame, to_frame, time))


class VelocityFrames(NamedTuple):
    """The frames of a velocity lookup, resolved, and its checked ``mode``."""

    frame: Any
    reference: Any
    represent_in: Any
    mode: Any

    def names(self) -> tuple[str, str, str]:
        return self.frame.name, self.reference.name, self.represent_in.name

    def twist_dataset(self, linear: Any, angular: Any, timestamps: Any) -> Any:
        return _xarray.twist_dataset(linear, angular, *self.names(), timestamps)

    def dataarray(self, values: Any, kind: str, timestamps: Any) -> Any:
        return _xarray.velocity_dataarray(values, kind, *self.names(), timestamps)


def velocity_frames(
    resolve: Callable,
    frame: Any,
    reference: Any,
    represent_in: Any,
    outlier_thresh: Any,
    cutoff: Any,
    mode: Any = None,
) -> VelocityFrames:
    """Frame, reference (default: the frame's parent) and representation frame
    (default: the reference) resolved, then the velocity options checked and
    a static chain refused, and the chain's samples checked (their spans
    must share some, as many as the filter needs)."""
    frame = resolve(frame, "frame")
    reference = resolve(reference_or_parent(frame, reference), "reference")
    represent_in = resolve(
        represent_in if represent_in is not None else reference, "represent_in"
    )
    mode = velocity_options(outlier_thresh, cutoff, mode=mode)
    _moving(frame, reference, outlier_thresh, cutoff, False)
    return VelocityFrames(frame, reference, represent_in, mode)


def reference_or_parent(frame: Any, reference: Any, where: str = "") -> Any:
    """``reference``, or by default the parent of ``frame`` (a resolved frame):
    the one rule of the velocities and ``plot.trajectory``; ``where`` starts
    the message (e.g. "trajectory: ")."""
    if reference is not None:
        return reference
    if frame.parent is None:
        raise ValueError(
            f"{where}frame {frame.name!r} has no parent; pass the reference frame "
            f"explicitly"
        )
    return frame.parent


def method_velocity_frames(
    frame: Any,
    reference: Any,
    represent_in: Any,
    outlier_thresh: Any,
    cutoff: Any,
    allow_static: bool,
) -> tuple[Any, Any]:
    """``(reference, represent_in)`` of a frame's velocity method (resolved
    frames or None; both default to the frame's parent), the chain checked
    as for :func:`velocity_frames` (a static one only if not ``allow_static``:
    then the velocity is zero)."""
    if represent_in is None:
        represent_in = reference_or_parent(frame, None)
    reference = reference_or_parent(frame, reference)
    _moving(frame, reference, outlier_thresh, cutoff, allow_static)
    return reference, represent_in


def _moving(frame: Any, reference: Any, outlier_thresh: Any, cutoff: Any,
            allow_static: bool) -> None:  # fmt: skip
    """Refuse a velocity lookup of the chain the engine could not estimate."""
    n = _coverage.chain_samples(frame, reference)
    if n == 0:
        # no frame of the chain has timestamps: there is no velocity
        if allow_static:
            return
        raise ValueError(
            f"the transform between {frame.name!r} and {reference.name!r} is static; "
            f"a velocity needs timestamps (pass allow_static=True for zeros)"
        )
    _coverage.velocity_samples(n, outlier_thresh, cutoff)
    _coverage.velocity_intervals(frame, reference)
