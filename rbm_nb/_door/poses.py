"""The door's rule for pose and rotation-matrix arguments (se3).

* :func:`rotation_blocks`: the 3 x 3 blocks of (n, k, k) matrices are
  rotations within a tolerance of SO(3);
* :func:`poses`: (..., 4, 4) homogeneous matrices, last row (0, 0, 0, 1),
  their rotation blocks in SO(3).

One counting kernel pass when the matrices pass; the first bad one is then
named by its index in the argument (:func:`rbm_nb._door.shapes.where`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._kernels import se3 as _se3
from .shapes import rows, where
from .unpack import kernel_array

__all__ = ["rotation_blocks", "poses"]


def rotation_blocks(rot: np.ndarray, lead: tuple, name: str, tolerance: float) -> None:
    """Raise if a (n, k, k) matrix's 3 x 3 block is not a rotation within ``tolerance``."""
    i = _se3.first_non_rotation(kernel_array(rot), tolerance)
    if i >= 0:
        r = rot[i, :3, :3]
        dev = np.abs(r.T @ r - np.eye(3)).max()
        raise ValueError(
            f"{name}{where(lead, i)} is not a rotation: |RᵀR - I| reaches "
            f"{dev:.3g} (tolerance {tolerance:g}) and det(R) = "
            f"{np.linalg.det(r):.6g}"
        )


def poses(
    value: Any, name: str, tolerance: float, rotation: bool = True
) -> tuple[np.ndarray, tuple]:
    """(n, 4, 4) homogeneous matrices: last row (0, 0, 0, 1), R in SO(3).

    ``rotation=False`` skips the SO(3) test (first-order poses such as the
    output of ``delta2tr``).
    """
    flat, lead = rows(value, name, (4, 4))
    i, code = _se3.first_bad_pose(flat, tolerance, bool(rotation))
    if code == 1:
        raise ValueError(f"{name}{where(lead, i)} is not finite")
    if code == 2:
        raise ValueError(
            f"{name}{where(lead, i)} is not a homogeneous matrix: its last row is "
            f"{flat[i, 3].tolist()}, expected [0, 0, 0, 1]"
        )
    if code == 3:
        rotation_blocks(flat[i : i + 1], (), f"{name}{where(lead, i)}", tolerance)
    return flat, lead
