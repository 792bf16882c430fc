"""Conversions between rotation representations, batched over leading axes.

Every function takes array_like input whose *last* axes hold one rotation
(``(..., 4)`` quaternions, ``(..., 3, 3)`` matrices, ``(..., 3)`` vectors or
angle triples, ``(..., 4, 4)`` homogeneous matrices) and returns arrays with
the same leading shape. Quaternions are always in ``w, x, y, z`` order and
describe active rotations: ``matrix_from_quaternion(q) @ v`` rotates ``v``
the way ``q v q*`` does.

Input is checked here and the numba kernels in ``rbm_nb._kernels.conversions``
compute; each kernel counts the invalid input rows in the same pass, so the
checks cost no extra sweep over the data (the worst row is looked up only
when there is one to report):

* quaternions must be within ``UNIT_QUATERNION_TOLERANCE`` of unit norm
  (they are normalised), otherwise a ``ValueError`` names the worst row;
* rotation matrices must be orthonormal to within ``tol`` (the largest
  entry of ``|RᵀR - I|``) and have a positive determinant;
* angles, vectors and translations must be finite.

Euler angles
------------
``order`` is a three-letter, lower-case axis sequence; the twelve valid ones
are the six Tait-Bryan sequences (``xyz``, ``xzy``, ``yxz``, ``yzx``, ``zxy``,
``zyx``) and the six proper Euler sequences (``xyx``, ``xzx``, ``yxy``,
``yzy``, ``zxz``, ``zyz``). Each can be read two ways, which gives the 24
variants:

* intrinsic (the default, ``extrinsic=False``): rotate about the body's own,
  moving axes, first about ``order[0]``; ``R = R_0(a) R_1(b) R_2(c)``. This is
  scipy's upper-case convention (``Rotation.from_euler("XYZ", ...)``).
* extrinsic (``extrinsic=True``): rotate about the fixed axes, first about
  ``order[0]``; ``R = R_2(c) R_1(b) R_0(a)``. This is scipy's lower-case
  convention.

Upper-case orders are refused rather than guessed, so that code ported from
scipy cannot silently flip between the two readings.
"""

from __future__ import annotations

from itertools import product

import numpy as np

from .._door import shapes as _shapes
from .._infra.config import UNIT_QUATERNION_TOLERANCE
from .._kernels import conversions as _kc

__all__ = [
    "EULER_ORDERS",
    "axis_angle_from_quaternion",
    "euler_from_quaternion",
    "homogeneous_from_transform",
    "matrix_from_quaternion",
    "quaternion_from_axis_angle",
    "quaternion_from_euler",
    "quaternion_from_matrix",
    "quaternion_from_rotation_vector",
    "rotation_vector_from_quaternion",
    "transform_from_homogeneous",
]

#: The twelve axis sequences accepted as ``order`` (each intrinsic or extrinsic).
EULER_ORDERS: tuple[str, ...] = tuple(
    "".join(seq)
    for seq in product("xyz", repeat=3)
    if seq[0] != seq[1] and seq[1] != seq[2]
)

#: Default tolerance on a matrix's distance from SO(3).
MATRIX_TOLERANCE = 1e-6


# ---------------------------------------------------------------------------
# validation helpers
# ---------------------------------------------------------------------------


def _report_quaternions(name: str, rows: np.ndarray, lead: tuple) -> None:
    """Raise for the quaternion farthest from unit norm (the kernel found some)."""
    with np.errstate(all="ignore"):
        norm = np.sqrt(np.einsum("ij,ij->i", rows, rows))
    dev = np.where(np.isnan(norm), np.inf, np.abs(norm - 1.0))
    idx = int(np.argmax(dev))
    if not np.isfinite(norm[idx]):
        raise ValueError(
            f"{name}{_shapes.where(lead, idx)} has norm {norm[idx]:.6g}: it is not finite, "
            f"so it is not a rotation"
        )
    raise ValueError(
        f"{name}{_shapes.where(lead, idx)} has norm {norm[idx]:.6g}, which is not a "
        f"rotation: quaternions must have unit norm to within "
        f"{UNIT_QUATERNION_TOLERANCE:g} (closer ones are normalised)"
    )


def _report_non_finite(name: str, rows: np.ndarray, lead: tuple, what: str) -> None:
    """Raise for the first row of ``rows`` holding a non-finite value."""
    bad = ~np.isfinite(rows.reshape(len(rows), -1)).all(axis=1)
    idx = int(np.argmax(bad))
    raise ValueError(
        f"{name}{_shapes.where(lead, idx)} is {rows[idx].tolist()}: {what}"
    )


def _report_matrices(name: str, mats: np.ndarray, lead: tuple, tol: float) -> None:
    """Raise for the matrix farthest from SO(3) (the kernel found some).

    ``mats`` holds (n, 3, 3) rotation or (n, 4, 4) homogeneous matrices; a
    reflection, a wrong bottom row or a non-finite value ranks as worst.
    """
    with np.errstate(all="ignore"):
        rot = mats[:, :3, :3]
        gram = np.einsum("nki,nkj->nij", rot, rot) - np.eye(3)
        ortho = np.abs(gram).reshape(len(mats), -1).max(axis=1)
        det = np.linalg.det(rot)
        score = np.where(det > 0.0, ortho, np.inf)
        score[~np.isfinite(mats.reshape(len(mats), -1)).all(axis=1)] = np.inf
        if mats.shape[1:] == (4, 4):
            bottom = np.abs(mats[:, 3] - [0.0, 0.0, 0.0, 1.0]).max(axis=1)
            score[~(bottom <= tol)] = np.inf
    idx = int(np.argmax(np.where(np.isnan(score), np.inf, score)))
    block = mats[idx]
    where = _shapes.where(lead, idx)
    if not np.all(np.isfinite(block)):
        raise ValueError(f"{name}{where} contains non-finite values: {block.tolist()}")
    if block.shape == (4, 4) and not np.abs(block[3] - [0, 0, 0, 1]).max() <= tol:
        raise ValueError(
            f"{name}{where} has bottom row {block[3].tolist()}; a homogeneous "
            f"transformation matrix needs [0, 0, 0, 1] (to within tol={tol:g})"
        )
    hint = ", a reflection" if det[idx] < 0 else ""
    worst = ", the worst in the batch" if lead else ""
    raise ValueError(
        f"{name}{where} is not a rotation matrix (max|RᵀR - I| = {ortho[idx]:.3g}, "
        f"det = {det[idx]:.6g}{hint}{worst}); rotation matrices must be orthonormal "
        f"to within tol={tol:g} with a positive determinant"
    )


def _parse_order(order) -> tuple[int, int, int]:
    if isinstance(order, str) and order in EULER_ORDERS:
        return tuple("xyz".index(c) for c in order)  # type: ignore[return-value]
    listing = ", ".join(EULER_ORDERS)
    variants = (
        f"the 24 valid variants are the orders {listing}, each either "
        "intrinsic (extrinsic=False, the default) or extrinsic (extrinsic=True)"
    )
    if isinstance(order, str) and order.lower() in EULER_ORDERS:
        raise ValueError(
            f"Euler order {order!r} is upper-case; rbm_nb takes lower-case "
            f"orders and an explicit extrinsic= keyword (scipy's {order!r} is "
            f"order={order.lower()!r}, extrinsic={order.islower()}); {variants}"
        )
    raise ValueError(f"unknown Euler order {order!r}; {variants}")


# ---------------------------------------------------------------------------
# quaternion <-> rotation matrix
# ---------------------------------------------------------------------------


def matrix_from_quaternion(quaternion) -> np.ndarray:
    """Rotation matrices of unit quaternions.

    Parameters
    ----------
    quaternion : array_like, shape (..., 4)
        ``w, x, y, z``; within ``UNIT_QUATERNION_TOLERANCE`` of unit norm.

    Returns
    -------
    ndarray, shape (..., 3, 3)

    Raises
    ------
    ValueError
        If the shape is wrong or a quaternion is far from unit norm.

    Examples
    --------
    >>> import numpy as np
    >>> from rbm_nb.conversions import matrix_from_quaternion
    >>> q = [np.cos(np.pi / 4), 0.0, 0.0, np.sin(np.pi / 4)]  # 90° about z
    >>> matrix_from_quaternion(q).round(12) + 0.0
    array([[ 0., -1.,  0.],
           [ 1.,  0.,  0.],
           [ 0.,  0.,  1.]])
    """
    rows, lead = _shapes.rows(quaternion, "quaternion", (4,))
    out, n_invalid = _kc.matrix_from_quaternion(rows, UNIT_QUATERNION_TOLERANCE)
    if n_invalid:
        _report_quaternions("quaternion", rows, lead)
    return out.reshape(lead + (3, 3))


def quaternion_from_matrix(matrix, *, tol: float = MATRIX_TOLERANCE) -> np.ndarray:
    """Unit quaternions of rotation matrices.

    Parameters
    ----------
    matrix : array_like, shape (..., 3, 3)
        Rotation matrices: orthonormal with determinant +1 to within ``tol``.
    tol : float, default 1e-6
        Largest accepted entry of ``|RᵀR - I|``; ``det R`` must be positive.

    Returns
    -------
    ndarray, shape (..., 4)
        ``w, x, y, z`` in canonical form: ``w > 0``, or for half turns
        (``w = 0``) the first non-zero of ``x, y, z`` positive - of the two
        quaternions of a rotation, the one scipy returns too.

    Raises
    ------
    ValueError
        If the shape is wrong, or a matrix is not a rotation (the message
        gives the tolerance, the worst matrix's index, its orthonormality
        error and determinant).

    Examples
    --------
    >>> from rbm_nb.conversions import quaternion_from_matrix
    >>> quaternion_from_matrix([[0, -1, 0], [1, 0, 0], [0, 0, 1]]).round(6)
    array([0.707107, 0.      , 0.      , 0.707107])
    """
    rows, lead, tol = _shapes.rows_within(matrix, "matrix", (3, 3), tol)
    out, n_invalid = _kc.quaternion_from_matrix(rows, tol)
    if n_invalid:
        _report_matrices("matrix", rows, lead, tol)
    return out.reshape(lead + (4,))


# ---------------------------------------------------------------------------
# quaternion <-> rotation vector
# ---------------------------------------------------------------------------


def quaternion_from_rotation_vector(rotation_vector) -> np.ndarray:
    """Unit quaternions of rotation vectors (the exponential map).

    Parameters
    ----------
    rotation_vector : array_like, shape (..., 3)
        Axis times angle in radians, any length.

    Returns
    -------
    ndarray, shape (..., 4)
        ``w, x, y, z`` with ``w = cos(|v| / 2)`` (negative for angles above
        pi: no sign is imposed, so the map stays continuous).

    Raises
    ------
    ValueError
        If the shape is wrong or a vector is not finite.

    Examples
    --------
    >>> import numpy as np
    >>> from rbm_nb.conversions import quaternion_from_rotation_vector
    >>> quaternion_from_rotation_vector([0.0, 0.0, np.pi]).round(12) + 0.0
    array([0., 0., 0., 1.])
    """
    rows, lead = _shapes.rows(rotation_vector, "rotation_vector", (3,))
    out, n_invalid = _kc.quaternion_from_rotation_vector(rows)
    if n_invalid:
        _report_non_finite(
            "rotation_vector", rows, lead, "rotation vectors must be finite"
        )
    return out.reshape(lead + (4,))


def rotation_vector_from_quaternion(quaternion) -> np.ndarray:
    """Rotation vectors of unit quaternions (the logarithm map).

    Parameters
    ----------
    quaternion : array_like, shape (..., 4)
        ``w, x, y, z``; within ``UNIT_QUATERNION_TOLERANCE`` of unit norm.
        ``q`` and ``-q`` give the same result.

    Returns
    -------
    ndarray, shape (..., 3)
        Axis times angle, with angle in [0, pi].

    Raises
    ------
    ValueError
        If the shape is wrong or a quaternion is far from unit norm.

    Examples
    --------
    >>> import numpy as np
    >>> from rbm_nb.conversions import rotation_vector_from_quaternion
    >>> rotation_vector_from_quaternion([np.cos(0.25), np.sin(0.25), 0, 0])
    array([0.5, 0. , 0. ])
    """
    rows, lead = _shapes.rows(quaternion, "quaternion", (4,))
    out, n_invalid = _kc.rotation_vector_from_quaternion(
        rows, UNIT_QUATERNION_TOLERANCE
    )
    if n_invalid:
        _report_quaternions("quaternion", rows, lead)
    return out.reshape(lead + (3,))


# ---------------------------------------------------------------------------
# quaternion <-> axis-angle
# ---------------------------------------------------------------------------


def quaternion_from_axis_angle(axis, angle) -> np.ndarray:
    """Unit quaternions of rotations by ``angle`` about ``axis``.

    Parameters
    ----------
    axis : array_like, shape (..., 3)
        Rotation axes, any non-zero length (they are normalised). A zero
        axis is accepted only together with a zero angle.
    angle : array_like, shape (...)
        Angles in radians (right-hand rule). Leading shapes broadcast.

    Returns
    -------
    ndarray, shape (..., 4)

    Raises
    ------
    ValueError
        If shapes do not fit, an axis is zero for a non-zero angle, or a
        value is not finite.

    Examples
    --------
    >>> import numpy as np
    >>> from rbm_nb.conversions import quaternion_from_axis_angle
    >>> quaternion_from_axis_angle([0, 0, 2], np.pi).round(12) + 0.0
    array([0., 0., 0., 1.])
    """
    axes, angles, lead = _shapes.paired_rows(axis, "axis", (3,), angle, "angle", ())
    out, n_invalid = _kc.quaternion_from_axis_angle(axes, angles)
    if n_invalid:
        length = np.linalg.norm(axes, axis=1)
        ok = np.isfinite(angles) & np.isfinite(length) & ((length > 0) | (angles == 0))
        bad = int(np.argmin(ok))
        raise ValueError(
            f"axis{_shapes.where(lead, bad)} is {axes[bad].tolist()} with angle "
            f"{float(angles[bad])!r}: axes must be finite and non-zero (a zero axis is "
            "only allowed with a zero angle) and angles finite"
        )
    return out.reshape(lead + (4,))


def axis_angle_from_quaternion(quaternion) -> tuple[np.ndarray, np.ndarray]:
    """Rotation axes and angles of unit quaternions.

    Parameters
    ----------
    quaternion : array_like, shape (..., 4)
        ``w, x, y, z``; within ``UNIT_QUATERNION_TOLERANCE`` of unit norm.

    Returns
    -------
    axis : ndarray, shape (..., 3)
        Unit axes; ``(1, 0, 0)`` for the identity, whose axis is arbitrary.
    angle : ndarray, shape (...)
        Angles in [0, pi].

    Raises
    ------
    ValueError
        If the shape is wrong or a quaternion is far from unit norm.

    Examples
    --------
    >>> import numpy as np
    >>> from rbm_nb.conversions import axis_angle_from_quaternion
    >>> axis, angle = axis_angle_from_quaternion([np.cos(0.5), 0.0, -np.sin(0.5), 0.0])
    >>> axis + 0.0, round(float(angle), 12)
    (array([ 0., -1.,  0.]), 1.0)
    """
    rows, lead = _shapes.rows(quaternion, "quaternion", (4,))
    axis, angle, n_invalid = _kc.axis_angle_from_quaternion(
        rows, UNIT_QUATERNION_TOLERANCE
    )
    if n_invalid:
        _report_quaternions("quaternion", rows, lead)
    return axis.reshape(lead + (3,)), angle.reshape(lead)


# ---------------------------------------------------------------------------
# quaternion <-> Euler angles
# ---------------------------------------------------------------------------


def quaternion_from_euler(
    angles, order: str = "xyz", *, extrinsic: bool = False, degrees: bool = False
) -> np.ndarray:
    """Unit quaternions of Euler angle triples.

    Parameters
    ----------
    angles : array_like, shape (..., 3)
        The three angles, ``angles[..., 0]`` about axis ``order[0]``.
    order : str, default "xyz"
        One of the twelve lower-case sequences in ``EULER_ORDERS``.
    extrinsic : bool, default False
        False: intrinsic rotations about the moving axes,
        ``R = R_order[0] R_order[1] R_order[2]`` (scipy ``"XYZ"``).
        True: extrinsic rotations about the fixed axes,
        ``R = R_order[2] R_order[1] R_order[0]`` (scipy ``"xyz"``).
    degrees : bool, default False
        Angles are in degrees instead of radians.

    Returns
    -------
    ndarray, shape (..., 4)

    Raises
    ------
    ValueError
        If the order is not one of the 24 variants (the message lists them),
        the shape is wrong, or an angle is not finite.

    Examples
    --------
    >>> from rbm_nb.conversions import quaternion_from_euler
    >>> quaternion_from_euler([0, 0, 90], "xyz", degrees=True).round(6)
    array([0.707107, 0.      , 0.      , 0.707107])
    """
    i, j, k = _parse_order(order)
    rows, lead = _shapes.rows(angles, "angles", (3,))
    radians = np.deg2rad(rows) if degrees else rows
    out, n_invalid = _kc.quaternion_from_euler(radians, i, j, k, bool(extrinsic))
    if n_invalid:
        _report_non_finite("angles", rows, lead, "Euler angles must be finite")
    return out.reshape(lead + (4,))


def euler_from_quaternion(
    quaternion, order: str = "xyz", *, extrinsic: bool = False, degrees: bool = False
) -> np.ndarray:
    """Euler angle triples of unit quaternions.

    Parameters
    ----------
    quaternion : array_like, shape (..., 4)
        ``w, x, y, z``; within ``UNIT_QUATERNION_TOLERANCE`` of unit norm.
    order : str, default "xyz"
        One of the twelve lower-case sequences in ``EULER_ORDERS``.
    extrinsic : bool, default False
        Intrinsic (moving axes) or extrinsic (fixed axes) reading, as in
        ``quaternion_from_euler``.
    degrees : bool, default False
        Return degrees instead of radians.

    Returns
    -------
    ndarray, shape (..., 3)
        First and third angle in [-pi, pi]; the middle one in [0, pi] for
        proper sequences and [-pi/2, pi/2] for Tait-Bryan ones. At gimbal
        lock (middle angle at a limit) only the sum or difference of the
        outer angles is defined: the third angle is then 0 and the first
        carries the rotation, so the conversion back is still exact.

    Raises
    ------
    ValueError
        If the order is not one of the 24 variants, the shape is wrong or a
        quaternion is far from unit norm.

    Examples
    --------
    >>> import numpy as np
    >>> from rbm_nb.conversions import euler_from_quaternion
    >>> q = [np.cos(np.pi / 8), 0, 0, np.sin(np.pi / 8)]  # 45° about z
    >>> euler_from_quaternion(q, "zyx", degrees=True).round(9) + 0.0
    array([45.,  0.,  0.])
    """
    i, j, k = _parse_order(order)
    rows, lead = _shapes.rows(quaternion, "quaternion", (4,))
    out, n_invalid = _kc.euler_from_quaternion(
        rows, i, j, k, bool(extrinsic), UNIT_QUATERNION_TOLERANCE
    )
    if n_invalid:
        _report_quaternions("quaternion", rows, lead)
    if degrees:
        out = np.rad2deg(out, out=out)
    return out.reshape(lead + (3,))


# ---------------------------------------------------------------------------
# (translation, rotation) <-> homogeneous matrix
# ---------------------------------------------------------------------------


def homogeneous_from_transform(translation, rotation) -> np.ndarray:
    """4 x 4 homogeneous matrices ``[[R, t], [0, 1]]``.

    The matrix maps homogeneous points as ``p' = R p + t``: rotation first,
    then translation, rbm_nb's convention for a transformation.

    Parameters
    ----------
    translation : array_like, shape (..., 3)
    rotation : array_like, shape (..., 4)
        Unit quaternions ``w, x, y, z``. Leading shapes broadcast.

    Returns
    -------
    ndarray, shape (..., 4, 4)

    Raises
    ------
    ValueError
        If shapes do not fit, a translation is not finite, or a quaternion
        is far from unit norm.

    Examples
    --------
    >>> from rbm_nb.conversions import homogeneous_from_transform
    >>> homogeneous_from_transform([1.0, 2.0, 3.0], [1.0, 0.0, 0.0, 0.0])
    array([[1., 0., 0., 1.],
           [0., 1., 0., 2.],
           [0., 0., 1., 3.],
           [0., 0., 0., 1.]])
    """
    t_rows, q_rows, lead = _shapes.paired_rows(
        translation, "translation", (3,), rotation, "rotation", (4,)
    )
    out, bad_q, bad_t = _kc.homogeneous_from_transform(
        t_rows, q_rows, UNIT_QUATERNION_TOLERANCE
    )
    if bad_q:
        _report_quaternions("rotation", q_rows, lead)
    if bad_t:
        _report_non_finite("translation", t_rows, lead, "translations must be finite")
    return out.reshape(lead + (4, 4))


def transform_from_homogeneous(
    matrix, *, tol: float = MATRIX_TOLERANCE
) -> tuple[np.ndarray, np.ndarray]:
    """Translations and rotations of 4 x 4 homogeneous matrices.

    Parameters
    ----------
    matrix : array_like, shape (..., 4, 4)
        ``[[R, t], [0, 0, 0, 1]]`` with ``R`` a rotation to within ``tol``.
    tol : float, default 1e-6
        Largest accepted entry of ``|RᵀR - I|``; ``det R`` must be positive.

    Returns
    -------
    translation : ndarray, shape (..., 3)
    rotation : ndarray, shape (..., 4)
        Unit quaternions ``w, x, y, z`` in the canonical form of
        ``quaternion_from_matrix``.

    Raises
    ------
    ValueError
        If the shape is wrong, the bottom row is not ``(0, 0, 0, 1)``, a value
        is not finite, or the rotation block is not a rotation.

    Examples
    --------
    >>> import numpy as np
    >>> from rbm_nb.conversions import transform_from_homogeneous
    >>> t, r = transform_from_homogeneous(np.eye(4))
    >>> t, r
    (array([0., 0., 0.]), array([1., 0., 0., 0.]))
    """
    rows, lead, tol = _shapes.rows_within(matrix, "matrix", (4, 4), tol)
    t, q, n_invalid = _kc.transform_from_homogeneous(rows, tol)
    if n_invalid:
        _report_matrices("matrix", rows, lead, tol)
    return t.reshape(lead + (3,)), q.reshape(lead + (4,))
