"""Moving a pose: ``Transform``'s scikit-robot-style pose algebra on rows.

Translate by a vector, turn about an axis, align an axis with a direction,
and one pose applied to a large cloud of points. Everything here works on
flat kernel rows (``(n, 3)`` translations and vectors, ``(n, 4)`` wxyz
quaternions) broadcast to a batch shape that
:class:`rbm_nb.core.rigid_transform.Transform` has already checked; the
functions return the moved pose's translation and rotation rows.
"""

from __future__ import annotations

import numpy as np

from .._kernels import quaternion as _kq
from . import _pose_algebra as _pa
from .conversions import homogeneous_from_transform


def translated(
    t: np.ndarray, q: np.ndarray, offset: np.ndarray, axes: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray]:
    """The origin moved by ``offset``, given in the axes of the rotations
    ``axes`` (None: in the axes the pose maps into)."""
    if axes is not None:
        offset = _kq.rotate_vectors(axes, offset)
    return t + offset, q


def turned(
    q: np.ndarray,
    axes: np.ndarray,
    angles: np.ndarray,
    wrt: str | np.ndarray,
) -> np.ndarray:
    """Rotations ``q`` turned by ``angles`` about the ``axes`` rows, which are
    in the pose's own axes (``"local"``), in the axes it maps into
    (``"world"``) or in those of the rotations ``wrt``."""
    k = _kq
    unit = _pa.unit_rows(axes, "axis")
    turn = _pa.quaternion_rows_from_axis_angle(unit, angles)
    if isinstance(wrt, str):
        return k.qmul(q, turn) if wrt == "local" else k.qmul(turn, q)
    return k.qmul(k.qmul(k.qmul(wrt, turn), k.qconj(wrt)), q)


def aligned(
    q: np.ndarray,
    axis: np.ndarray,
    direction: np.ndarray,
    wrt: str | np.ndarray,
) -> np.ndarray:
    """Rotations ``q`` turned the shortest way so that their local ``axis``
    points along ``direction``, given in the pose's own axes (``"local"``),
    the axes it maps into (``"world"``) or those of the rotations ``wrt``."""
    k = _kq
    target = _pa.unit_rows(direction, "direction")
    if isinstance(wrt, np.ndarray):
        target = k.rotate_vectors(wrt, target)
    elif wrt == "local":
        target = k.rotate_vectors(q, target)
    current = k.rotate_vectors(q, _pa.unit_rows(axis, "axis"))
    return k.qmul(_pa.shortest_arc_rows(current, target), q)


def single_pose_applied(
    translation: np.ndarray, rotation: np.ndarray, points: np.ndarray, inverse: bool
) -> np.ndarray:
    """One transformation applied to many points as a matrix product (BLAS).

    For a single pose and a large cloud this is several times faster than
    rotating every point by the quaternion, and what scikit-robot does.
    """
    rot = homogeneous_from_transform(translation, rotation)[:3, :3]
    rows = points.reshape(-1, 3).T  # (3, n): one BLAS call on the long axis
    if inverse:
        out = rot.T @ (rows - translation[:, None])
    else:
        out = rot @ rows + translation[:, None]
    return out.T.reshape(points.shape)
