"""The estimators' one door call each: a velocity's series, a pair of vector sets.

:func:`velocity_arguments` is what :func:`rbm_nb.estimate_linear_velocity` and
:func:`rbm_nb.estimate_angular_velocity` call: it routes dask-backed data to
the chunked estimate (:func:`rbm_nb._door.dask_blocks.estimate`), and checks
everything else once (the series' rules in :mod:`rbm_nb._door.series`, the
options, the quaternions' axis and norms) before handing back a frozen
:class:`VelocityArguments` laid out as the engine takes it.
:func:`vector_pairs` does the same for the rotations between vector sets
(``shortest_arc_rotation``, ``best_fit_rotation``, ``best_fit_transform``,
``iterative_closest_point``).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np

from .._engine.velocity import lowpass_reach
from . import dask_blocks as _dask
from .series import enough_samples, series, velocity_options
from .shapes import along_axis
from .unpack import dim_axis, is_dataarray, kernel_array
from .validation import check_tolerance, check_unit_norms, is_scalar

__all__ = [
    "VelocityArguments",
    "velocity_arguments",
    "VectorPair",
    "vector_pairs",
    "ClosestPoint",
    "closest_point_input",
    "check_rank",
]


class VelocityArguments(NamedTuple):
    """A checked velocity estimate's input, or its lazy result.

    ``rows`` is the series as (time, series, components) float64, ``t`` its
    seconds; ``moved_shape``, ``axis`` and ``time_axis`` put the result back
    in the argument's layout. For dask-backed data only ``lazy`` is set.
    """

    rows: Any
    t: Any
    moved_shape: tuple
    axis: int
    time_axis: int
    dataarray: bool
    lazy: Any = None

    def result(self, out: np.ndarray, width: int) -> np.ndarray:
        """The engine's (time, series, width) output in the argument's layout."""
        out = out.reshape(self.moved_shape[:-1] + (width,))
        return np.moveaxis(out, (0, -1), (self.time_axis, self.axis))


def velocity_arguments(
    estimate: Callable,
    arr: Any,
    dim: Any,
    axis: Any,
    timestamps: Any,
    time_axis: Any,
    outlier_thresh: Any,
    cutoff: Any,
    mode: Any = None,
) -> VelocityArguments:
    """The one door call of a velocity estimator; ``mode`` only for angular ones.

    ``estimate(args, arr, outlier_thresh, cutoff, mode)`` is the estimator's
    step on a checked series: dask-backed data is estimated chunk by chunk
    with it (see :func:`rbm_nb._door.dask_blocks.estimate`), each chunk
    checked here (:func:`_estimate_block`), not by the facade again.
    """
    angular = mode is not None
    if _dask.is_dask(arr):
        eager = functools.partial(_estimate_block, estimate=estimate)
        return _lazy(
            eager, arr, dim, axis, timestamps, time_axis, outlier_thresh, cutoff, mode
        )
    data, axis, time_axis, t = series(arr, dim, axis, timestamps, time_axis)
    if angular and data.shape[axis] != 4:
        raise ValueError(
            f"arr must have length 4 (w, x, y, z) along axis {axis}, got shape {data.shape}"
        )
    velocity_options(outlier_thresh, cutoff, data.shape[time_axis], mode)
    moved = np.moveaxis(data, (time_axis, axis), (0, -1))
    norms = check_unit_norms(moved, "arr") if angular else None
    enough_samples(moved.shape[0])
    if norms is not None:
        _enough_present(norms.reshape(norms.shape[0], -1))
    rows = moved.reshape(moved.shape[0], -1, moved.shape[-1])
    return VelocityArguments(rows, t, moved.shape, axis, time_axis, is_dataarray(arr))


def _enough_present(norms: np.ndarray) -> None:
    """Refuse quaternion series with fewer than two samples without NaN (the
    rows' norms (n, b), NaN where missing, as the unit-norm check made them):
    the spline of an angular velocity needs two (the samples on each side of
    a missing one are differentiated on their own)."""
    present = norms.shape[0] - np.isnan(norms).sum(axis=0)
    if present.size and present.min() < 2:
        raise ValueError(
            f"arr needs at least 2 samples without NaN to estimate a velocity, "
            f"got {present.min()}"
        )


def _estimate_block(
    block: Any, dim: Any = None, axis: Any = None, timestamps: Any = None,
    cutoff: Any = None, mode: Any = None, *, estimate: Callable,
) -> Any:  # fmt: skip
    """One chunk (with its halo) of a lazy estimate, as an eager call: checked
    here, estimated by the estimator's step (outliers are rejected lazily
    over the whole series, so none here)."""
    args = velocity_arguments(
        estimate, block, dim, axis, timestamps, None, None, cutoff, mode
    )
    return estimate(args, block, None, cutoff, mode)


def _lazy(eager, arr, dim, axis, timestamps, time_axis, outlier_thresh, cutoff, mode):
    """A velocity estimate of dask-backed data, chunk by chunk with a halo."""
    if mode is None:
        halo = _dask.GRADIENT_HALO
        options: dict[str, Any] = {}
    else:
        halo = _dask.SPLINE_HALO if mode == "quaternion" else _dask.GRADIENT_HALO
        options = {"mode": mode}
    if outlier_thresh is not None:
        # its value, before the graph is built (rejection is lazy, see _dask)
        velocity_options(outlier_thresh, None)
    if cutoff is not None:
        # the value of cutoff, before it sets the halo; the series' length is
        # checked by each chunk's eager call, which reads the whole halo
        velocity_options(None, cutoff)
        halo = max(halo, lowpass_reach(cutoff))
    lazy = _dask.estimate(
        eager, arr, dim, axis, timestamps, time_axis, halo, mode is not None,
        **options, outlier_thresh=outlier_thresh, cutoff=cutoff,
    )  # fmt: skip
    return VelocityArguments(None, None, (), 0, 0, is_dataarray(arr), lazy)


class VectorPair(NamedTuple):
    """Two checked vector arguments: finite float64, x, y, z along ``axis1``/``axis2``.

    ``axis`` is the axis as the caller gave it (or the DataArray's ``dim``);
    ``rows1``/``rows2`` the vectors as (n, 3) rows, when asked for.
    """

    a: np.ndarray
    b: np.ndarray
    axis1: int
    axis2: int
    axis: Any
    dataarray: bool
    rows1: Any = None
    rows2: Any = None
    covariance: Any = None
    centroids: Any = None


def vector_pairs(
    v1: Any, v2: Any, dim: Any, axis: Any, rows: str | None = None,
    fit: str | None = None,
) -> VectorPair:  # fmt: skip
    """The one door call of the rotations between vector sets.

    ``rows``: None (vectors kept in their layout), "same" (as rows, of the
    same shape: corresponding vectors) or "any" (as rows, of any sizes).
    ``fit`` (with ``rows="same"``): "rotation" or "transform", the
    least-squares fit the rows are for; their ``covariance`` (about the
    ``centroids`` for a transform) is then computed and refused if the
    vectors are collinear, and the transform's at least 3 points.
    """
    axis = dim_axis(v1, dim, axis, "v1")
    a, ax1 = _vectors(v1, axis, "v1")
    b, ax2 = _vectors(v2, axis, "v2")
    rows1: Any = None
    rows2: Any = None
    if rows is not None:
        if a.ndim < 2:
            raise ValueError(
                f"v1 must be an array of vectors with at least 2 dimensions, got shape {a.shape}"
            )
        rows1 = np.moveaxis(a, ax1, -1).reshape(-1, 3)
        rows2 = np.moveaxis(b, ax2, -1).reshape(-1, 3)
        if rows == "same" and a.shape != b.shape:
            raise ValueError(
                f"v1 and v2 must have the same shape, got {a.shape} and {b.shape}"
            )
        for flat, name in ((rows1, "v1"), (rows2, "v2")):
            if not np.all(np.isfinite(flat)):
                raise ValueError(f"{name} must be finite")
    h: Any = None
    centroids: Any = None
    if fit == "rotation":
        h = rows1.T @ rows2
        check_rank(h, "the vectors of v1 or v2")
    elif fit == "transform":
        if len(rows1) < 3:
            raise ValueError(
                f"v1 and v2 need at least 3 points to fix a rigid transform, got {len(rows1)}"
            )
        centroids = rows1.mean(axis=0), rows2.mean(axis=0)
        h = (rows1 - centroids[0]).T @ (rows2 - centroids[1])
        check_rank(h, "the points of v1 or v2 (after removing their centroids)")
    return VectorPair(
        a, b, ax1, ax2, axis, is_dataarray(v1), rows1, rows2, h, centroids
    )


def _vectors(v, axis, name: str) -> tuple[np.ndarray, int]:
    """Finite float64 vectors with x, y, z along ``axis`` (kept in place)."""
    data = v.values if is_dataarray(v) else v
    ax = -1 if axis is None else axis
    moved, ax = along_axis(data, name, ax, 3, "x, y, z", finite=True)
    return np.moveaxis(moved, -1, ax), ax


class ClosestPoint(NamedTuple):
    """Checked input of ICP: point rows ``p1``, ``p2``; ``init``: the initial
    guess (translation (3,), rotation (4,)) or None; the loop's limits."""

    p1: np.ndarray
    p2: np.ndarray
    dataarray: bool
    init: Any
    max_iterations: int
    tolerance: float


def closest_point_input(
    v1: Any, v2: Any, dim: Any, axis: Any, init_transform: Any,
    max_iterations: Any, tolerance: Any,
) -> ClosestPoint:  # fmt: skip
    """The one door call of :func:`rbm_nb.iterative_closest_point`."""
    pair = vector_pairs(v1, v2, dim, axis, rows="any")
    p1, p2 = pair.rows1, pair.rows2
    for rows, name in ((p1, "v1"), (p2, "v2")):
        if len(rows) < 3:
            raise ValueError(f"{name} needs at least 3 points for ICP, got {len(rows)}")
    centred = p1 - p1.mean(axis=0)
    check_rank(centred.T @ centred, "the points of v1")
    if (
        not is_scalar(max_iterations)
        or not np.isfinite(max_iterations)
        or int(max_iterations) != max_iterations
        or max_iterations < 0
    ):
        raise ValueError(
            f"max_iterations must be a non-negative integer, got {max_iterations!r}"
        )
    check_tolerance(tolerance, "tolerance")
    init = None
    if init_transform is not None:
        try:
            t0, r0 = init_transform
        except (TypeError, ValueError):
            raise ValueError(
                "init_transform must be a (translation, rotation) tuple"
            ) from None
        t0 = np.asarray(getattr(t0, "values", t0), dtype=float)
        r0 = np.asarray(getattr(r0, "values", r0), dtype=float)
        if t0.shape != (3,) or r0.shape != (4,):
            raise ValueError(
                f"init_transform must hold a translation of shape (3,) and a rotation of "
                f"shape (4,), got {t0.shape} and {r0.shape}"
            )
        if not (np.isfinite(t0).all() and np.isfinite(r0).all()):
            raise ValueError(
                f"init_transform is not finite: translation {t0.tolist()}, "
                f"rotation {r0.tolist()}"
            )
        if not np.any(r0):
            raise ValueError("init_transform: the rotation is a zero quaternion")
        init = (t0, kernel_array(r0[None]))
    return ClosestPoint(p1, p2, pair.dataarray, init, int(max_iterations), tolerance)


def check_rank(h: np.ndarray, what: str) -> None:
    """Refuse a covariance ``h`` of collinear (or zero) vectors: the rotation
    about their line is undetermined."""
    s = np.linalg.svd(h, compute_uv=False)
    if not s[1] > 1e-10 * s[0]:
        raise ValueError(
            f"{what} are collinear (or all zero): the rotation about their common "
            f"line is undetermined"
        )
