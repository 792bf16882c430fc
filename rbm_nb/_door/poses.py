"""The door's rule for pose and rotation-matrix arguments (se3).

* :func:`rotation_blocks`: the 3 x 3 blocks of (n, k, k) matrices are
  rotations within a tolerance of SO(3);
* :func:`poses`: (..., 4, 4) homogeneous matrices, last row (0, 0, 0, 1),
  their rotation blocks in SO(3).

One counting kernel pass when the matrices pass; the first bad one is then
named by its index in the argument (:func:`rbm_nb._door.shapes.where`).
"""

from __future__ import annotations

import numbers
from typing import Any, NamedTuple

import numpy as np

from .._kernels import se3 as _se3
from .shapes import rows, where
from .unpack import float_array, kernel_array
from .validation import check_tolerance

__all__ = [
    "rotation_blocks",
    "poses",
    "PoseRows",
    "adjoint_input",
    "normalisable",
    "PosePairs",
    "delta_input",
    "interpolation_input",
    "rates_input",
]


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


# ---------------------------------------------------------------------------
# the se3 functions' one door call each
# ---------------------------------------------------------------------------


class PoseRows(NamedTuple):
    """Checked matrices as C-contiguous float64 rows ``(n, *tail)`` and the
    leading shape they came from; ``rotation_only``: the argument held
    rotations (3, 3), not poses (4, 4)."""

    rows: np.ndarray
    lead: tuple
    rotation_only: bool


def adjoint_input(value: Any, tolerance: float) -> PoseRows:
    """``tr2adjoint``'s ``T``: rotations (..., 3, 3) or poses (..., 4, 4)."""
    arr = float_array(value, "T")
    if arr.shape[-2:] == (3, 3):
        flat, lead = rows(arr, "T", (3, 3), finite=True)
        rotation_blocks(flat, lead, "T", tolerance)
        return PoseRows(flat, lead, True)
    flat, lead = poses(arr, "T", tolerance)
    return PoseRows(flat, lead, False)


def normalisable(value: Any) -> PoseRows:
    """``trnorm``'s ``T``: finite (..., 3, 3) or (..., 4, 4) matrices."""
    arr = float_array(value, "T")
    rotation_only = arr.shape[-2:] == (3, 3)
    flat, lead = rows(arr, "T", (3, 3) if rotation_only else (4, 4), finite=True)
    return PoseRows(flat, lead, rotation_only)


class PosePairs(NamedTuple):
    """Two stacks of poses (``a``, ``b``: (n, 4, 4) rows, a single pose or
    a stack of the result's leading shape ``lead``), and for ``trinterp``
    the fractions ``f`` as rows of that shape too."""

    a: np.ndarray
    b: np.ndarray
    lead: tuple
    f: Any = None
    rotation_only: bool = False


def delta_input(T0: Any, T1: Any, tolerance: float) -> PosePairs:
    """``tr2delta``'s poses (their rotations need not be orthonormal)."""
    if T1 is None:
        flat, lead = poses(T0, "T0", tolerance, rotation=False)
        return PosePairs(np.eye(4)[None], flat, lead)
    a, a_lead = poses(T0, "T0", tolerance, rotation=False)
    b, b_lead = poses(T1, "T1", tolerance, rotation=False)
    lead = leading_shape(a_lead, b_lead, "T0", "T1")
    # a single pose on either side is reused by the kernel; anything else
    # is broadcast explicitly
    if a_lead != b_lead and len(a) != 1 and len(b) != 1:
        a = expand(a, a_lead, lead)
        b = expand(b, b_lead, lead)
    return PosePairs(a, b, lead)


def interpolation_input(start: Any, end: Any, s: Any, tolerance: float) -> PosePairs:
    """``trinterp``'s end poses (``start`` None: the identity) and fractions."""
    end_arr = float_array(end, "end")
    rotation_only = end_arr.shape[-2:] == (3, 3)
    if rotation_only:
        end_arr = embed(end_arr)
    end_rows, end_lead = poses(end_arr, "end", tolerance)
    if start is None:
        start_rows, start_lead = np.eye(4)[None], ()
    else:
        start_arr = float_array(start, "start")
        if (start_arr.shape[-2:] == (3, 3)) != rotation_only:
            raise ValueError(
                f"start and end must both be rotations (3, 3) or both poses "
                f"(4, 4), got shapes {start_arr.shape} and {end_arr.shape}"
            )
        start_rows, start_lead = poses(
            embed(start_arr) if rotation_only else start_arr, "start", tolerance
        )
    frac = _fractions(s)
    lead = leading_shape(start_lead, end_lead, "start", "end")
    lead = leading_shape(lead, frac.shape, "the poses", "s")
    # a stack whose leading shape is the result's, or a single value, is
    # passed as is (the kernel reuses single rows); anything else is expanded
    a = _rows_for(start_rows, start_lead, lead)
    b = _rows_for(end_rows, end_lead, lead)
    f = _rows_for(np.ascontiguousarray(frac.reshape(-1)), frac.shape, lead)
    return PosePairs(
        kernel_array(a), kernel_array(b), lead, kernel_array(f), rotation_only
    )


def leading_shape(a: tuple, b: tuple, a_name: str, b_name: str) -> tuple:
    try:
        return np.broadcast_shapes(a, b)
    except ValueError:
        raise ValueError(
            f"the leading shapes of {a_name} {a} and {b_name} {b} do not broadcast"
        ) from None


def expand(flat: np.ndarray, lead: tuple, target: tuple) -> np.ndarray:
    """Rows of a stack broadcast from leading shape ``lead`` to ``target``."""
    tail = flat.shape[1:]
    full = np.broadcast_to(flat.reshape(lead + tail), target + tail)
    return np.ascontiguousarray(full).reshape((-1,) + tail)


def embed(rot: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) as poses (..., 4, 4) without translation."""
    out = np.zeros(rot.shape[:-2] + (4, 4))
    out[..., :3, :3] = rot
    out[..., 3, 3] = 1.0
    return out


def _rows_for(flat: np.ndarray, lead: tuple, target: tuple) -> np.ndarray:
    """``flat`` as the kernel wants it for a result of leading shape ``target``."""
    if lead == target or len(flat) == 1:
        return flat
    return expand(flat, lead, target)


def _fractions(s: Any) -> np.ndarray:
    """``s`` as an array of fractions; an integer > 1 is a number of steps."""
    if isinstance(s, numbers.Integral) and not isinstance(s, bool) and int(s) > 1:
        return np.linspace(0.0, 1.0, int(s))
    arr = float_array(s, "s")
    if not np.isfinite(arr).all() or (arr < 0).any() or (arr > 1).any():
        flat = arr.reshape(-1)
        i = int(np.argmax(~np.isfinite(flat) | (flat < 0) | (flat > 1)))
        raise ValueError(
            f"s must lie in [0, 1] (or be an integer number of steps > 1); "
            f"s{where(arr.shape, i)} = {flat[i]!r}"
        )
    return arr


def rates_input(value: Any, tol: Any, tolerance: float) -> PoseRows:
    """``rotvelxform``'s ``Γ``: angle triples (..., 3), or rotation matrices
    (..., 3, 3) (``rotation_only``) within ``tolerance``; after its ``tol``."""
    check_tolerance(tol)
    arr = float_array(value, "Γ")
    if arr.shape[-2:] != (3, 3):
        flat, lead = rows(arr, "Γ", (3,), finite=True)
        return PoseRows(flat, lead, False)
    flat, lead = rows(arr, "Γ", (3, 3), finite=True)
    try:
        rotation_blocks(flat, lead, "Γ", tolerance)
    except ValueError as err:
        # the likely mistake: a stack of exactly three angle triples
        raise ValueError(
            f"{err}. A trailing (3, 3) shape is read as rotation matrices (as in "
            "spatialmath); to pass three angle triples, give them shape (3, 1, 3)"
        ) from None
    return PoseRows(flat, lead, True)
