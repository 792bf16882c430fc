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

from .._engine import chain as _chain
from . import xarray as _xarray
from .series import velocity_options

__all__ = [
    "Frames",
    "frames",
    "pose_frames",
    "transform_frames",
    "VelocityFrames",
    "velocity_frames",
]


class Frames(NamedTuple):
    """Two resolved frames: the transform maps points wrt ``outof`` to ``into``."""

    outof: Any
    into: Any

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
    return resolve(outof, "outof"), to_frame


def pose_frames(resolve: Callable, frame: Any, reference: Any) -> Frames:
    """``lookup_pose``'s frames: ``reference`` resolved first."""
    to_frame = resolve(reference, "reference")
    return Frames(resolve(frame, "frame"), to_frame)


def transform_frames(
    resolve: Callable,
    outof: Any,
    into: Any,
    as_matrix: bool,
    as_transform: bool,
    as_dataset: bool,
) -> Frames:
    """:func:`frames` for ``lookup_at``, after its result options (at most one)."""
    if (as_matrix or as_transform) and (as_dataset or (as_matrix and as_transform)):
        chosen = [k for k, v in (("as_matrix", as_matrix), ("as_transform", as_transform),
                                 ("as_dataset", as_dataset)) if v]  # fmt: skip
        raise ValueError(f"choose at most one of {', '.join(chosen)}")
    to_frame = resolve(into, "into")
    return Frames(resolve(outof, "outof"), to_frame)


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
    a static chain refused."""
    frame = resolve(frame, "frame")
    if reference is None:
        if frame.parent is None:
            raise ValueError(
                f"frame {frame.name!r} has no parent; pass the reference frame explicitly"
            )
        reference = frame.parent
    reference = resolve(reference, "reference")
    represent_in = resolve(
        represent_in if represent_in is not None else reference, "represent_in"
    )
    mode = velocity_options(outlier_thresh, cutoff, mode=mode)
    # known before anything is computed: a chain whose frames all have no
    # timestamps has no velocity (the engine would find it after the lookup)
    if _chain.static_transform(frame, reference) is not None:
        raise ValueError(
            f"the transform between {frame.name!r} and {reference.name!r} is static; "
            f"a velocity needs timestamps (pass allow_static=True for zeros)"
        )
    return VelocityFrames(frame, reference, represent_in, mode)
