"""Array helpers behind ``Transform``'s pose algebra (translate, rotate, align).

Everything here works on flat rows (``(n, 3)`` vectors, ``(n, 4)`` wxyz
quaternions) that ``rigid_transform`` has already broadcast and validated, so
the methods of ``Transform`` stay short.
"""

from __future__ import annotations

import numpy as np

# named axes accepted wherever a rotation axis or an axis of the frame is asked
# for; the two-letter names are the diagonals scikit-robot users know
NAMED_AXES = {
    "x": (1.0, 0.0, 0.0),
    "y": (0.0, 1.0, 0.0),
    "z": (0.0, 0.0, 1.0),
    "-x": (-1.0, 0.0, 0.0),
    "-y": (0.0, -1.0, 0.0),
    "-z": (0.0, 0.0, -1.0),
    "xy": (1.0, 1.0, 0.0),
    "yx": (1.0, 1.0, 0.0),
    "yz": (0.0, 1.0, 1.0),
    "zy": (0.0, 1.0, 1.0),
    "xz": (1.0, 0.0, 1.0),
    "zx": (1.0, 0.0, 1.0),
    "xyz": (1.0, 1.0, 1.0),
}

# below this norm of the cross product two unit vectors count as (anti-)parallel
PARALLEL_TOLERANCE = 1e-12


def axis_vectors(axis, name: str) -> np.ndarray:
    """An axis name or vector(s) as a float array of shape (..., 3), unnormalised."""
    if isinstance(axis, str):
        try:
            return np.array(NAMED_AXES[axis.lower()])
        except KeyError:
            raise ValueError(
                f"{name} must be one of {sorted(NAMED_AXES)} or a vector (..., 3), "
                f"got {axis!r}"
            ) from None
    try:
        arr = np.asarray(axis, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(
            f"{name} must be an axis name such as 'z' or a vector (..., 3), got {axis!r}"
        ) from None
    if arr.ndim == 0 or arr.shape[-1] != 3:
        raise ValueError(f"{name} must have shape (..., 3), got shape {arr.shape}")
    if not np.isfinite(arr).all():
        raise ValueError(f"{name} must be finite")
    return arr


def unit_rows(rows: np.ndarray, name: str) -> np.ndarray:
    """Rows divided by their norms; a zero row is an error that names ``name``."""
    norm = np.linalg.norm(rows, axis=1)
    if not np.all(norm > 0.0):
        bad = int(np.flatnonzero(~(norm > 0.0))[0])
        raise ValueError(f"{name} has a zero-length vector (at flat index {bad})")
    return rows / norm[:, None]


def quaternion_rows_from_axis_angle(axes: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """Quaternions of rotations by ``angles`` (n,) about unit ``axes`` (n, 3)."""
    half = 0.5 * angles
    q = np.empty((len(angles), 4))
    q[:, 0] = np.cos(half)
    q[:, 1:] = np.sin(half)[:, None] * axes
    return q


def shortest_arc_rows(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Quaternions turning unit vectors ``a`` onto unit vectors ``b`` (both (n, 3)).

    Parallel vectors give the identity; anti-parallel ones a half turn about
    ``a x e_x`` (or ``a x e_y`` when ``a`` lies along x), the choice
    scikit-robot's ``rotation_matrix_from_vectors`` makes, so that both
    libraries land on the same frame in that degenerate case.
    """
    cross = np.cross(a, b)
    sin = np.linalg.norm(cross, axis=1)
    cos = np.clip(np.einsum("ij,ij->i", a, b), -1.0, 1.0)
    degenerate = sin < PARALLEL_TOLERANCE
    axes = np.where(
        degenerate[:, None],
        (1.0, 0.0, 0.0),
        cross / np.where(degenerate, 1.0, sin)[:, None],
    )
    # atan2 keeps the angle exact near 0 and pi, where arccos of a cosine
    # that rounds to +-1 loses up to sqrt(eps) (1e-8 rad)
    angles = np.arctan2(sin, cos)
    opposite = degenerate & (cos <= 0.0)
    if opposite.any():
        perp = np.cross(a[opposite], (1.0, 0.0, 0.0))
        along_x = np.linalg.norm(perp, axis=1) < PARALLEL_TOLERANCE
        perp[along_x] = np.cross(a[opposite][along_x], (0.0, 1.0, 0.0))
        axes[opposite] = perp / np.linalg.norm(perp, axis=1)[:, None]
        angles[opposite] = np.pi
    angles[degenerate & (cos > 0.0)] = 0.0
    return quaternion_rows_from_axis_angle(axes, angles)
