"""Estimators: velocities from sampled motion, rotations and transforms from data.

The velocity estimators follow rigid-body-motion: finite differences on
(possibly uneven) timestamps, optional suppression of outliers found by
second-order differences (the rejected samples are re-interpolated), and an
optional 7th-order Butterworth low-pass applied forwards and backwards
(the reference's ``filtfilt`` filter, run in second-order sections: at
cutoff 0.05 the transfer-function form's rounding noise is ~2e-9 of the
signal, the sections' ~1e-14) with ``cutoff`` as a fraction of the
Nyquist frequency. Linear velocity uses numpy's gradient scheme; angular velocity uses
the derivative of the not-a-knot cubic spline through the quaternions
("quaternion" mode) or the gradient of the rotation vectors
("rotation_vector" mode).

The numerics live in :mod:`rbm_nb._engine.velocity` (shared with the
velocity lookups); the public functions here add axis handling, timestamp
conversion and DataArray support around them.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._door.estimators import (
    closest_point_input,
    vector_pairs,
    velocity_arguments,
)
from .._door.unpack import ArrayInput
from .._engine.velocity import angular_series as _angular_series
from .._engine.velocity import linear_series as _linear_series
from .._kernels import conversions as _kc
from .._kernels import quaternion as _qk
from .coordinates import _replace_dim

__all__ = [
    "best_fit_rotation",
    "best_fit_transform",
    "estimate_angular_velocity",
    "estimate_linear_velocity",
    "iterative_closest_point",
    "shortest_arc_rotation",
]

# ---------------------------------------------------------------------------
# public velocity estimators
# ---------------------------------------------------------------------------


def estimate_linear_velocity(
    arr: ArrayInput,
    dim: str | None = None,
    axis: int | None = None,
    timestamps: Any = None,
    time_axis: int | None = None,
    outlier_thresh: float | None = None,
    cutoff: float | None = None,
) -> Any:
    """Estimate linear velocity from positions sampled in time.

    Parameters
    ----------
    arr : array_like or DataArray, shape (..., n, ..., 3, ...)
        Positions (any number of spatial components is accepted).
    dim : str, optional
        For a DataArray, the dimension holding the spatial components.
    axis : int, optional
        The axis holding the spatial components; default the last.
    timestamps : array_like or str, optional
        Times of the samples along ``time_axis`` (numbers in seconds, or
        datetime64), or for a DataArray the name of its time coordinate.
        Required for plain arrays; defaults to the coordinate of the DataArray
        dimension at ``time_axis``.
    time_axis : int, optional
        The axis along which the samples lie; default the first.
    outlier_thresh : float, optional
        Reject samples where the norm of the second-order differences of the
        positions exceeds this and interpolate the velocity there (1e-3 suits
        the Intel RealSense T265, whose position corrections cause jumps).
    cutoff : float, optional
        Low-pass the velocity (7th-order Butterworth, forwards and backwards)
        at this fraction of the Nyquist frequency.

    Returns
    -------
    ndarray or DataArray
        Velocities, same shape (and coordinates) as ``arr``.

    Notes
    -----
    The stencil is numpy's ``gradient``: at sample i the three-point
    central difference of samples i-1, i, i+1, and at the ends of a series
    one-sided first differences (i, i+1 or i-1, i). NaN rows (missing
    samples) split the series, and each run of present samples is
    differenced on its own, so that a velocity is missing only at a missing
    sample and at a present one with no present neighbour; nothing is
    differenced across a missing sample. (rigid-body-motion differences
    across them and returns NaN on both sides of each missing sample.)

    Raises
    ------
    ValueError
        For missing, unsorted or mismatched timestamps, bad axes, a ``cutoff``
        outside (0, 1) or too few samples.

    Examples
    --------
    >>> estimate_linear_velocity([[0.0, 0, 0], [1, 0, 0], [2, 0, 0]], timestamps=[0, 1, 2])
    array([[1., 0., 0.],
           [1., 0., 0.],
           [1., 0., 0.]])
    """
    args = velocity_arguments(
        _linear, arr, dim, axis, timestamps, time_axis, outlier_thresh, cutoff
    )
    if args.lazy is not None:
        return args.lazy
    return _linear(args, arr, outlier_thresh, cutoff)


def _linear(args, arr, outlier_thresh, cutoff, mode=None):
    """:func:`estimate_linear_velocity` of a checked series (``args``) of ``arr``."""
    v = _linear_series(args.rows, args.t, outlier_thresh, cutoff)
    out = args.result(v, args.rows.shape[-1])
    if args.dataarray:
        return arr.copy(data=out)
    return out


def estimate_angular_velocity(
    arr: ArrayInput,
    dim: str | None = None,
    axis: int | None = None,
    timestamps: Any = None,
    time_axis: int | None = None,
    mode: str = "quaternion",
    outlier_thresh: float | None = None,
    cutoff: float | None = None,
) -> Any:
    """Estimate angular velocity from orientations (quaternions) sampled in time.

    Parameters
    ----------
    arr : array_like or DataArray, shape (..., n, ..., 4, ...)
        Quaternions (w, x, y, z); sign flips between samples are harmless.
    dim : str, optional
        For a DataArray, the dimension holding the quaternion components.
    axis : int, optional
        The axis holding the quaternion components; default the last.
    timestamps : array_like or str, optional
        As in :func:`estimate_linear_velocity`.
    time_axis : int, optional
        The axis along which the samples lie; default the first.
    mode : {"quaternion", "rotation_vector"}, default "quaternion"
        "quaternion": vector part of ``2 q⁻¹ dq/dt`` with ``dq/dt`` from the
        cubic spline through the samples (the angular velocity in the rotated
        frame); its stencil is the whole run of present samples the spline
        passes through (not-a-knot; a parabola for three samples, a line for
        two). "rotation_vector": numerical gradient of the rotation vectors,
        with :func:`estimate_linear_velocity`'s stencil (i-1, i, i+1, one-sided
        at the ends). In both modes NaN rows (missing samples) split the
        series into runs estimated on their own: a velocity is missing only at
        a missing sample and at a present one with no present neighbour.
    outlier_thresh : float, optional
        Reject samples where the norm of the second-order differences of the
        rotation vectors exceeds this, and interpolate the velocity there.
    cutoff : float, optional
        Low-pass the velocity at this fraction of the Nyquist frequency.

    Returns
    -------
    ndarray or DataArray
        Angular velocities in rad/s, ``arr``'s shape with the quaternion axis
        of length 3; a DataArray gets a ``cartesian_axis`` dimension (x, y, z)
        in place of the quaternion one.

    Raises
    ------
    ValueError
        For an unknown ``mode``, a quaternion axis not of length 4, zero
        quaternions, and the timestamp and option errors of
        :func:`estimate_linear_velocity`.

    Examples
    --------
    >>> q = [[np.cos(a / 2), 0, 0, np.sin(a / 2)] for a in (0.0, 0.1, 0.2, 0.3)]
    >>> estimate_angular_velocity(q, timestamps=[0, 1, 2, 3]).round(6)
    array([[0. , 0. , 0.1],
           [0. , 0. , 0.1],
           [0. , 0. , 0.1],
           [0. , 0. , 0.1]])
    """
    args = velocity_arguments(
        _angular, arr, dim, axis, timestamps, time_axis, outlier_thresh, cutoff, mode
    )
    if args.lazy is not None:
        return args.lazy
    return _angular(args, arr, outlier_thresh, cutoff, mode)


def _angular(args, arr, outlier_thresh, cutoff, mode):
    """:func:`estimate_angular_velocity` of a checked series (``args``) of ``arr``."""
    w = _angular_series(args.rows, args.t, mode, outlier_thresh, cutoff)
    out = args.result(w, 3)
    if not args.dataarray:
        return out
    import xarray as xr

    coords, dims = _replace_dim(
        dict(arr.coords), tuple(arr.dims), args.axis, "cartesian", 3
    )
    return xr.DataArray(out, coords, dims, arr.name, dict(arr.attrs))


# ---------------------------------------------------------------------------
# rotations and transforms between vector sets
# ---------------------------------------------------------------------------


def shortest_arc_rotation(
    v1: ArrayInput, v2: ArrayInput, dim: str | None = None, axis: int | None = None
) -> Any:
    """Rotation by the smallest angle that turns the direction of v1 into v2's.

    Finds ``r`` with ``v2 / |v2| = rot(r, v1) / |v1|``.

    Parameters
    ----------
    v1, v2 : array_like, shape (..., 3, ...)
        Vectors along ``axis``; the other axes broadcast. ``v1`` may be a
        DataArray.
    dim : str, optional
        For a DataArray ``v1``, the dimension holding x, y, z.
    axis : int, optional
        The axis holding x, y, z; default the last.

    Returns
    -------
    ndarray or DataArray, shape (..., 4, ...)
        Unit quaternions (w >= 0) along ``axis``; for antiparallel vectors a
        half turn about an axis perpendicular to them. A DataArray ``v1`` gives
        a DataArray with a ``quaternion_axis`` dimension (w, x, y, z).

    Raises
    ------
    ValueError
        For axes not of length 3, shapes that do not broadcast, or zero vectors.

    Examples
    --------
    >>> shortest_arc_rotation([1.0, 0, 0], [0, 1.0, 0]).round(6)
    array([0.707107, 0.      , 0.      , 0.707107])
    """
    pair = vector_pairs(v1, v2, dim, axis)
    a, b, ax1, ax2, axis = pair.a, pair.b, pair.axis1, pair.axis2, pair.axis
    am, bm = np.moveaxis(a, ax1, -1), np.moveaxis(b, ax2, -1)
    try:
        am, bm = np.broadcast_arrays(am, bm)
    except ValueError:
        raise ValueError(
            f"v1 and v2: shapes {a.shape} and {b.shape} cannot be broadcast together"
        ) from None
    na, nb = np.linalg.norm(am, axis=-1), np.linalg.norm(bm, axis=-1)
    for norm, name in ((na, "v1"), (nb, "v2")):
        if np.any(norm == 0):
            raise ValueError(f"{name} contains a zero vector, which has no direction")
    scale = na * nb
    q = np.concatenate(
        ((scale + np.einsum("...i,...i->...", am, bm))[..., None], np.cross(am, bm)),
        axis=-1,
    )
    qn = np.linalg.norm(q, axis=-1)
    # Antiparallel: the cross product vanishes, so any axis perpendicular to v1
    # will do; take the one from the coordinate axis least aligned with v1.
    opposite = qn <= 1e-8 * scale
    if np.any(opposite):
        a_opp = am[opposite]
        helper = np.eye(3)[np.argmin(np.abs(a_opp), axis=-1)]
        perp = np.cross(a_opp, helper)
        q[opposite] = np.concatenate(
            (
                np.zeros((len(perp), 1)),
                perp / np.linalg.norm(perp, axis=-1, keepdims=True),
            ),
            axis=-1,
        )
        qn = np.where(opposite, 1.0, qn)
    q = q / qn[..., None]
    pos = (
        axis
        if axis is not None and axis >= 0
        else q.ndim + (-1 if axis is None else axis)
    )
    out = np.moveaxis(q, -1, min(max(pos, 0), q.ndim - 1))
    if pair.dataarray and out.shape == a.shape[:ax1] + (4,) + a.shape[ax1 + 1 :]:
        import xarray as xr

        coords, dims = _replace_dim(
            dict(v1.coords), tuple(v1.dims), ax1, "quaternion", 4
        )
        return xr.DataArray(out, coords, dims, v1.name, dict(v1.attrs))
    return out


def _rotation_from_covariance(h: np.ndarray) -> np.ndarray:
    """Kabsch: the proper rotation R minimising sum |R p1 - p2|² for h = p1^T p2."""
    u, _, vt = np.linalg.svd(h)
    r = vt.T @ u.T
    if np.linalg.det(r) < 0:  # a reflection fits better: take the best rotation
        vt[2, :] *= -1
        r = vt.T @ u.T
    return r


def _quaternion(r: np.ndarray) -> np.ndarray:
    # r comes from an SVD: orthonormal with det +1 to rounding, so the
    # validity count of the kernel (tolerance 1: nothing is counted) is unused
    q, _ = _kc.quaternion_from_matrix(np.array(r[None], dtype=np.float64), 1.0)
    return q[0]


def _fit_transform(p1: np.ndarray, p2: np.ndarray):
    c1, c2 = p1.mean(axis=0), p2.mean(axis=0)
    return _transform_from_covariance((p1 - c1).T @ (p2 - c2), c1, c2)


def _transform_from_covariance(h: np.ndarray, c1: np.ndarray, c2: np.ndarray):
    r = _rotation_from_covariance(h)
    return c2 - r @ c1, r


def _rotation_dataarray(rotation):
    import xarray as xr

    labels = {"quaternion_axis": ["w", "x", "y", "z"]}
    return xr.DataArray(rotation, labels, "quaternion_axis", name="rotation")


def _transform_dataarrays(translation, rotation):
    import xarray as xr

    labels = {"cartesian_axis": ["x", "y", "z"]}
    translation = xr.DataArray(
        translation, labels, "cartesian_axis", name="translation"
    )
    return translation, _rotation_dataarray(rotation)


def best_fit_rotation(
    v1: ArrayInput, v2: ArrayInput, dim: str | None = None, axis: int | None = None
) -> Any:
    """Least-squares rotation between corresponding vectors (Kabsch).

    Finds the rotation ``r`` that minimises ``|| v2 - rot(r, v1) ||``.

    Parameters
    ----------
    v1, v2 : array_like, shape (..., 3, ...)
        Corresponding vectors (same shape, at least 2 dimensions, not all
        collinear). ``v1`` may be a DataArray.
    dim : str, optional
        For a DataArray ``v1``, the dimension holding x, y, z.
    axis : int, optional
        The axis holding x, y, z; default the last.

    Returns
    -------
    ndarray or DataArray, shape (4,)
        Unit quaternion with w >= 0 (a DataArray named "rotation" if ``v1``
        is one). Always a proper rotation, never a reflection.

    Raises
    ------
    ValueError
        For shapes that differ or have no length-3 axis, non-finite values, or
        vectors that are all collinear.

    Examples
    --------
    >>> best_fit_rotation([[1.0, 0, 0], [0, 1, 0]], [[0, 1.0, 0], [-1, 0, 0]]).round(6)
    array([0.707107, 0.      , 0.      , 0.707107])
    """
    pair = vector_pairs(v1, v2, dim, axis, rows="same", fit="rotation")
    rotation = _quaternion(_rotation_from_covariance(pair.covariance))
    if pair.dataarray:
        return _rotation_dataarray(rotation)
    return rotation


def best_fit_transform(
    v1: ArrayInput, v2: ArrayInput, dim: str | None = None, axis: int | None = None
) -> Any:
    """Least-squares rigid transform between corresponding points.

    Finds the rotation ``r`` and translation ``t`` that minimise
    ``|| v2 - (rot(r, v1) + t) ||``.

    Parameters
    ----------
    v1, v2 : array_like, shape (..., 3, ...)
        Corresponding points (same shape, at least 3 points not on one line).
        ``v1`` may be a DataArray.
    dim : str, optional
        For a DataArray ``v1``, the dimension holding x, y, z.
    axis : int, optional
        The axis holding x, y, z; default the last.

    Returns
    -------
    translation : ndarray or DataArray, shape (3,)
    rotation : ndarray or DataArray, shape (4,)
        Unit quaternion with w >= 0. DataArrays ("translation",
        "rotation") if ``v1`` is one.

    Raises
    ------
    ValueError
        For shapes that differ or have no length-3 axis, non-finite values,
        fewer than 3 points or collinear points.

    Examples
    --------
    >>> p = np.eye(3)
    >>> t, r = best_fit_transform(p, p + [1.0, 2.0, 3.0])
    >>> t.round(6), r.round(6) + 0.0  # + 0.0 turns -0.0 into 0.0
    (array([1., 2., 3.]), array([1., 0., 0., 0.]))
    """
    pair = vector_pairs(v1, v2, dim, axis, rows="same", fit="transform")
    translation, r = _transform_from_covariance(pair.covariance, *pair.centroids)
    rotation = _quaternion(r)
    if pair.dataarray:
        return _transform_dataarrays(translation, rotation)
    return translation, rotation


def iterative_closest_point(
    v1: ArrayInput,
    v2: ArrayInput,
    dim: str | None = None,
    axis: int | None = None,
    init_transform: Any = None,
    max_iterations: int = 20,
    tolerance: Any = 1e-3,
) -> Any:
    """Rigid transform aligning two point sets without known correspondences.

    Repeatedly pairs every point of ``v1`` (moved by the current estimate)
    with its nearest neighbour in ``v2`` and refits the transform, until the
    mean pairing distance changes by less than ``tolerance``. Finds ``r`` and
    ``t`` with ``v2 ~ rot(r, v1) + t``.

    Parameters
    ----------
    v1, v2 : array_like, shape (..., 3, ...)
        Point sets (sizes may differ; at least 3 points each, v1 not collinear).
        ``v1`` may be a DataArray.
    dim : str, optional
        For a DataArray ``v1``, the dimension holding x, y, z.
    axis : int, optional
        The axis holding x, y, z; default the last.
    init_transform : tuple of array_like, optional
        Initial guess ``(translation (3,), rotation (4,))``.
    max_iterations : int, default 20
        Maximum number of iterations.
    tolerance : float, default 1e-3
        Stop when the mean distance improves by less than this.

    Returns
    -------
    translation : ndarray or DataArray, shape (3,)
    rotation : ndarray or DataArray, shape (4,)
        Unit quaternion with w >= 0.

    Raises
    ------
    ValueError
        For axes not of length 3, non-finite values, fewer than 3 points,
        collinear ``v1``, a malformed ``init_transform`` or negative
        ``max_iterations``/``tolerance``.

    Notes
    -----
    Points with known correspondences (e.g. two time series resampled to the
    same timestamps) are better matched with :func:`best_fit_transform`.
    """
    from scipy.spatial import cKDTree

    args = closest_point_input(
        v1, v2, dim, axis, init_transform, max_iterations, tolerance
    )
    p1, p2 = args.p1, args.p2
    moved = p1.copy()
    if args.init is not None:
        t0, r0 = args.init
        moved = _qk.rotate_vectors(r0, moved) + t0

    tree = cKDTree(p2)
    prev_error = 0.0
    for _ in range(args.max_iterations):
        distances, idx = tree.query(moved, 1)
        t, r = _fit_transform(moved, p2[idx])
        moved = moved @ r.T + t
        error = float(np.mean(distances))
        if abs(prev_error - error) < tolerance:
            break
        prev_error = error

    translation, r = _fit_transform(p1, moved)
    rotation = _quaternion(r)
    if args.dataarray:
        return _transform_dataarrays(translation, rotation)
    return translation, rotation
