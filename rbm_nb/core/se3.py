"""Velocity, differential-motion and interpolation tools on SE(3) matrices, batched.

The functions carry the names (and argument order) of their counterparts in
spatialmath-python's ``spatialmath.base``, so code written against it ports
by changing the import. Unlike there, every argument may be a stack: the
trailing axes hold one value (``(4, 4)`` pose, ``(3, 3)`` rotation, ``(3,)``
angle triple or vector, ``(6,)`` differential motion, ``(4,)`` quaternion)
and any leading axes are looped over by numba kernels
(:mod:`rbm_nb._kernels.se3`). A single value in gives a single value out.

The module is called ``se3`` because everything in it works on homogeneous
4 x 4 matrices and their tangent space (rotation rates, differential
motions, adjoints); the quaternion-first API lives in
:mod:`rbm_nb.quaternions` and :mod:`rbm_nb.conversions`.

Conventions (those of spatialmath unless stated)
------------------------------------------------
* Angles are in radians; a differential motion is ``(dx, dy, dz, rx, ry, rz)``.
* ``rpy2jac(angles, order)`` takes ``angles = (roll, pitch, yaw)``. With
  ``order="zyx"`` (the default) the rotation is ``Rz(yaw) Ry(pitch) Rx(roll)``;
  with ``"xyz"`` it is ``Rx(yaw) Ry(pitch) Rz(roll)``, with ``"yxz"``
  ``Ry(yaw) Rx(pitch) Rz(roll)``. ``rotvelxform``'s default representation is
  ``"rpy/xyz"``, *not* ``rpy2jac``'s ``"zyx"``: both defaults are spatialmath's.
* Euler angles are ZYZ, ``Rz(phi) Ry(theta) Rz(psi)``.
* Quaternions are ``w, x, y, z``.

Deliberate differences from spatialmath
---------------------------------------
* The inverse Jacobians (``rotvelxform(..., inverse=True)``) raise a
  :class:`SingularityError` naming the row and the angle at a singular
  attitude (pitch = ±90° for RPY, theta = 0 or 180° for ZYZ Euler, a
  rotation by a non-zero multiple of 360° for exponential coordinates)
  instead of returning ``inf``/``nan``.
* The exponential-coordinate maps use their Taylor series near the origin,
  so ``rotvelxform(0, inverse=True, representation="exp")`` is the identity
  (spatialmath returns ``nan`` there) and small angles keep full precision.
* ``qlog`` of a negative real quaternion returns the vector part
  ``(pi, 0, 0)`` (a valid logarithm); spatialmath returns a zero vector part.
* ``trinterp`` also accepts an array of fractions or a number of steps, and
  pose stacks broadcast against the fractions.
* ``skew``/``vex`` are three-dimensional only (no so(2) case).
"""

from __future__ import annotations

import numpy as np

from .._door import poses as _poses
from .._door import shapes as _shapes
from .._door.unpack import kernel_array
from .._infra.config import UNIT_QUATERNION_TOLERANCE
from .._kernels import conversions as _kc
from .._kernels import se3
from . import conversions

__all__ = [
    "REPRESENTATIONS",
    "SingularityError",
    "delta2tr",
    "eul2jac",
    "exp2jac",
    "qexp",
    "qlog",
    "rotvelxform",
    "rpy2jac",
    "skew",
    "tr2adjoint",
    "tr2delta",
    "trinterp",
    "trnorm",
    "vex",
]

#: Names accepted as ``representation`` by :func:`rotvelxform`, with aliases.
REPRESENTATIONS = {
    "rpy/xyz": 0,
    "arm": 0,
    "rpy/zyx": 1,
    "vehicle": 1,
    "rpy/yxz": 2,
    "camera": 2,
    "eul": 3,
    "exp": 4,
}

#: Default tolerance of the singularity test of the inverse Jacobians.
SINGULARITY_TOLERANCE = 1e-12

# Tolerance on how far a pose's rotation block may be from SO(3).
_ROTATION_TOLERANCE = 1e-6


class SingularityError(ValueError):
    """An inverse Jacobian was asked for at an attitude where it does not exist."""


def _kernels():
    return se3


# ---------------------------------------------------------------------------
# skew / vex
# ---------------------------------------------------------------------------


def skew(v) -> np.ndarray:
    """Skew-symmetric matrices of 3-vectors: ``skew(v) @ u == cross(v, u)``.

    Parameters
    ----------
    v : array_like, shape (..., 3)

    Returns
    -------
    ndarray, shape (..., 3, 3)

    Examples
    --------
    >>> from rbm_nb.se3 import skew
    >>> skew([1, 2, 3])
    array([[ 0., -3.,  2.],
           [ 3.,  0., -1.],
           [-2.,  1.,  0.]])
    """
    rows, lead = _shapes.rows(v, "v", (3,), finite=True)
    return _kernels().skew(rows).reshape(lead + (3, 3))


def vex(s) -> np.ndarray:
    """The 3-vectors of skew-symmetric matrices (inverse of :func:`skew`).

    For a matrix that is not exactly skew-symmetric this is the vector of
    its antisymmetric part ``(S - Sᵀ) / 2``, as in spatialmath.

    Parameters
    ----------
    s : array_like, shape (..., 3, 3)

    Returns
    -------
    ndarray, shape (..., 3)

    Examples
    --------
    >>> from rbm_nb.se3 import skew, vex
    >>> vex(skew([[1, 2, 3], [4, 5, 6]]))
    array([[1., 2., 3.],
           [4., 5., 6.]])
    """
    rows, lead = _shapes.rows(s, "s", (3, 3), finite=True)
    return _kernels().vex(rows).reshape(lead + (3,))


# ---------------------------------------------------------------------------
# differential motion and adjoint
# ---------------------------------------------------------------------------


def tr2delta(T0, T1=None) -> np.ndarray:
    """Differential motion from pose ``T0`` to pose ``T1``, in the ``T0`` frame.

    With ``inv(T0) @ T1 = [[R, p], [0, 1]]`` the result is ``(p, vex(R - I))``:
    a first-order approximation of the motion, good when the two poses are
    close (it approximates the spatial velocity times the time step).

    Parameters
    ----------
    T0 : array_like, shape (..., 4, 4)
        Start poses. With ``T1`` omitted, the motion from the identity to ``T0``.
    T1 : array_like, shape (..., 4, 4), optional
        End poses; the leading shapes of ``T0`` and ``T1`` broadcast.
        The rotation blocks need not be orthonormal (first-order poses from
        :func:`delta2tr` are accepted, as in spatialmath).

    Returns
    -------
    ndarray, shape (..., 6)
        ``(dx, dy, dz, rx, ry, rz)``.

    Raises
    ------
    ValueError
        If a matrix's last row is not (0, 0, 0, 1) or a value is not finite.

    Examples
    --------
    >>> import numpy as np
    >>> from rbm_nb.se3 import delta2tr, tr2delta
    >>> T0 = np.eye(4)
    >>> T1 = delta2tr([0.01, 0, 0, 0, 0, 0.002])
    >>> tr2delta(T0, T1).round(6)
    array([0.01 , 0.   , 0.   , 0.   , 0.   , 0.002])
    """
    k = _kernels()
    args = _poses.delta_input(T0, T1, _ROTATION_TOLERANCE)
    return k.tr2delta(args.a, args.b).reshape(args.lead + (6,))


def delta2tr(d) -> np.ndarray:
    """Poses of differential motions: ``I + [[skew(r), p], [0, 0]]``.

    The inverse of :func:`tr2delta` to first order; the rotation block is
    *not* orthonormal (use :func:`trnorm` to make it so).

    Parameters
    ----------
    d : array_like, shape (..., 6)
        ``(dx, dy, dz, rx, ry, rz)``.

    Returns
    -------
    ndarray, shape (..., 4, 4)

    Examples
    --------
    >>> from rbm_nb.se3 import delta2tr
    >>> delta2tr([0.001, 0, 0, 0, 0.002, 0]) + 0.0  # + 0.0 turns -0. into 0.
    array([[ 1.   ,  0.   ,  0.002,  0.001],
           [ 0.   ,  1.   ,  0.   ,  0.   ],
           [-0.002,  0.   ,  1.   ,  0.   ],
           [ 0.   ,  0.   ,  0.   ,  1.   ]])
    """
    rows, lead = _shapes.rows(d, "d", (6,), finite=True)
    return _kernels().delta2tr(rows).reshape(lead + (4, 4))


def tr2adjoint(T) -> np.ndarray:
    """Adjoint matrices of poses: ``[[R, skew(t) R], [0, R]]``.

    For ``T`` the pose of frame {B} in frame {A}, the adjoint maps a spatial
    velocity or differential motion ``(v, w)`` of a body expressed in {B}
    to the same motion expressed in {A}. For a rotation matrix the adjoint
    is the matrix itself.

    Parameters
    ----------
    T : array_like, shape (..., 4, 4) or (..., 3, 3)

    Returns
    -------
    ndarray, shape (..., 6, 6) or (..., 3, 3)

    Examples
    --------
    >>> import numpy as np
    >>> from rbm_nb.se3 import tr2adjoint
    >>> T = np.eye(4); T[:3, 3] = [1, 0, 0]
    >>> tr2adjoint(T)[:3, 3:]
    array([[ 0.,  0.,  0.],
           [ 0.,  0., -1.],
           [ 0.,  1.,  0.]])
    """
    args = _poses.adjoint_input(T, _ROTATION_TOLERANCE)
    if args.rotation_only:
        return args.rows.reshape(args.lead + (3, 3)).copy()
    return _kernels().tr2adjoint(args.rows).reshape(args.lead + (6, 6))


# ---------------------------------------------------------------------------
# rates -> angular velocity
# ---------------------------------------------------------------------------


def _representation(representation) -> int:
    try:
        return REPRESENTATIONS[representation]
    except (KeyError, TypeError):
        raise ValueError(
            f"representation must be one of {sorted(REPRESENTATIONS)}, "
            f"got {representation!r}"
        ) from None


def _angles_of_rotations(rot: np.ndarray, code: int) -> np.ndarray:
    """spatialmath's ``r2x``: the angle triple of each rotation matrix (rows
    (n, 3, 3) the door checked: rotations, so the conversion kernels are
    called directly, as the public conversions call them after their door)."""
    q, invalid = _kc.quaternion_from_matrix(rot, conversions.MATRIX_TOLERANCE)
    if invalid:
        # (not a rotation within the conversions' own test: their message)
        conversions.quaternion_from_matrix(rot)
    if code == 4:
        out, _ = _kc.rotation_vector_from_quaternion(q, UNIT_QUATERNION_TOLERANCE)
        return out
    # RPY (roll, pitch, yaw) about (z, y, x) of "xyz" etc. are the intrinsic
    # Euler angles of the reversed sequence, read backwards.
    order = {0: "xyz", 1: "zyx", 2: "yxz", 3: "zyz"}[code]
    i, j, k = ("xyz".index(c) for c in order)
    out, _ = _kc.euler_from_quaternion(q, i, j, k, False, UNIT_QUATERNION_TOLERANCE)
    return out if code == 3 else np.ascontiguousarray(out[:, ::-1])


_SINGULAR_WHAT = {
    0: ("pitch", "cos(pitch) = 0 (pitch = ±90°)"),
    1: ("pitch", "cos(pitch) = 0 (pitch = ±90°)"),
    2: ("pitch", "cos(pitch) = 0 (pitch = ±90°)"),
    3: ("theta", "sin(theta) = 0 (theta = 0 or ±180°)"),
    4: ("rotation angle", "the rotation angle is a non-zero multiple of 360°"),
}


def rotvelxform(
    Γ,
    inverse: bool = False,
    full: bool = False,
    representation: str = "rpy/xyz",
    *,
    tol: float = SINGULARITY_TOLERANCE,
) -> np.ndarray:
    """Matrices mapping angle-representation rates to angular velocity (or back).

    ``omega = A(Γ) @ dΓ/dt``; with ``inverse=True`` the closed-form ``A⁻¹``.

    Parameters
    ----------
    Γ : array_like, shape (..., 3) or (..., 3, 3)
        Angle triples in the chosen representation (radians), or rotation
        matrices, which are first converted to it (a trailing (3, 3) shape is
        always read as rotation matrices, as in spatialmath: pass three angle
        triples as shape (3, 1, 3)).
    inverse : bool, default False
        Return ``A⁻¹``, mapping angular velocity to representation rates.
    full : bool, default False
        Return the 6 x 6 block-diagonal ``diag(I, A)`` acting on ``(v, w)``.
    representation : str, default "rpy/xyz"
        ``"rpy/xyz"`` (``"arm"``), ``"rpy/zyx"`` (``"vehicle"``),
        ``"rpy/yxz"`` (``"camera"``), ``"eul"`` (ZYZ) or ``"exp"``
        (exponential coordinates / rotation vector).
    tol : float, default 1e-12
        With ``inverse``, an attitude counts as singular when the vanishing
        quantity (cos pitch, sin theta, or the distance of the rotation angle
        from a non-zero multiple of 2 pi) is within ``tol``.

    Returns
    -------
    ndarray, shape (..., 3, 3) or (..., 6, 6)

    Raises
    ------
    SingularityError
        With ``inverse``, at a singular attitude; the message names the
        first such row and its angle.
    ValueError
        For an unknown representation, a bad shape, non-finite values or a
        matrix that is not a rotation.

    Examples
    --------
    >>> from rbm_nb.se3 import rotvelxform
    >>> rotvelxform([0.1, 0.2, 0.3], representation="rpy/zyx").round(4)
    array([[ 0.9363, -0.2955,  0.    ],
           [ 0.2896,  0.9553,  0.    ],
           [-0.1987,  0.    ,  1.    ]])
    >>> rotvelxform([0.1, 1.5707963267948966, 0.3], inverse=True)
    Traceback (most recent call last):
    ...
    rbm_nb.core.se3.SingularityError: rotvelxform(inverse=True, representation='rpy/xyz') is singular at Γ: pitch = 90°, where cos(pitch) = 0 (pitch = ±90°)
    """
    code = _representation(representation)
    args = _poses.rates_input(Γ, tol, _ROTATION_TOLERANCE)
    lead = args.lead
    if args.rotation_only:
        angles = kernel_array(_angles_of_rotations(args.rows, code))
    else:
        angles = args.rows
    out, bad = _kernels().rotvelxform(angles, code, bool(inverse), float(tol))
    if bad >= 0:
        what, why = _SINGULAR_WHAT[code]
        row = angles[bad]
        value = np.linalg.norm(row) if code == 4 else row[1]
        raise SingularityError(
            f"rotvelxform(inverse=True, representation={representation!r}) is "
            f"singular at Γ{_shapes.where(lead, bad)}: {what} = {np.rad2deg(value):.6g}°, "
            f"where {why}"
        )
    if full:
        big = np.zeros((len(out), 6, 6))
        big[:, 0, 0] = big[:, 1, 1] = big[:, 2, 2] = 1.0
        big[:, 3:, 3:] = out
        return big.reshape(lead + (6, 6))
    return out.reshape(lead + (3, 3))


def eul2jac(angles) -> np.ndarray:
    """Jacobians mapping ZYZ Euler angle rates to angular velocity.

    Same as ``rotvelxform(angles, representation="eul")``.

    Parameters
    ----------
    angles : array_like, shape (..., 3)
        ``(phi, theta, psi)`` in radians.

    Returns
    -------
    ndarray, shape (..., 3, 3)

    Examples
    --------
    >>> from rbm_nb.se3 import eul2jac
    >>> eul2jac([0.1, 0.2, 0.3]).round(4)
    array([[ 0.    , -0.0998,  0.1977],
           [ 0.    ,  0.995 ,  0.0198],
           [ 1.    ,  0.    ,  0.9801]])
    """
    return _forward(angles, 3)


def rpy2jac(angles, order: str = "zyx") -> np.ndarray:
    """Jacobians mapping roll-pitch-yaw angle rates to angular velocity.

    Same as ``rotvelxform(angles, representation="rpy/" + order)``.

    Parameters
    ----------
    angles : array_like, shape (..., 3)
        ``(roll, pitch, yaw)`` in radians.
    order : {"zyx", "xyz", "yxz"}, default "zyx"
        Rotation order, see the module notes.

    Returns
    -------
    ndarray, shape (..., 3, 3)

    Examples
    --------
    >>> from rbm_nb.se3 import rpy2jac
    >>> rpy2jac([0.1, 0.2, 0.3]).round(4)
    array([[ 0.9363, -0.2955,  0.    ],
           [ 0.2896,  0.9553,  0.    ],
           [-0.1987,  0.    ,  1.    ]])
    """
    codes = {"xyz": 0, "zyx": 1, "yxz": 2}
    if order not in codes:
        raise ValueError(f"order must be 'zyx', 'xyz' or 'yxz', got {order!r}")
    return _forward(angles, codes[order])


def exp2jac(v) -> np.ndarray:
    """Jacobians mapping exponential-coordinate rates to angular velocity.

    Same as ``rotvelxform(v, representation="exp")``; the identity at ``v = 0``.

    Parameters
    ----------
    v : array_like, shape (..., 3)
        Rotation vectors (axis times angle, radians).

    Returns
    -------
    ndarray, shape (..., 3, 3)

    Examples
    --------
    >>> from rbm_nb.se3 import exp2jac
    >>> exp2jac([0.3, 0, 0]).round(4)
    array([[ 1.    ,  0.    ,  0.    ],
           [ 0.    ,  0.9851, -0.1489],
           [ 0.    ,  0.1489,  0.9851]])
    """
    return _forward(v, 4)


def _forward(angles, code: int) -> np.ndarray:
    rows, lead = _shapes.rows(angles, "angles", (3,), finite=True)
    out, _ = _kernels().rotvelxform(rows, code, False, 0.0)
    return out.reshape(lead + (3, 3))


# ---------------------------------------------------------------------------
# normalisation and interpolation
# ---------------------------------------------------------------------------


def trnorm(T) -> np.ndarray:
    """Make the rotation block of poses (or rotation matrices) orthonormal.

    spatialmath's recipe: keep the direction of the z column ``a``, take
    ``n = o x a`` and ``o = a x n`` and normalise the three columns. The
    translation is unchanged.

    Parameters
    ----------
    T : array_like, shape (..., 4, 4) or (..., 3, 3)

    Returns
    -------
    ndarray, same shape as ``T``

    Raises
    ------
    ValueError
        If a matrix's y and z columns are parallel or zero (no frame can be
        built from them), or a value is not finite.

    Examples
    --------
    >>> import numpy as np
    >>> from rbm_nb.se3 import trnorm
    >>> R = np.array([[1, 0.01, 0], [0, 1, 0], [0, 0, 1.02]])
    >>> R1 = trnorm(R)
    >>> bool(np.allclose(R1.T @ R1, np.eye(3)))
    True
    """
    args = _poses.normalisable(T)
    rows, lead = args.rows, args.lead
    tail = (3, 3) if args.rotation_only else (4, 4)
    out, bad = _kernels().trnorm(rows)
    if bad >= 0:
        raise ValueError(
            f"T{_shapes.where(lead, bad)} cannot be normalised: its y and z columns are "
            "parallel or zero"
        )
    return out.reshape(lead + tail)


def trinterp(start, end, s, shortest: bool = True) -> np.ndarray:
    """Interpolate poses: slerp the rotation, lerp the translation.

    Parameters
    ----------
    start : array_like, shape (..., 4, 4) or (..., 3, 3), or None
        Pose at ``s = 0``; None means the identity.
    end : array_like, same trailing shape as ``start``
        Pose at ``s = 1``.
    s : float, array_like or int
        Fraction(s) in [0, 1]. An integer ``m > 1`` means ``m`` evenly spaced
        steps ``linspace(0, 1, m)`` (as spatialmath's ``SE3.interp``); note
        that ``0`` and ``1`` as integers are fractions. The shape of ``s``
        broadcasts against the leading shapes of ``start`` and ``end``: one
        pose pair with ``m`` fractions gives ``m`` poses, ``n`` pairs with one
        fraction ``n`` poses.
    shortest : bool, default True
        Rotate along the shorter arc. With False the arc depends on the sign
        of each endpoint's quaternion; as in spatialmath, the quaternion of a
        matrix is the one whose largest-magnitude component is positive.
        (The quaternions are computed in the kernel, Shepperd's method.)

    Returns
    -------
    ndarray, shape (..., 4, 4) or (..., 3, 3)
        The broadcast shape of the inputs and ``s``.

    Raises
    ------
    ValueError
        If ``s`` is outside [0, 1], a matrix is not a pose/rotation, or the
        shapes do not broadcast.

    Examples
    --------
    >>> import numpy as np
    >>> from rbm_nb.se3 import trinterp
    >>> T1 = np.eye(4); T1[:3, 3] = [1, 2, 3]
    >>> T2 = np.eye(4); T2[:3, 3] = [4, 5, 6]
    >>> trinterp(T1, T2, 0.5)[:3, 3]
    array([2.5, 3.5, 4.5])
    >>> trinterp(None, T2, 3)[:, :3, 3]
    array([[0. , 0. , 0. ],
           [2. , 2.5, 3. ],
           [4. , 5. , 6. ]])
    """
    args = _poses.interpolation_input(start, end, s, _ROTATION_TOLERANCE)
    lead, rotation_only = args.lead, args.rotation_only
    out = _kernels().trinterp(args.a, args.b, args.f, bool(shortest))
    if rotation_only:
        return np.ascontiguousarray(out[:, :3, :3]).reshape(lead + (3, 3))
    return out.reshape(lead + (4, 4))


# ---------------------------------------------------------------------------
# quaternion exp / log
# ---------------------------------------------------------------------------


def qexp(q) -> np.ndarray:
    """Exponential of quaternions (any norm), ``w, x, y, z``.

    ``exp(w + v) = e^w (cos|v| + v/|v| sin|v|)``; for a pure quaternion
    ``(0, θ/2 u)`` this is the unit quaternion of a rotation by θ about u.

    Parameters
    ----------
    q : array_like, shape (..., 4)

    Returns
    -------
    ndarray, shape (..., 4)

    Examples
    --------
    >>> import numpy as np
    >>> from rbm_nb.se3 import qexp
    >>> qexp([0, np.pi / 4, 0, 0]).round(6)
    array([0.707107, 0.707107, 0.      , 0.      ])
    """
    rows, lead = _shapes.rows(q, "q", (4,), finite=True)
    return _kernels().qexp(rows).reshape(lead + (4,))


def qlog(q) -> np.ndarray:
    """Principal logarithm of non-zero quaternions, ``w, x, y, z``.

    ``log(q) = (log|q|, atan2(|v|, w) v/|v|)``; for a unit quaternion the
    vector part is half the rotation vector. A negative real quaternion
    gets the vector part ``(pi, 0, 0)``.

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Non-zero quaternions.

    Returns
    -------
    ndarray, shape (..., 4)

    Raises
    ------
    ValueError
        For a zero quaternion (its logarithm does not exist).

    Examples
    --------
    >>> import numpy as np
    >>> from rbm_nb.se3 import qlog
    >>> qlog([np.cos(0.3), np.sin(0.3), 0, 0]).round(6) + 0.0
    array([0. , 0.3, 0. , 0. ])
    """
    rows, lead = _shapes.rows(q, "q", (4,), finite=True)
    zero = ~rows.any(axis=1)
    if zero.any():
        raise ValueError(
            f"q{_shapes.where(lead, int(np.argmax(zero)))} is zero: it has no logarithm"
        )
    return _kernels().qlog(rows).reshape(lead + (4,))
