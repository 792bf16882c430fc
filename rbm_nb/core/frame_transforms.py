"""The lookups and transforms a reference frame offers, as methods.

:class:`FrameTransforms` is a base class of
:class:`~rbm_nb.core.frames.ReferenceFrame`: ``lookup_transform``, the
velocity lookups and the ``transform_*`` methods (the functions of
:mod:`rbm_nb.core.lookups` and :mod:`rbm_nb.core.transforms` with this
frame as the source). Each resolves its frame arguments, calls the door
(:mod:`rbm_nb._door`) once and forwards to the engine (:mod:`rbm_nb._engine`).

Names are resolved by ``ReferenceFrame._resolve`` (that is
:func:`~rbm_nb.core.frames.resolve_frame`): the registry checks frames
against ``ReferenceFrame`` itself, so it lives with that class, which
imports this module, not the other way round.
"""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING, Any, TypeAlias

from .._door import coverage as _coverage
from .._door import inputs as _inputs
from .._door import lookups as _lookups
from .._door.series import velocity_options
from .._door.unpack import ArrayInput
from .._door.validation import check_what
from .._engine import chain as _chain
from .._engine import transform as _transform
from .._engine import twist as _twist
from .frame_node import FrameNode

__all__ = ["FrameTransforms"]

# A frame argument: a frame or the name of a registered one (FrameLike of
# rbm_nb.core.frames, which defines ReferenceFrame, the FrameNode meant here).
FrameLike: TypeAlias = "FrameNode | str"


class FrameTransforms:
    """Lookups and transforms from this frame, as methods of ``ReferenceFrame``.

    Not used on its own: ``ReferenceFrame`` derives from it and provides
    what is declared below.
    """

    if TYPE_CHECKING:  # provided by ReferenceFrame

        @staticmethod
        def _resolve(frame: Any, argument: str) -> FrameNode: ...

    def _resolve_optional(self, frame: Any, argument: str) -> FrameNode | None:
        """``_resolve`` for arguments that may be None (a default applies)."""
        return None if frame is None else self._resolve(frame, argument)

    def lookup_transform(self, to_frame: FrameLike) -> Any:
        """Transform from this frame to ``to_frame``.

        Returns
        -------
        t : ndarray, shape (3,) or (n, 3)
        r : ndarray, shape (4,) or (n, 4)
        ts : ndarray, shape (n,), or None if static
        """
        to = self._resolve(to_frame, "to_frame")
        _coverage.chain_samples(self, to)  # frames that share no time: refused
        return _chain.lookup_transform(self, to)

    def get_transformation(self, to_frame: FrameLike) -> Any:
        """Deprecated alias of :meth:`lookup_transform`."""
        warnings.warn(
            "get_transformation is deprecated, use lookup_transform instead",
            DeprecationWarning,
            stacklevel=2,
        )
        return self.lookup_transform(to_frame)

    def lookup_twist(
        self,
        reference: FrameLike | None = None,
        represent_in: FrameLike | None = None,
        outlier_thresh: float | None = None,
        cutoff: float | None = None,
        mode: str = "quaternion",
        allow_static: bool = False,
        return_timestamps: bool = False,
    ) -> Any:
        """Linear and angular velocity of this frame wrt ``reference``.

        Both default to the parent frame. Returns ``(linear, angular)``
        with shape (n, 3) each, plus the timestamps if ``return_timestamps``.
        """
        reference = self._resolve_optional(reference, "reference")
        represent_in = self._resolve_optional(represent_in, "represent_in")
        mode = velocity_options(outlier_thresh, cutoff, mode=mode)
        reference, represent_in = _lookups.method_velocity_frames(
            self, reference, represent_in, outlier_thresh, cutoff, allow_static
        )
        linear, angular, ts = _twist.lookup_twist(
            self, reference, represent_in, outlier_thresh, cutoff, mode, allow_static
        )
        return (linear, angular, ts) if return_timestamps else (linear, angular)

    def lookup_linear_velocity(
        self,
        reference: FrameLike | None = None,
        represent_in: FrameLike | None = None,
        outlier_thresh: float | None = None,
        cutoff: float | None = None,
        allow_static: bool = False,
        return_timestamps: bool = False,
    ) -> Any:
        """Linear velocity of this frame wrt ``reference``, shape (n, 3)."""
        velocity_options(outlier_thresh, cutoff)
        reference, represent_in = _lookups.method_velocity_frames(
            self,
            self._resolve_optional(reference, "reference"),
            self._resolve_optional(represent_in, "represent_in"),
            outlier_thresh,
            cutoff,
            allow_static,
        )
        linear, ts = _twist.lookup_linear_velocity(
            self, reference, represent_in, outlier_thresh, cutoff, allow_static
        )
        return (linear, ts) if return_timestamps else linear

    def lookup_angular_velocity(
        self,
        reference: FrameLike | None = None,
        represent_in: FrameLike | None = None,
        outlier_thresh: float | None = None,
        cutoff: float | None = None,
        mode: str = "quaternion",
        allow_static: bool = False,
        return_timestamps: bool = False,
    ) -> Any:
        """Angular velocity of this frame wrt ``reference``, shape (n, 3)."""
        reference = self._resolve_optional(reference, "reference")
        represent_in = self._resolve_optional(represent_in, "represent_in")
        mode = velocity_options(outlier_thresh, cutoff, mode=mode)
        reference, represent_in = _lookups.method_velocity_frames(
            self, reference, represent_in, outlier_thresh, cutoff, allow_static
        )
        angular, ts = _twist.lookup_angular_velocity(
            self, reference, represent_in, outlier_thresh, cutoff, mode, allow_static
        )
        return (angular, ts) if return_timestamps else angular

    def transform_points(
        self,
        arr: ArrayInput,
        to_frame: FrameLike,
        axis: int | None = -1,
        time_axis: int | None = 0,
        timestamps: Any = None,
        return_timestamps: bool = False,
    ) -> Any:
        """Points given in this frame, expressed in ``to_frame``."""
        return _transform_call(
            "points",
            self,
            arr,
            self._resolve(to_frame, "to_frame"),
            axis,
            time_axis,
            timestamps,
            return_timestamps,
        )

    def transform_vectors(
        self,
        arr: ArrayInput,
        to_frame: FrameLike,
        axis: int | None = -1,
        time_axis: int | None = 0,
        timestamps: Any = None,
        return_timestamps: bool = False,
    ) -> Any:
        """Vectors represented in this frame, represented in ``to_frame``."""
        return _transform_call(
            "vectors",
            self,
            arr,
            self._resolve(to_frame, "to_frame"),
            axis,
            time_axis,
            timestamps,
            return_timestamps,
        )

    def transform_quaternions(
        self,
        arr: ArrayInput,
        to_frame: FrameLike,
        axis: int | None = -1,
        time_axis: int | None = 0,
        timestamps: Any = None,
        return_timestamps: bool = False,
    ) -> Any:
        """Orientations wrt this frame, expressed wrt ``to_frame``."""
        return _transform_call(
            "quaternions",
            self,
            arr,
            self._resolve(to_frame, "to_frame"),
            axis,
            time_axis,
            timestamps,
            return_timestamps,
        )

    def transform_angular_velocity(
        self,
        arr: ArrayInput,
        to_frame: FrameLike,
        what: str = "reference_frame",
        axis: int | None = -1,
        time_axis: int | None = 0,
        timestamps: Any = None,
        return_timestamps: bool = False,
        cutoff: float | None = None,
    ) -> Any:
        """Change the reference, moving or representation frame of angular velocities."""
        to_frame = self._resolve(to_frame, "to_frame")
        check_what(what)
        blocks = _inputs.blocks(arr, 3, axis, time_axis, timestamps, "vectors")
        _coverage.velocity_transform(
            self, to_frame, blocks.track, what, False, cutoff=cutoff
        )
        out, ts = _twist.transform_angular_velocity(
            self, blocks, to_frame, what, cutoff
        )
        return (out, ts) if return_timestamps else out

    def transform_linear_velocity(
        self,
        arr: ArrayInput,
        to_frame: FrameLike,
        what: str = "reference_frame",
        moving_frame: FrameLike | None = None,
        reference_frame: FrameLike | None = None,
        axis: int | None = -1,
        time_axis: int | None = 0,
        timestamps: Any = None,
        return_timestamps: bool = False,
        outlier_thresh: float | None = None,
        cutoff: float | None = None,
    ) -> Any:
        """Change the reference, moving or representation frame of linear velocities."""
        to_frame = self._resolve(to_frame, "to_frame")
        check_what(what)
        blocks = _inputs.blocks(arr, 3, axis, time_axis, timestamps, "vectors")
        moving = self._resolve_optional(moving_frame, "moving_frame")
        reference = self._resolve_optional(reference_frame, "reference_frame")
        _coverage.velocity_transform(
            self, to_frame, blocks.track, what, True, moving, reference,
            outlier_thresh, cutoff,
        )  # fmt: skip
        out, ts = _twist.transform_linear_velocity(
            self, blocks, to_frame, what, moving, reference, outlier_thresh, cutoff
        )
        return (out, ts) if return_timestamps else out


def _transform_call(
    kind, frame, arr, to_frame, axis, time_axis, timestamps, return_timestamps
):  # fmt: skip
    """A transform method's call (``to_frame`` resolved): through the door, then the engine."""
    args = _inputs.method_arguments(
        kind, frame, arr, to_frame, axis, time_axis, timestamps
    )
    if args.rows is not None:  # a static chain, plain rows: the short way
        out = _transform.transform_static(kind, args.static, args.rows)
        return (
            (out.reshape(args.shape), None)
            if return_timestamps
            else out.reshape(args.shape)
        )
    out, ts = _transform.transform(frame, kind, args.blocks, args.into)
    return (out, ts) if return_timestamps else out
