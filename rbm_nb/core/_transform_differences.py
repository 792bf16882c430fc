"""How far one pose is from another: ``Transform.difference*``'s arithmetic.

The position and rotation errors a controller moving one pose onto another
acts on, in the first pose's axes. Everything here works on the flat kernel
rows (``(n, 3)`` translations, ``(n, 4)`` wxyz quaternions) of two
transformations already paired to one batch shape and checked by
:class:`rbm_nb.core.rigid_transform.Transform`; results come back flat too.
"""

from __future__ import annotations

import numpy as np

from .._kernels import quaternion as _kq
from . import _pose_algebra as _pa
from .conversions import rotation_vector_from_quaternion


def position_in_first(
    t_self: np.ndarray, q_self: np.ndarray, t_other: np.ndarray
) -> np.ndarray:
    """``rot(r_self⁻¹, t_other - t_self)``: where ``other``'s origin lies."""
    return _kq.rotate_vectors(_kq.qconj(q_self), t_other - t_self)


def closer_of_mirrored(
    q_rel: np.ndarray, rotation: np.ndarray, axis: int
) -> np.ndarray:
    """The rotation vector of ``q_rel`` or of ``q_rel`` turned half a turn about
    its own ``axis``, whichever is shorter (``Transform.difference``'s rule for
    symmetric objects)."""
    half_turn = np.zeros((1, 4))
    half_turn[0, 1 + axis] = 1.0
    mirrored = rotation_vector_from_quaternion(_kq.qmul(q_rel, half_turn))
    closer = np.linalg.norm(mirrored, axis=1) < np.linalg.norm(rotation, axis=1)
    return np.where(closer[:, None], mirrored, rotation)


def difference(
    t_self: np.ndarray,
    q_self: np.ndarray,
    t_other: np.ndarray,
    q_other: np.ndarray,
    mirror_axis: int | None,
) -> tuple[np.ndarray, np.ndarray]:
    """Position and rotation vector of ``other`` relative to ``self`` (unmasked)."""
    k = _kq
    q_inv = k.qconj(q_self)
    position = k.rotate_vectors(q_inv, t_other - t_self)
    q_rel = k.qmul(q_inv, q_other)
    rotation = rotation_vector_from_quaternion(q_rel)
    if mirror_axis is not None:
        rotation = closer_of_mirrored(q_rel, rotation, mirror_axis)
    return position, rotation


def scikit_robot_mirrored(
    q_self: np.ndarray, q_other: np.ndarray, axis: int
) -> np.ndarray:
    """``q_other``, turned half a turn about its own ``axis`` unless that axis
    makes an angle of less than 90° with the same axis of ``q_self``
    (scikit-robot's ``Coordinates.difference_rotation`` mirror rule)."""
    k = _kq
    e = np.zeros((1, 3))
    e[0, axis] = 1.0
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
    half_turn[0, 1 + axis] = 1.0
    turned = k.qmul(q_other, np.repeat(half_turn, len(q_other), axis=0))
    return np.where(keep[:, None], q_other, turned)


def rotation_from_first(
    q_self: np.ndarray, q_other: np.ndarray, mirror_axis: int | None
) -> np.ndarray:
    """Rotation vector of ``r_self⁻¹ r_other`` (scikit-robot's mirror rule)."""
    if mirror_axis is not None:
        q_other = scikit_robot_mirrored(q_self, q_other, mirror_axis)
    return rotation_vector_from_quaternion(_kq.qmul(_kq.qconj(q_self), q_other))
