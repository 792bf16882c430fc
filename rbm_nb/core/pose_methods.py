"""scikit-robot's ``Coordinates`` methods on ``Transform``, immutable.

``translate``, ``rotate``, ``align_axis_to_direction``, ``transform_vector``,
``inverse_transform_vector``, ``difference_position`` and
``difference_rotation`` read as scikit-robot's, but return a new
:class:`~rbm_nb.core.rigid_transform.Transform` (or an array) instead of
changing their receiver. :class:`PoseMethods` is a base class of
``Transform``, which holds the values (``_translation``, ``_rotation``) and
the algebra these methods build on; the arithmetic on kernel rows is in
``_transform_moves`` and ``_transform_differences``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np

from .._door import shapes as _shapes
from . import _pose_algebra as _pa
from . import _transform_differences as _diff
from . import _transform_moves as _moves
from ._transform_arguments import (
    axis_mask,
    finite_numbers,
    finite_translation,
    mirror_axis,
    rows,
)

__all__ = ["PoseMethods"]

_T = TypeVar("_T", bound="PoseMethods")


class PoseMethods:
    """scikit-robot's pose algebra, as methods of ``Transform`` (immutable).

    Not used on its own: ``Transform`` derives from it and provides what is
    declared below for the type checker.
    """

    __slots__ = ()

    if TYPE_CHECKING:  # provided by Transform
        _translation: np.ndarray
        _rotation: np.ndarray

        @property
        def shape(self) -> tuple: ...

        @classmethod
        def _trusted(
            cls: type[_T], translation: np.ndarray, rotation: np.ndarray
        ) -> _T: ...

        def _paired(self, other: Any, what: str) -> tuple: ...

        def inv(self: _T) -> _T: ...

        def apply(self, points) -> np.ndarray: ...

    def _reference(self, wrt, what: str):
        """``wrt`` as "local", "world" ("parent" is the same) or a Transform whose axes are meant."""
        if isinstance(wrt, PoseMethods):
            return wrt
        if isinstance(wrt, str) and wrt in ("local", "world", "parent"):
            return "world" if wrt == "parent" else wrt
        raise ValueError(
            f"{what}: wrt must be 'local', 'world' or a Transform, got {wrt!r}"
        )

    def _batch_shape(self, what: str, *shapes) -> tuple:
        try:
            return np.broadcast_shapes(self.shape, *shapes)
        except ValueError:
            raise ValueError(
                f"{what}: batch shapes {(self.shape,) + shapes} do not broadcast"
            ) from None

    def translate(self: _T, vec, wrt="local") -> _T:
        """Move the origin by ``vec``, expressed in the axes named by ``wrt``.

        The rotation is unchanged. Unlike scikit-robot's in-place
        ``Coordinates.translate``, a new Transform is returned.

        Parameters
        ----------
        vec : array_like, shape (..., 3)
            Displacement; leading shape broadcasts against the batch shape.
        wrt : {"local", "world", "parent"} or Transform, default "local"
            ``"local"``: ``vec`` is in this transformation's own axes;
            ``"world"`` (or ``"parent"``): in the axes it maps into; a
            Transform: in that transformation's axes.

        Returns
        -------
        Transform

        Examples
        --------
        >>> import numpy as np
        >>> from rbm_nb import Transform
        >>> turned = Transform().rotate(np.pi / 2, "y")
        >>> turned.translate([0.1, 0.2, 0.3]).translation.round(12) + 0.0
        array([ 0.3,  0.2, -0.1])
        >>> turned.translate([0.1, 0.2, 0.3], wrt="world").translation
        array([0.1, 0.2, 0.3])
        """
        v = finite_translation(vec)
        ref = self._reference(wrt, "translate")
        extra = (ref.shape,) if isinstance(ref, PoseMethods) else ()
        shape = self._batch_shape("translate", v.shape[:-1], *extra)
        axes = None if ref == "world" else (self if ref == "local" else ref)
        t, q = _moves.translated(
            rows(self._translation, shape, 3),
            rows(self._rotation, shape, 4),
            rows(v, shape, 3),
            None if axes is None else rows(axes._rotation, shape, 4),
        )
        return self._trusted(t.reshape(shape + (3,)), q.reshape(shape + (4,)))

    def rotate(self: _T, angle, axis, wrt="local") -> _T:
        """Turn the axes by ``angle`` about ``axis``; the origin stays where it is.

        Parameters
        ----------
        angle : float or array_like, shape (...)
            Radians, right-hand rule.
        axis : {"x", "y", "z", "-x", "-y", "-z", "xy", "yz", "xz", "xyz"} or array_like, shape (..., 3)
            Rotation axis (normalised; the two-letter names are diagonals),
            expressed in the axes named by ``wrt``.
        wrt : {"local", "world", "parent"} or Transform, default "local"
            ``"local"`` multiplies the rotation from the right (turn about
            the frame's own axes), ``"world"`` from the left; a Transform
            ``W`` turns about ``W``'s axes: ``R' = R_W R R_W⁻¹ R_self``.

        Returns
        -------
        Transform
            Same translation, new rotation; a new object (scikit-robot's
            ``Coordinates.rotate`` changes its receiver instead).

        Raises
        ------
        ValueError
            For an unknown axis name, a zero axis, a non-finite angle or
            shapes that do not broadcast.

        Examples
        --------
        >>> import numpy as np
        >>> from rbm_nb import Transform
        >>> tf = Transform([1.0, 0.0, 0.0]).rotate(np.pi / 2, "z")
        >>> tf.translation
        array([1., 0., 0.])
        >>> tf.apply_vectors([1.0, 0.0, 0.0]).round(12) + 0.0
        array([0., 1., 0.])
        """
        theta = finite_numbers(angle, "angle")
        ax = _pa.axis_vectors(axis, "axis")
        ref = self._reference(wrt, "rotate")
        extra = (ref.shape,) if isinstance(ref, PoseMethods) else ()
        shape = self._batch_shape("rotate", theta.shape, ax.shape[:-1], *extra)
        q = _moves.turned(
            rows(self._rotation, shape, 4),
            rows(ax, shape, 3),
            np.broadcast_to(theta, shape).reshape(-1),
            ref if isinstance(ref, str) else rows(ref._rotation, shape, 4),
        )
        t = rows(self._translation, shape, 3)
        return self._trusted(t.reshape(shape + (3,)), q.reshape(shape + (4,)))

    def transform_vector(self, points) -> np.ndarray:
        """Local coordinates to the coordinates this transformation maps into.

        scikit-robot's name for :meth:`apply`: ``rot(r, p) + t``.

        Parameters
        ----------
        points : array_like, shape (..., 3)

        Returns
        -------
        ndarray, shape (broadcast, 3)

        Examples
        --------
        >>> from rbm_nb import Transform
        >>> Transform([1.0, 2.0, 3.0]).transform_vector([[1.0, 0.0, 0.0]])
        array([[2., 2., 3.]])
        """
        if self.shape:
            return self.apply(points)
        return self._single_matrix_apply(points, inverse=False)

    def _single_matrix_apply(self, points, inverse: bool) -> np.ndarray:
        p = _shapes.last_axis(points, "points", 3)
        return _moves.single_pose_applied(self._translation, self._rotation, p, inverse)

    def inverse_transform_vector(self, points) -> np.ndarray:
        """World coordinates to local ones: ``rot(r⁻¹, p - t)``.

        Parameters
        ----------
        points : array_like, shape (..., 3)

        Returns
        -------
        ndarray, shape (broadcast, 3)

        Examples
        --------
        >>> import numpy as np
        >>> from rbm_nb import Transform
        >>> tf = Transform([1.0, 0.0, 0.0]).rotate(np.pi / 2, "z")
        >>> tf.inverse_transform_vector([1.0, 1.0, 0.0]).round(12) + 0.0
        array([1., 0., 0.])
        """
        if self.shape:
            return self.inv().apply(points)
        return self._single_matrix_apply(points, inverse=True)

    def difference_position(self, other: PoseMethods, position_mask=True) -> np.ndarray:
        """Where ``other``'s origin lies, in this transformation's local axes.

        ``rot(r_self⁻¹, t_other - t_self)``, the position error a controller
        moving ``self`` onto ``other`` acts on.

        Parameters
        ----------
        other : Transform
        position_mask : bool, None, str or array_like of 3, default True
            Components to keep (scikit-robot calls them constrained): True
            all, False or None none, a string of axes such as ``"xy"``, or
            three 0/1 flags. The others come back as 0.

        Returns
        -------
        ndarray, shape (broadcast, 3)

        Examples
        --------
        >>> import numpy as np
        >>> from rbm_nb import Transform
        >>> c1 = Transform([0.1, 0.2, 0.3])
        >>> c2 = Transform([0.3, -0.3, 0.1]).rotate(np.pi / 3, "x")
        >>> c1.difference_position(c2).round(12) + 0.0
        array([ 0.2, -0.5, -0.2])
        >>> c1.difference_position(c2, position_mask="z").round(12) + 0.0
        array([ 0. ,  0. , -0.2])
        """
        shape = self._paired(other, "difference_position")
        mask = axis_mask(position_mask, "position_mask")
        position = _diff.position_in_first(
            rows(self._translation, shape, 3),
            rows(self._rotation, shape, 4),
            rows(other._translation, shape, 3),
        )
        # "+ 0.0" turns the -0.0 of masked-out negative components into 0.0
        return (position * mask + 0.0).reshape(shape + (3,))

    def difference_rotation(
        self, other: PoseMethods, rotation_mask=True, rotation_mirror: str | None = None
    ) -> np.ndarray:
        """Rotation vector of ``r_self⁻¹ r_other``, in this transformation's axes.

        Parameters
        ----------
        other : Transform
        rotation_mask : bool, None, str or array_like of 3, default True
            Components to keep, as ``position_mask`` of
            :meth:`difference_position`.
        rotation_mirror : {"x", "y", "z"}, optional
            scikit-robot's mirror rule: ``other`` is replaced by ``other``
            turned half a turn about its own axis of that name unless that
            axis of ``other`` makes an angle of less than 90° with the same
            axis of ``self`` (parallel or anti-parallel axes, to within
            rounding, also count as "not less", so they are turned too). Unlike
            :meth:`difference`, which keeps whichever candidate is closer,
            this reproduces ``Coordinates.difference_rotation`` exactly.

        Returns
        -------
        ndarray, shape (broadcast, 3)
            Axis times angle, angle in [0, pi].

        Examples
        --------
        >>> import numpy as np
        >>> from rbm_nb import Transform
        >>> flipped = Transform().rotate(np.pi, "x")
        >>> bool(np.linalg.norm(Transform().difference_rotation(flipped)) > 3.14)
        True
        >>> Transform().difference_rotation(flipped, rotation_mirror="x").round(12) + 0.0
        array([0., 0., 0.])
        """
        shape = self._paired(other, "difference_rotation")
        mask = axis_mask(rotation_mask, "rotation_mask")
        mirror = None if rotation_mirror is None else mirror_axis(rotation_mirror)
        rotation = _diff.rotation_from_first(
            rows(self._rotation, shape, 4), rows(other._rotation, shape, 4), mirror
        )
        return (rotation * mask + 0.0).reshape(shape + (3,))

    def align_axis_to_direction(self: _T, direction, axis="z", wrt="world") -> _T:
        """Turn the frame the shortest way so that its ``axis`` points along ``direction``.

        Parameters
        ----------
        direction : array_like, shape (..., 3)
            Target direction, any non-zero length.
        axis : {"x", "y", "z", "-x", "-y", "-z", ...} or array_like, shape (..., 3), default "z"
            The frame's axis to align, in its local axes.
        wrt : {"world", "local", "parent"} or Transform, default "world"
            The axes ``direction`` is expressed in.

        Returns
        -------
        Transform
            Same translation; rotation turned (in world axes) by the shortest
            arc from the current axis to ``direction``. When the two point in
            opposite directions the half turn is about ``axis × e_x`` (or
            ``axis × e_y``), as in scikit-robot.

        Raises
        ------
        ValueError
            For a zero ``direction`` or ``axis`` (scikit-robot silently
            replaces a zero direction by +z; a zero direction has no meaning
            here, so it is refused).

        Examples
        --------
        >>> from rbm_nb import Transform
        >>> tf = Transform().align_axis_to_direction([1.0, 0.0, 0.0])
        >>> tf.apply_vectors([0.0, 0.0, 1.0]).round(12) + 0.0
        array([1., 0., 0.])
        """
        d = _pa.axis_vectors(direction, "direction")
        ax = _pa.axis_vectors(axis, "axis")
        ref = self._reference(wrt, "align_axis_to_direction")
        extra = (ref.shape,) if isinstance(ref, PoseMethods) else ()
        shape = self._batch_shape(
            "align_axis_to_direction", d.shape[:-1], ax.shape[:-1], *extra
        )
        q = _moves.aligned(
            rows(self._rotation, shape, 4),
            rows(ax, shape, 3),
            rows(d, shape, 3),
            ref if isinstance(ref, str) else rows(ref._rotation, shape, 4),
        )
        t = rows(self._translation, shape, 3)
        return self._trusted(t.reshape(shape + (3,)), q.reshape(shape + (4,)))
