"""``Transform``: an immutable rigid transformation value, scalar or batched.

A transformation maps a point ``p`` given in frame B to frame T by rotating
first and translating second, the convention of rbm_nb and of
``lookup_transform``::

    p_T = rot(r, p_B) + t

``translation`` has shape ``(..., 3)`` and ``rotation`` (unit quaternions,
``w, x, y, z``) shape ``(..., 4)``; the leading shape is the batch shape, ``()``
for a single transformation. Composition reads like matrix products:
``(a @ b).apply(p) == a.apply(b.apply(p))``.
"""

from __future__ import annotations

import numpy as np

from .._door import shapes as _shapes
from .._door.unpack import kernel_array
from .._kernels import quaternion as _kq
from . import _transform_differences as _diff
from . import _transform_interpolation as _interp
from ._transform_arguments import (
    array_text,
    axis_mask,
    finite_numbers,
    finite_translation,
    mirror_axis,
    read_only,
    rows,
    unit_rotation,
)
from .conversions import (
    MATRIX_TOLERANCE,
    homogeneous_from_transform,
    transform_from_homogeneous,
)
from .pose_methods import PoseMethods

__all__ = ["Transform"]


class Transform(PoseMethods):
    """A rigid transformation (or a batch of them): rotate, then translate.

    Parameters
    ----------
    translation : array_like, shape (..., 3), default (0, 0, 0)
    rotation : array_like, shape (..., 4), default (1, 0, 0, 0)
        Unit quaternions ``w, x, y, z`` (within ``UNIT_QUATERNION_TOLERANCE``,
        normalised on construction). The leading shapes of ``translation``
        and ``rotation`` broadcast to the batch shape.

    Raises
    ------
    ValueError
        If a shape is wrong, a translation is not finite or a quaternion is
        not (close to) unit norm.

    Notes
    -----
    scikit-robot's pose methods (``translate``, ``rotate``,
    ``align_axis_to_direction``, ``transform_vector``,
    ``inverse_transform_vector``, ``difference_position``,
    ``difference_rotation``) come from the base class
    :class:`~rbm_nb.core.pose_methods.PoseMethods`.

    Examples
    --------
    >>> import numpy as np
    >>> from rbm_nb import Transform
    >>> quarter_z = [np.cos(np.pi / 4), 0.0, 0.0, np.sin(np.pi / 4)]
    >>> a = Transform([1.0, 0.0, 0.0], quarter_z)
    >>> a.apply([1.0, 0.0, 0.0]).round(12) + 0.0
    array([1., 1., 0.])
    >>> (a @ a.inv()).allclose(Transform.identity())
    True
    """

    __slots__ = ("_translation", "_rotation")
    # set once, through object.__setattr__ (the instances are immutable)
    _translation: np.ndarray
    _rotation: np.ndarray
    # numpy must not treat a Transform as an array operand: ``tf @ ndarray``
    # and ``ndarray @ tf`` then raise TypeError instead of guessing
    __array_ufunc__ = None

    def __init__(self, translation=(0.0, 0.0, 0.0), rotation=(1.0, 0.0, 0.0, 0.0)):
        t = finite_translation(translation)
        q = unit_rotation(rotation)
        try:
            shape = np.broadcast_shapes(t.shape[:-1], q.shape[:-1])
        except ValueError:
            raise ValueError(
                f"translation of shape {t.shape} and rotation of shape {q.shape} "
                "have batch shapes that do not broadcast"
            ) from None
        # np.array copies: the caller's arrays must not alias ours
        object.__setattr__(
            self, "_translation", read_only(np.array(np.broadcast_to(t, shape + (3,))))
        )
        object.__setattr__(
            self, "_rotation", read_only(np.array(np.broadcast_to(q, shape + (4,))))
        )

    @classmethod
    def _trusted(cls, translation: np.ndarray, rotation: np.ndarray) -> Transform:
        """Wrap arrays that are already valid (results of our own arithmetic)."""
        new = object.__new__(cls)
        object.__setattr__(new, "_translation", read_only(translation))
        object.__setattr__(new, "_rotation", read_only(rotation))
        return new

    def __setattr__(self, name, value):
        raise AttributeError("Transform is immutable; build a new one instead")

    def __delattr__(self, name):
        raise AttributeError("Transform is immutable")

    def __reduce__(self):
        return (Transform, (np.array(self._translation), np.array(self._rotation)))

    # -- construction -------------------------------------------------------

    @classmethod
    def identity(cls, shape=()) -> Transform:
        """The identity, or a batch of identities of the given shape.

        Parameters
        ----------
        shape : int or tuple of int, default ()
        """
        shape = (shape,) if np.ndim(shape) == 0 and shape != () else tuple(shape)
        t = np.zeros(shape + (3,))
        q = np.zeros(shape + (4,))
        q[..., 0] = 1.0
        return cls._trusted(t, q)

    @classmethod
    def from_matrix(cls, matrix, *, tol: float = MATRIX_TOLERANCE) -> Transform:
        """From homogeneous matrices ``[[R, t], [0, 0, 0, 1]]``.

        Parameters
        ----------
        matrix : array_like, shape (..., 4, 4)
        tol : float, default 1e-6
            Accepted deviation of ``R`` from orthonormality (see
            ``rbm_nb.conversions.transform_from_homogeneous``).
        """
        t, q = transform_from_homogeneous(matrix, tol=tol)
        return cls._trusted(t, q)

    # -- array-like behaviour -----------------------------------------------

    @property
    def translation(self) -> np.ndarray:
        """Translations, shape (..., 3), read-only."""
        return self._translation

    @property
    def rotation(self) -> np.ndarray:
        """Unit quaternions ``w, x, y, z``, shape (..., 4), read-only."""
        return self._rotation

    @property
    def shape(self) -> tuple:
        """Batch shape; ``()`` for a single transformation."""
        return self._translation.shape[:-1]

    @property
    def ndim(self) -> int:
        return len(self.shape)

    def __len__(self) -> int:
        if not self.shape:
            raise TypeError("len() of a single Transform (batch shape ())")
        return self.shape[0]

    def __getitem__(self, index) -> Transform:
        if not self.shape:
            raise IndexError("a single Transform (batch shape ()) cannot be indexed")
        rows = np.arange(int(np.prod(self.shape))).reshape(self.shape)[index]
        return Transform._trusted(
            self._translation.reshape(-1, 3)[rows], self._rotation.reshape(-1, 4)[rows]
        )

    def __iter__(self):
        for i in range(len(self)):
            yield self[i]

    def __repr__(self) -> str:
        t = array_text(self._translation, "    translation=")
        r = array_text(self._rotation, "    rotation=")
        if not self.shape:
            return f"Transform(translation={t}, rotation={r})"
        return f"Transform(shape={self.shape},\n    translation={t},\n    rotation={r})"

    def __eq__(self, other):
        """Exactly the same transformation(s): equal translations and q or -q."""
        if not isinstance(other, Transform):
            return NotImplemented
        if self.shape != other.shape:
            return False
        same_q = np.all(self._rotation == other._rotation, axis=-1) | np.all(
            self._rotation == -other._rotation, axis=-1
        )
        return bool(np.all(self._translation == other._translation) and np.all(same_q))

    # mutable-free but array-valued: no meaningful hash (None is how Python
    # says so; typeshed declares object.__hash__ a method)
    __hash__ = None  # type: ignore[assignment]

    def allclose(self, other: Transform, *, atol: float = 1e-12) -> bool:
        """Whether both describe the same transformation(s) to within ``atol``.

        Translations are compared entry by entry, rotations as quaternions
        up to sign (q and -q are the same rotation). Batch shapes broadcast.
        """
        if not isinstance(other, Transform):
            raise TypeError(f"allclose needs a Transform, got {type(other).__name__}")
        dt = np.abs(self._translation - other._translation).max(axis=-1)
        dq = np.minimum(
            np.abs(self._rotation - other._rotation).max(axis=-1),
            np.abs(self._rotation + other._rotation).max(axis=-1),
        )
        return bool(np.all(dt <= atol) and np.all(dq <= atol))

    # -- algebra --------------------------------------------------------------

    def _paired(self, other: Transform, what: str):
        if not isinstance(other, Transform):
            raise TypeError(f"{what} needs a Transform, got {type(other).__name__}")
        try:
            return np.broadcast_shapes(self.shape, other.shape)
        except ValueError:
            raise ValueError(
                f"cannot {what} Transforms of batch shapes {self.shape} and {other.shape}"
            ) from None

    def __matmul__(self, other: Transform) -> Transform:
        """Composition: ``(self @ other).apply(p) == self.apply(other.apply(p))``."""
        if not isinstance(other, Transform):
            return NotImplemented
        shape = self._paired(other, "compose")
        k = _kq
        qa = rows(self._rotation, shape, 4)
        q = k.qmul(qa, rows(other._rotation, shape, 4))
        t = k.rotate_vectors(qa, rows(other._translation, shape, 3))
        t += rows(self._translation, shape, 3)
        return Transform._trusted(t.reshape(shape + (3,)), q.reshape(shape + (4,)))

    def inv(self) -> Transform:
        """The inverse: ``self.inv() @ self`` is the identity."""
        k = _kq
        q = k.qconj(kernel_array(self._rotation.reshape(-1, 4)))
        t = -k.rotate_vectors(q, kernel_array(self._translation.reshape(-1, 3)))
        return Transform._trusted(
            t.reshape(self.shape + (3,)), q.reshape(self.shape + (4,))
        )

    def _rotate(self, vectors, name: str, shift: bool) -> np.ndarray:
        v = _shapes.last_axis(vectors, name, 3)
        try:
            shape = np.broadcast_shapes(self.shape, v.shape[:-1])
        except ValueError:
            raise ValueError(
                f"{name} of shape {v.shape} do not broadcast against the Transform's "
                f"batch shape {self.shape}"
            ) from None
        out = _kq.rotate_vectors(rows(self._rotation, shape, 4), rows(v, shape, 3))
        if shift:
            out += rows(self._translation, shape, 3)
        return out.reshape(shape + (3,))

    def apply(self, points) -> np.ndarray:
        """Transform points: ``rot(r, p) + t``.

        Parameters
        ----------
        points : array_like, shape (..., 3)
            Leading shape broadcasts against the batch shape.

        Returns
        -------
        ndarray, shape (broadcast, 3)
        """
        return self._rotate(points, "points", shift=True)

    def apply_vectors(self, vectors) -> np.ndarray:
        """Transform free vectors (directions, velocities): rotation only.

        Parameters
        ----------
        vectors : array_like, shape (..., 3)

        Returns
        -------
        ndarray, shape (broadcast, 3)
        """
        return self._rotate(vectors, "vectors", shift=False)

    def as_matrix(self) -> np.ndarray:
        """Homogeneous matrices ``[[R, t], [0, 0, 0, 1]]``, shape (..., 4, 4)."""
        return homogeneous_from_transform(self._translation, self._rotation)

    # -- interpolation and differences -------------------------------------

    def _blend(self, other: Transform, ratio, what: str):
        shape = self._paired(other, what)
        r = finite_numbers(ratio)
        try:
            shape = np.broadcast_shapes(shape, r.shape)
        except ValueError:
            raise ValueError(
                f"ratio of shape {r.shape} does not broadcast against batch shape {shape}"
            ) from None
        r_rows = kernel_array(np.broadcast_to(r, shape)).reshape(-1)
        t = _interp.linear(
            rows(self._translation, shape, 3),
            rows(other._translation, shape, 3),
            r_rows,
        )
        q0, q1 = rows(self._rotation, shape, 4), rows(other._rotation, shape, 4)
        return shape, r_rows, t, q0, q1

    def slerp(self, other: Transform, ratio) -> Transform:
        """Interpolate towards ``other``: linear in translation, slerp in rotation.

        Parameters
        ----------
        other : Transform
        ratio : float or array_like
            0 gives ``self``, 1 gives ``other``; values outside [0, 1]
            extrapolate. Broadcasts against the batch shapes.

        Returns
        -------
        Transform
            The rotation follows the shorter arc at constant angular speed.
        """
        shape, r, t, q0, q1 = self._blend(other, ratio, "slerp")
        q = _interp.slerped(q0, q1, r)
        return Transform._trusted(t.reshape(shape + (3,)), q.reshape(shape + (4,)))

    def lerp(self, other: Transform, ratio) -> Transform:
        """Interpolate towards ``other`` linearly (normalised lerp for rotations).

        Cheaper than ``slerp`` and on the same shorter arc, but the angular
        speed is not constant.

        Parameters
        ----------
        other : Transform
        ratio : float or array_like
            As in ``slerp``.
        """
        shape, r, t, q0, q1 = self._blend(other, ratio, "lerp")
        q = _interp.lerped(q0, q1, r)
        return Transform._trusted(t.reshape(shape + (3,)), q.reshape(shape + (4,)))

    def difference(
        self,
        other: Transform,
        *,
        position_mask=True,
        rotation_mask=True,
        rotation_mirror: str | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Position and rotation of ``other`` relative to ``self``, in ``self``'s axes.

        The position difference is ``rot(r_self⁻¹, t_other - t_self)`` and the
        rotation difference the rotation vector of ``r_self⁻¹ r_other``: both
        are zero when the two coincide and are what a controller moving
        ``self`` onto ``other`` would act on.

        Parameters
        ----------
        other : Transform
        position_mask, rotation_mask : bool, None, str or array_like of 3
            Which components to keep: True (all, the default), False or None
            (none), a string of axes such as ``"xy"``, or three 0/1 flags.
            Dropped components are returned as 0.
        rotation_mirror : {"x", "y", "z"}, optional
            Treat ``other`` rotated by 180° about its own axis of that name as
            equally good, and report whichever of the two is closer (for
            symmetric objects).

        Returns
        -------
        position : ndarray, shape (..., 3)
        rotation : ndarray, shape (..., 3)
            Rotation vector, angle in [0, pi].
        """
        shape = self._paired(other, "difference")
        pmask = axis_mask(position_mask, "position_mask")
        rmask = axis_mask(rotation_mask, "rotation_mask")
        mirror = None if rotation_mirror is None else mirror_axis(rotation_mirror)
        position, rotation = _diff.difference(
            rows(self._translation, shape, 3),
            rows(self._rotation, shape, 4),
            rows(other._translation, shape, 3),
            rows(other._rotation, shape, 4),
            mirror,
        )
        # "+ 0.0" turns the -0.0 of masked-out negative components into 0.0
        position = position * pmask + 0.0
        rotation = rotation * rmask + 0.0
        return position.reshape(shape + (3,)), rotation.reshape(shape + (3,))
