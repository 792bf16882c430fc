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
from .._door.validation import check_finite, normalize_quaternions
from .._kernels import quaternion as _kq
from . import _pose_algebra as _pa
from .conversions import (
    MATRIX_TOLERANCE,
    homogeneous_from_transform,
    rotation_vector_from_quaternion,
    transform_from_homogeneous,
)

__all__ = ["Transform"]

_AXES = "xyz"


def _unit_rotation(rotation) -> np.ndarray:
    return normalize_quaternions(_shapes.last_axis(rotation, "rotation", 4), "rotation")


def _finite_translation(translation) -> np.ndarray:
    t = _shapes.last_axis(translation, "translation", 3)
    check_finite(t, "translation")
    return t


def _ratio(ratio, name: str = "ratio") -> np.ndarray:
    try:
        r = np.asarray(ratio, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise ValueError(f"{name} must be a number or an array of numbers") from err
    if not np.isfinite(r).all():
        raise ValueError(f"{name} must be finite, got {ratio!r}")
    return r


def _array_text(arr: np.ndarray, prefix: str) -> str:
    return np.array2string(
        arr,
        precision=6,
        suppress_small=True,
        separator=", ",
        threshold=12,
        edgeitems=2,
        prefix=prefix,
    )


def _read_only(arr: np.ndarray) -> np.ndarray:
    arr = np.ascontiguousarray(arr)
    arr.flags.writeable = False
    return arr


def _mask(mask, name: str) -> np.ndarray:
    """A 0/1 weight per axis from True/False/None, 'xz'-style strings or 3 flags."""
    if mask is True:
        return np.ones(3)
    if mask is False or mask is None:
        return np.zeros(3)
    if isinstance(mask, str):
        letters = mask.lower()
        if not letters or any(c not in _AXES for c in letters):
            raise ValueError(f"{name} must use the letters x, y, z, got {mask!r}")
        return np.array([float(c in letters) for c in _AXES])
    arr = np.asarray(mask)
    if arr.shape != (3,) or not np.isin(arr, (0, 1)).all():
        raise ValueError(
            f"{name} must be True, False, None, a string of axes such as 'xy' or "
            f"three 0/1 flags, got {mask!r}"
        )
    return arr.astype(np.float64)


def _rows(arr: np.ndarray, shape: tuple, width: int) -> np.ndarray:
    return kernel_array(np.broadcast_to(arr, shape + (width,))).reshape(-1, width)


class Transform:
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
        t = _finite_translation(translation)
        q = _unit_rotation(rotation)
        try:
            shape = np.broadcast_shapes(t.shape[:-1], q.shape[:-1])
        except ValueError:
            raise ValueError(
                f"translation of shape {t.shape} and rotation of shape {q.shape} "
                "have batch shapes that do not broadcast"
            ) from None
        # np.array copies: the caller's arrays must not alias ours
        object.__setattr__(
            self, "_translation", _read_only(np.array(np.broadcast_to(t, shape + (3,))))
        )
        object.__setattr__(
            self, "_rotation", _read_only(np.array(np.broadcast_to(q, shape + (4,))))
        )

    @classmethod
    def _trusted(cls, translation: np.ndarray, rotation: np.ndarray) -> Transform:
        """Wrap arrays that are already valid (results of our own arithmetic)."""
        new = object.__new__(cls)
        object.__setattr__(new, "_translation", _read_only(translation))
        object.__setattr__(new, "_rotation", _read_only(rotation))
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
        t = _array_text(self._translation, "    translation=")
        r = _array_text(self._rotation, "    rotation=")
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
        qa = _rows(self._rotation, shape, 4)
        q = k.qmul(qa, _rows(other._rotation, shape, 4))
        t = k.rotate_vectors(qa, _rows(other._translation, shape, 3))
        t += _rows(self._translation, shape, 3)
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
        out = _kq.rotate_vectors(_rows(self._rotation, shape, 4), _rows(v, shape, 3))
        if shift:
            out += _rows(self._translation, shape, 3)
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
        r = _ratio(ratio)
        try:
            shape = np.broadcast_shapes(shape, r.shape)
        except ValueError:
            raise ValueError(
                f"ratio of shape {r.shape} does not broadcast against batch shape {shape}"
            ) from None
        r_rows = kernel_array(np.broadcast_to(r, shape)).reshape(-1)
        t0 = _rows(self._translation, shape, 3)
        t1 = _rows(other._translation, shape, 3)
        t = t0 + r_rows[:, None] * (t1 - t0)
        return shape, r_rows, t

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
        shape, r, t = self._blend(other, ratio, "slerp")
        q = _kq.slerp(
            _rows(self._rotation, shape, 4), _rows(other._rotation, shape, 4), r
        )
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
        shape, r, t = self._blend(other, ratio, "lerp")
        q0 = _rows(self._rotation, shape, 4)
        q1 = _rows(other._rotation, shape, 4)
        q1 = np.where(np.einsum("ij,ij->i", q0, q1)[:, None] < 0.0, -q1, q1)
        q = q0 + r[:, None] * (q1 - q0)
        norm = np.linalg.norm(q, axis=1, keepdims=True)
        if not np.all(norm > 0.0):
            raise ValueError(
                "lerp passes through a zero quaternion for this ratio; use slerp"
            )
        return Transform._trusted(
            t.reshape(shape + (3,)), (q / norm).reshape(shape + (4,))
        )

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
        pmask = _mask(position_mask, "position_mask")
        rmask = _mask(rotation_mask, "rotation_mask")
        k = _kq
        q_inv = k.qconj(_rows(self._rotation, shape, 4))
        offset = _rows(other._translation, shape, 3) - _rows(
            self._translation, shape, 3
        )
        position = k.rotate_vectors(q_inv, offset)
        q_rel = k.qmul(q_inv, _rows(other._rotation, shape, 4))
        rotation = rotation_vector_from_quaternion(q_rel)
        if rotation_mirror is not None:
            if rotation_mirror not in ("x", "y", "z"):
                raise ValueError(
                    f"rotation_mirror must be 'x', 'y', 'z' or None, got {rotation_mirror!r}"
                )
            half_turn = np.zeros((1, 4))
            half_turn[0, 1 + _AXES.index(rotation_mirror)] = 1.0
            mirrored = rotation_vector_from_quaternion(k.qmul(q_rel, half_turn))
            closer = np.linalg.norm(mirrored, axis=1) < np.linalg.norm(rotation, axis=1)
            rotation = np.where(closer[:, None], mirrored, rotation)
        # "+ 0.0" turns the -0.0 of masked-out negative components into 0.0
        position = position * pmask + 0.0
        rotation = rotation * rmask + 0.0
        return position.reshape(shape + (3,)), rotation.reshape(shape + (3,))

    # -- pose algebra (scikit-robot's Coordinates methods, immutable) -------

    def _reference(self, wrt, what: str):
        """``wrt`` as "local", "world" ("parent" is the same) or a Transform whose axes are meant."""
        if isinstance(wrt, Transform):
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

    def translate(self, vec, wrt="local") -> Transform:
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
        v = _finite_translation(vec)
        ref = self._reference(wrt, "translate")
        k = _kq
        if ref == "world":
            shape = self._batch_shape("translate", v.shape[:-1])
            offset = _rows(v, shape, 3)
        else:
            axes = self if ref == "local" else ref
            extra = () if ref == "local" else (axes.shape,)
            shape = self._batch_shape("translate", v.shape[:-1], *extra)
            offset = k.rotate_vectors(
                _rows(axes._rotation, shape, 4), _rows(v, shape, 3)
            )
        t = _rows(self._translation, shape, 3) + offset
        q = _rows(self._rotation, shape, 4)
        return Transform._trusted(t.reshape(shape + (3,)), q.reshape(shape + (4,)))

    def rotate(self, angle, axis, wrt="local") -> Transform:
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
        theta = _ratio(angle, "angle")
        ax = _pa.axis_vectors(axis, "axis")
        ref = self._reference(wrt, "rotate")
        extra = (ref.shape,) if isinstance(ref, Transform) else ()
        shape = self._batch_shape("rotate", theta.shape, ax.shape[:-1], *extra)
        pa = _pa
        unit = pa.unit_rows(_rows(ax, shape, 3), "axis")
        turn = pa.quaternion_rows_from_axis_angle(
            unit, np.broadcast_to(theta, shape).reshape(-1)
        )
        k = _kq
        q = _rows(self._rotation, shape, 4)
        if ref == "local":
            q = k.qmul(q, turn)
        elif ref == "world":
            q = k.qmul(turn, q)
        else:
            qw = _rows(ref._rotation, shape, 4)
            q = k.qmul(k.qmul(k.qmul(qw, turn), k.qconj(qw)), q)
        t = _rows(self._translation, shape, 3)
        return Transform._trusted(t.reshape(shape + (3,)), q.reshape(shape + (4,)))

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
        """One transformation applied to many points as a matrix product (BLAS).

        For a single pose and a large cloud this is several times faster than
        rotating every point by the quaternion, and what scikit-robot does.
        """
        p = _shapes.last_axis(points, "points", 3)
        rot = homogeneous_from_transform(self._translation, self._rotation)[:3, :3]
        rows = p.reshape(-1, 3).T  # (3, n): one BLAS call on the long axis
        if inverse:
            out = rot.T @ (rows - self._translation[:, None])
        else:
            out = rot @ rows + self._translation[:, None]
        return out.T.reshape(p.shape)

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

    def difference_position(self, other: Transform, position_mask=True) -> np.ndarray:
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
        mask = _mask(position_mask, "position_mask")
        k = _kq
        offset = _rows(other._translation, shape, 3) - _rows(
            self._translation, shape, 3
        )
        position = k.rotate_vectors(k.qconj(_rows(self._rotation, shape, 4)), offset)
        # "+ 0.0" turns the -0.0 of masked-out negative components into 0.0
        return (position * mask + 0.0).reshape(shape + (3,))

    def difference_rotation(
        self, other: Transform, rotation_mask=True, rotation_mirror: str | None = None
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
        mask = _mask(rotation_mask, "rotation_mask")
        k = _kq
        q_self = _rows(self._rotation, shape, 4)
        q_other = _rows(other._rotation, shape, 4)
        if rotation_mirror is not None:
            if rotation_mirror not in ("x", "y", "z"):
                raise ValueError(
                    f"rotation_mirror must be 'x', 'y', 'z' or None, got {rotation_mirror!r}"
                )
            e = np.zeros((1, 3))
            e[0, _AXES.index(rotation_mirror)] = 1.0
            a0 = k.rotate_vectors(q_self, np.repeat(e, len(q_self), axis=0))
            a1 = k.rotate_vectors(q_other, np.repeat(e, len(q_other), axis=0))
            cos = np.clip(np.einsum("ij,ij->i", a0, a1), -1.0, 1.0)
            # a zero cross product makes both candidate angles 0 in
            # scikit-robot's rule, and "0 < 0" is false: the mirror is used.
            # Whether rounding leaves the cross product at exactly 0 is luck,
            # so (anti-)parallel within PARALLEL_TOLERANCE counts as parallel
            cross = np.linalg.norm(np.cross(a0, a1), axis=1)
            parallel = cross < _pa.PARALLEL_TOLERANCE
            keep = (np.arccos(cos) < np.arccos(-cos)) & ~parallel
            half_turn = np.zeros((1, 4))
            half_turn[0, 1 + _AXES.index(rotation_mirror)] = 1.0
            turned = k.qmul(q_other, np.repeat(half_turn, len(q_other), axis=0))
            q_other = np.where(keep[:, None], q_other, turned)
        rotation = rotation_vector_from_quaternion(k.qmul(k.qconj(q_self), q_other))
        return (rotation * mask + 0.0).reshape(shape + (3,))

    def align_axis_to_direction(self, direction, axis="z", wrt="world") -> Transform:
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
        pa = _pa
        d = pa.axis_vectors(direction, "direction")
        ax = pa.axis_vectors(axis, "axis")
        ref = self._reference(wrt, "align_axis_to_direction")
        extra = (ref.shape,) if isinstance(ref, Transform) else ()
        shape = self._batch_shape(
            "align_axis_to_direction", d.shape[:-1], ax.shape[:-1], *extra
        )
        k = _kq
        q = _rows(self._rotation, shape, 4)
        target = pa.unit_rows(_rows(d, shape, 3), "direction")
        if ref == "local":
            target = k.rotate_vectors(q, target)
        elif isinstance(ref, Transform):
            target = k.rotate_vectors(_rows(ref._rotation, shape, 4), target)
        current = k.rotate_vectors(q, pa.unit_rows(_rows(ax, shape, 3), "axis"))
        q = k.qmul(pa.shortest_arc_rows(current, target), q)
        t = _rows(self._translation, shape, 3)
        return Transform._trusted(t.reshape(shape + (3,)), q.reshape(shape + (4,)))
