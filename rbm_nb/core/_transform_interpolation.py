"""Between two poses: ``Transform.slerp`` and ``Transform.lerp`` on rows.

Translations are interpolated linearly; rotations by slerp (constant angular
speed) or by normalised lerp (cheaper, same shorter arc). The rows are those
of two transformations and a ratio already broadcast to one batch shape by
:class:`rbm_nb.core.rigid_transform.Transform`.
"""

from __future__ import annotations

import numpy as np

from .._kernels import quaternion as _kq


def linear(t0: np.ndarray, t1: np.ndarray, ratio: np.ndarray) -> np.ndarray:
    """Translations from ``t0`` (ratio 0) to ``t1`` (ratio 1), extrapolated beyond."""
    return t0 + ratio[:, None] * (t1 - t0)


def slerped(q0: np.ndarray, q1: np.ndarray, ratio: np.ndarray) -> np.ndarray:
    return _kq.slerp(q0, q1, ratio)


def lerped(q0: np.ndarray, q1: np.ndarray, ratio: np.ndarray) -> np.ndarray:
    """Normalised lerp on the shorter arc; a zero quaternion on the way is refused."""
    q1 = np.where(np.einsum("ij,ij->i", q0, q1)[:, None] < 0.0, -q1, q1)
    q = q0 + ratio[:, None] * (q1 - q0)
    norm = np.linalg.norm(q, axis=1, keepdims=True)
    if not np.all(norm > 0.0):
        raise ValueError(
            "lerp passes through a zero quaternion for this ratio; use slerp"
        )
    return q / norm
