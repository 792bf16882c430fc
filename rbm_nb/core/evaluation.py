"""Trajectory evaluation: absolute and relative pose error (what evo does), on rbm_nb's frames.

:func:`ape` and :func:`rpe` compare an estimated trajectory with a reference
one. Either may be

* the name of a registered moving frame (or a :class:`~rbm_nb.ReferenceFrame`),
  whose poses are looked up wrt ``frame`` (default: its parent);
* an xarray Dataset with ``position`` (time, cartesian_axis) and
  ``orientation`` (time, quaternion_axis) variables and a time coordinate,
  the schema of ``rbm.lookup_pose(..., as_dataset=True)`` and of the
  example head/eye recordings;
* a tuple ``(timestamps, positions, wxyz quaternions)`` of shapes (n,),
  (n, 3), (n, 4).

Timestamps are matched by rbm_nb's own lookups: the estimate is looked up
(``rbm.lookup_transform(..., time=...)``) at each reference timestamp
inside its time range, so its poses are interpolated there (translation
linearly, rotation by squad, as everywhere in rbm_nb). When both share
their timestamps this is exact and the numbers are evo's; evo instead pairs
each pose with the *nearest* one within ``max_diff`` (or slerps with its
``interpolation`` sync), which differs where the sampling differs.

The errors follow evo's definitions (``evo.core.metrics``): APE compares
``E_i = inv(P_i) Q_i`` (P estimate, Q reference), RPE compares the motions
``E_ij = inv(inv(Q_i) Q_j) inv(P_i) P_j`` over pairs chosen by frame count,
path length or rotation angle. The pose relations are

================================ =============================================
``"translation"``                ``|p_est - p_ref|`` (APE), ``|t(E)|`` (RPE), m
``"rotation"``                   ``|R(E) - I|_F`` (unitless)
``"full"``                       ``|E - I|_F`` (unitless)
``"angle_deg"``/``"angle_rad"``  rotation angle of ``R(E)``
``"point_distance"``             APE: as translation; RPE: ``| |dQ| - |dP| |``
``"point_distance_error_ratio"`` RPE only: the above in % of ``|dQ|``
================================ =============================================

(evo's names such as ``"translation part"`` or ``"rotation_angle_deg"`` are
accepted too.) Alignment is Umeyama's least-squares fit of the estimate's
positions onto the reference's: rigid (``align=True``), similarity
(``align=True, correct_scale=True``, evo's sim3), scale only
(``correct_scale=True`` alone), optionally from the first ``n_to_align``
matched poses.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .._door import evaluation as _door
from .._door.evaluation import POSE_RELATIONS, Trajectory
from .._infra import parallel as _parallel
from .._kernels import conversions as _kc
from .._kernels import evaluation as k
from .._kernels import rotations as _rk
from .._kernels._arrays import kernel_array
from .._kernels.evaluation import absolute_pose_errors, relative_pose_errors
from .conversions import MATRIX_TOLERANCE
from .frames import register_frame, resolve_frame

if TYPE_CHECKING:  # xarray is imported where a DataArray is made
    import xarray as xr

__all__ = [
    "POSE_RELATIONS",
    "Trajectory",
    "TrajectoryError",
    "ape",
    "rpe",
    "umeyama_alignment",
]


# ---------------------------------------------------------------------------
# alignment
# ---------------------------------------------------------------------------


def umeyama_alignment(source, target, *, with_scale: bool = False):
    """Least-squares similarity (or rigid) transform mapping ``source`` onto ``target``.

    Finds ``R, t, s`` minimising ``sum |target_i - (s R source_i + t)|²``
    (Umeyama 1991), with ``R`` a proper rotation.

    Parameters
    ----------
    source, target : array_like, shape (n, 3)
        Corresponding points, n >= 3 and not all on one line.
    with_scale : bool, default False
        Estimate ``s``; otherwise ``s = 1``.

    Returns
    -------
    rotation : ndarray, shape (3, 3)
    translation : ndarray, shape (3,)
    scale : float

    Raises
    ------
    ValueError
        If the shapes differ or the points are degenerate (collinear), where
        the rotation is not determined.

    Examples
    --------
    >>> import numpy as np
    >>> from rbm_nb.evaluation import umeyama_alignment
    >>> x = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    >>> R, t, s = umeyama_alignment(x, 2 * x + [1, 2, 3], with_scale=True)
    >>> float(round(s, 12)), t.round(12) + 0.0
    (2.0, array([1., 2., 3.]))
    """
    x, y = _door.umeyama_points(source, target)
    return _fit(x, y, with_scale)


def _fit(x: np.ndarray, y: np.ndarray, with_scale: bool):
    """Umeyama's fit of checked (n, 3) points (the estimate's matched positions
    in ``ape``/``rpe``, NaN rows of a recording's missing samples included)."""
    n = len(x)
    mean_x, mean_y = x.mean(axis=0), y.mean(axis=0)
    xc, yc = x - mean_x, y - mean_y
    var_x = np.sum(xc * xc) / n
    # einsum, not BLAS: on a loaded machine OpenBLAS's threads make these
    # thin (n, 3) products erratic (10-200 ms instead of ~1 ms)
    cov = np.einsum("ni,nj->ij", yc, xc) / n
    u, d, vt = np.linalg.svd(cov)
    # rank < 2: the rotation about the line is free. Relative to the largest
    # singular value (evo tests d > eps absolutely, which rounding noise of
    # collinear points passes)
    if not d[1] > 1e-12 * d[0]:
        raise ValueError(
            f"the {n} aligned positions are degenerate (all on one line or point): "
            "the alignment rotation is not determined"
        )
    sign = np.ones(3)
    if np.linalg.det(u) * np.linalg.det(vt) < 0.0:
        sign[2] = -1.0  # a reflection would fit better: take the best rotation
    rotation = (u * sign) @ vt
    scale = float(np.sum(d * sign) / var_x) if with_scale else 1.0
    translation = mean_y - scale * rotation @ mean_x
    return rotation, translation, scale


def _apply(traj: Trajectory, rotation, translation, scale) -> Trajectory:
    # column by column: numpy's matmul of an (n, 3) stack by a 3 x 3 matrix
    # goes through BLAS, whose threads make it erratic on a loaded machine
    pos = traj.positions
    p = scale * sum(pos[:, [k]] * rotation[:, k] for k in range(3)) + translation
    return traj._with_poses(p, _rotated(rotation, traj.orientations))


def _rotated(rotation: np.ndarray, q: np.ndarray) -> np.ndarray:
    """``qmul(quaternion_from_matrix(rotation), q)`` by the kernels those call.

    ``rotation`` is the fit's ``U V^T``, orthonormal to rounding, so no
    matrix is invalid; ``q`` holds the trajectory's unit quaternions.
    """
    matrix = kernel_array(np.reshape(rotation, (1, 3, 3)))
    head, _ = _kc.quaternion_from_matrix(matrix, float(MATRIX_TOLERANCE))
    rows = kernel_array(q)
    out = np.empty((len(rows), 4))
    _parallel.launch(_rk.qmul_into, _rk.qmul_into_parallel, len(rows), head, rows, out)
    return out


def _align(ref, est, est_full, n_to_align, align, correct_scale):
    if n_to_align is None:
        return est, est_full, None
    n = n_to_align
    rotation, translation, scale = _fit(
        est.positions[:n], ref.positions[:n], correct_scale
    )
    if not align:  # scale only (evo's correct_only_scale)
        rotation, translation = np.eye(3), np.zeros(3)
    alignment = {"rotation": rotation, "translation": translation, "scale": scale}
    return (
        _apply(est, rotation, translation, scale),
        _apply(est_full, rotation, translation, scale),
        alignment,
    )


# ---------------------------------------------------------------------------
# errors
# ---------------------------------------------------------------------------


def _from_parts(rel: str, trans: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Error values of a relation from the error poses' translations and angles."""
    if rel == "translation":
        return np.sqrt(np.einsum("ij,ij->i", trans, trans))
    if rel == "angle_rad":
        return angle
    if rel == "angle_deg":
        return np.rad2deg(angle)
    # |R - I|_F² = 2 (3 - trace R) = 8 sin²(angle / 2)
    rot = 2.0 * np.sqrt(2.0) * np.sin(angle / 2.0)
    if rel == "rotation":
        return rot
    return np.sqrt(rot * rot + np.einsum("ij,ij->i", trans, trans))


def _statistics(error: np.ndarray) -> dict[str, float]:
    sq = error * error
    return {
        "rmse": float(np.sqrt(np.mean(sq))),
        "mean": float(np.mean(error)),
        "median": float(np.median(error)),
        "std": float(np.std(error)),
        "min": float(np.min(error)),
        "max": float(np.max(error)),
        "sse": float(np.sum(sq)),
    }


def _contiguous(traj: Trajectory) -> tuple[np.ndarray, np.ndarray]:
    return kernel_array(traj.positions), kernel_array(traj.orientations)


@dataclass
class TrajectoryError:
    """The result of :func:`ape` or :func:`rpe`.

    Attributes
    ----------
    metric : {"APE", "RPE"}
    pose_relation : str
        The canonical name (see :data:`POSE_RELATIONS`).
    unit : str
        Unit of the error values ("" for unitless relations).
    error : xarray.DataArray, dims ("time",)
        The error per matched pose (APE) or per pose pair, stamped with the
        pair's second time (RPE).
    stats : dict of str to float
        ``rmse, mean, median, std, min, max, sse`` of the error.
    reference, estimate : Trajectory
        The matched reference poses and the estimate interpolated at their
        times (aligned, if alignment was asked for).
    alignment : dict or None
        ``rotation`` (3, 3), ``translation`` (3,) and ``scale`` of the
        alignment applied to the estimate, or None.
    aligned_estimate : Trajectory
        The whole estimate (all its samples) with the alignment applied.
    pairs : ndarray of int, shape (m, 2), or None
        RPE: the index pairs into the matched trajectories.
    """

    metric: str
    pose_relation: str
    unit: str
    error: xr.DataArray
    stats: dict
    reference: Trajectory
    estimate: Trajectory
    alignment: dict | None
    aligned_estimate: Trajectory
    pairs: np.ndarray | None = None
    description: str = ""

    def __repr__(self) -> str:
        unit = f" ({self.unit})" if self.unit else ""
        lines = [f"{self.metric} w.r.t. {self.pose_relation}{unit}{self.description}"]
        lines += [f"  {k:>6}: {v:.6g}" for k, v in self.stats.items()]
        return "\n".join(lines)

    def plot(self, ax=None):
        """Plot the error over time with its rmse, mean, median and ±std band.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Axes to draw into (a new figure otherwise).

        Returns
        -------
        matplotlib.axes.Axes
        """
        try:
            import matplotlib.pyplot as plt
        except ImportError as err:  # pragma: no cover - depends on the install
            raise ImportError(
                "TrajectoryError.plot needs matplotlib: pip install 'rbm_nb[notebook]'"
            ) from err
        if ax is None:
            _, ax = plt.subplots(figsize=(8, 3))
        time = self.error["time"].values
        values = self.error.values
        ax.plot(time, values, color="0.3", lw=1, label=self.metric)
        s = self.stats
        ax.axhline(s["rmse"], color="tab:blue", lw=1.5, label="rmse")
        ax.axhline(s["median"], color="tab:green", lw=1.5, label="median")
        ax.axhline(s["mean"], color="tab:red", lw=1.5, label="mean")
        ax.axhspan(s["mean"] - s["std"], s["mean"] + s["std"], color="tab:red",
                   alpha=0.15, label="std")  # fmt: skip
        unit = f" ({self.unit})" if self.unit else ""
        ax.set_ylabel(f"{self.pose_relation}{unit}")
        ax.set_xlabel("time")
        ax.set_title(f"{self.metric} w.r.t. {self.pose_relation}")
        ax.legend(loc="upper left", fontsize="small", ncol=5)
        return ax

    def register_aligned(self, name: str, parent, *, update: bool = False):
        """Register the (aligned) estimate as a moving frame, e.g. for a Scene.

        Parameters
        ----------
        name : str
            Name of the new frame.
        parent : str or ReferenceFrame
            The frame the reference trajectory is expressed in.
        update : bool, default False
            Replace a frame registered under ``name``.

        Returns
        -------
        ReferenceFrame
            The registered frame: all estimate samples, alignment applied.
        """
        traj = self.aligned_estimate
        register_frame(
            name, parent=parent, translation=traj.positions,
            rotation=traj.orientations, timestamps=traj.timestamps, update=update,
        )  # fmt: skip
        return resolve_frame(name, "name")


def _result(metric, rel, values, times, ref, est, alignment, est_full, pairs=None,
            description=""):  # fmt: skip
    import xarray as xr

    if len(values) == 0:
        raise ValueError(f"{metric}: no error values (no pose pairs were found)")
    unit = POSE_RELATIONS[rel]
    error = xr.DataArray(
        values, dims=("time",), coords={"time": times}, name=metric.lower(),
        attrs={"units": unit, "long_name": f"{metric} ({rel})"},
    )  # fmt: skip
    return TrajectoryError(
        metric, rel, unit, error, _statistics(values), ref, est, alignment, est_full,
        pairs, description,
    )  # fmt: skip


def ape(
    reference,
    estimate,
    *,
    align: bool = False,
    correct_scale: bool = False,
    n_to_align: int | None = None,
    pose_relation: str = "translation",
    frame=None,
) -> TrajectoryError:
    """Absolute pose error of an estimated trajectory against a reference.

    Parameters
    ----------
    reference, estimate : str, ReferenceFrame, xarray.Dataset or tuple
        Trajectories (see the module notes): a moving frame, a Dataset with
        ``position``/``orientation`` or ``(timestamps, positions, wxyz)``.
    align : bool, default False
        Fit the estimate onto the reference first (Umeyama, rigid).
    correct_scale : bool, default False
        Also fit a scale (sim3); alone (``align=False``) only the scale.
    n_to_align : int, optional
        Fit only the first ``n_to_align`` matched poses (>= 3).
    pose_relation : str, default "translation"
        One of :data:`POSE_RELATIONS` except ``"point_distance_error_ratio"``.
    frame : str or ReferenceFrame, optional
        The frame in which to look up frame trajectories (default: each
        frame's parent).

    Returns
    -------
    TrajectoryError

    Raises
    ------
    ValueError
        For an unknown pose relation, trajectories that overlap in fewer
        than two reference timestamps, degenerate alignment positions or
        bad trajectory data (the message names the argument).

    Examples
    --------
    >>> import numpy as np
    >>> from rbm_nb.evaluation import ape
    >>> t = np.arange(5.0)
    >>> p = np.c_[t, np.sin(t), np.zeros(5)]
    >>> q = np.tile([1.0, 0, 0, 0], (5, 1))
    >>> result = ape((t, p, q), (t, p + [0.1, 0, 0], q))
    >>> round(result.stats["rmse"], 12)
    0.1
    >>> round(ape((t, p, q), (t, p + [0.1, 0, 0], q), align=True).stats["max"], 12)
    0.0
    """
    args = _door.evaluation_inputs(
        resolve_frame, "APE", reference, estimate, frame, pose_relation, align,
        correct_scale, n_to_align,
    )  # fmt: skip
    rel, ref = args.relation, args.reference
    est, est_full, alignment = _align(
        ref, args.estimate, args.estimate_full, args.n_to_align, align, correct_scale
    )
    if rel in ("translation", "point_distance"):
        d = est.positions - ref.positions
        values = np.sqrt(np.einsum("ij,ij->i", d, d))
    else:
        trans, angle = absolute_pose_errors(*_contiguous(ref), *_contiguous(est))
        values = _from_parts(rel, trans, angle)
    return _result("APE", rel, values, ref.timestamps, ref, est, alignment, est_full)


def _pairs(
    traj: Trajectory, delta, delta_unit, radians, rel_delta_tol, all_pairs
) -> np.ndarray:
    """Index pairs of a checked ``delta`` (``radians``: an angle's, else None)."""
    n = len(traj)
    if delta_unit == "frames":
        step = int(delta)
        if all_pairs:
            i = np.arange(max(n - step, 0))
        else:
            i = np.arange(0, n, step)[:-1] if n > step else np.empty(0, dtype=int)
        return np.stack([i, i + step], axis=1).astype(np.int64)
    p, q = _contiguous(traj)
    if delta_unit == "meters":
        if all_pairs:
            return k.all_path_pairs(
                p, float(delta), float(float(delta) * rel_delta_tol)
            )
        return k.path_pairs(p, float(delta))
    tol = float(radians * rel_delta_tol)
    return (
        k.all_angle_pairs(q, radians, tol) if all_pairs else k.angle_pairs(q, radians)
    )


def rpe(
    reference,
    estimate,
    *,
    delta=1,
    delta_unit: str = "frames",
    pose_relation: str = "translation",
    all_pairs: bool = False,
    rel_delta_tol: float = 0.1,
    pairs_from_reference: bool = False,
    align: bool = False,
    correct_scale: bool = False,
    n_to_align: int | None = None,
    frame=None,
) -> TrajectoryError:
    """Relative pose error: how well the estimate reproduces the motion over ``delta``.

    Parameters
    ----------
    reference, estimate : str, ReferenceFrame, xarray.Dataset or tuple
        Trajectories, as for :func:`ape`.
    delta : int or float, default 1
        Distance between the two poses of a pair, in ``delta_unit``.
    delta_unit : {"frames", "meters", "degrees", "radians"}, default "frames"
        Frames: pairs ``(i, i + delta)``. Meters/degrees/radians: without
        ``all_pairs``, consecutive pairs where the path length / rotation
        accumulated since the pair's first pose reaches ``delta``; with it,
        for each pose the one whose path length from it is closest to
        ``delta`` (meters), or every pose whose rotation from it is within
        the tolerance of ``delta`` (angles: quadratic in the length).
    pose_relation : str, default "translation"
        One of :data:`POSE_RELATIONS`.
    all_pairs : bool, default False
        Use every start pose instead of consecutive, non-overlapping pairs.
    rel_delta_tol : float, default 0.1
        With ``all_pairs`` and a distance/angle unit: accept pairs within
        ``delta * rel_delta_tol`` of ``delta``.
    pairs_from_reference : bool, default False
        Select the pairs on the reference instead of the estimate (evo's
        default is the estimate).
    align, correct_scale, n_to_align : optional
        Alignment as in :func:`ape` (it cancels in the translation relation
        but not with scale).
    frame : str or ReferenceFrame, optional
        As in :func:`ape`.

    Returns
    -------
    TrajectoryError
        ``error`` is stamped with the time of each pair's second pose.

    Raises
    ------
    ValueError
        As :func:`ape`, plus for a bad ``delta``/``delta_unit`` or when no
        pairs are found.

    Examples
    --------
    >>> import numpy as np
    >>> from rbm_nb.evaluation import rpe
    >>> t = np.arange(6.0)
    >>> p = np.c_[t, np.zeros(6), np.zeros(6)]
    >>> q = np.tile([1.0, 0, 0, 0], (6, 1))
    >>> drift = p * [1.1, 1, 1]  # the estimate moves 10 % too far
    >>> rpe((t, p, q), (t, drift, q), delta=2).error.values.round(12)
    array([0.2, 0.2])
    """
    args = _door.evaluation_inputs(
        resolve_frame, "RPE", reference, estimate, frame, pose_relation, align,
        correct_scale, n_to_align, delta, delta_unit,
    )  # fmt: skip
    rel, ref = args.relation, args.reference
    est, est_full, alignment = _align(
        ref, args.estimate, args.estimate_full, args.n_to_align, align, correct_scale
    )
    pairs = _pairs(
        ref if pairs_from_reference else est,
        delta,
        delta_unit,
        args.radians,
        rel_delta_tol,
        all_pairs,
    )
    if len(pairs) == 0:
        raise ValueError(
            f"delta = {delta} {delta_unit} gives no pose pairs among the {len(ref)} "
            "matched poses; try a smaller delta"
        )
    i, j = pairs[:, 0], pairs[:, 1]
    if rel in ("point_distance", "point_distance_error_ratio"):
        d_ref = np.linalg.norm(ref.positions[j] - ref.positions[i], axis=1)
        d_est = np.linalg.norm(est.positions[j] - est.positions[i], axis=1)
        values = np.abs(d_ref - d_est)
        if rel == "point_distance_error_ratio":
            keep = d_ref != 0
            pairs, values = pairs[keep], values[keep] / d_ref[keep] * 100
    else:
        # the kernel takes writeable C-contiguous int64 pairs
        index = np.require(pairs, np.int64, ["C", "W"])
        trans, angle = relative_pose_errors(*_contiguous(ref), *_contiguous(est), index)
        values = _from_parts(rel, trans, angle)
    how = "all pairs" if all_pairs else "consecutive pairs"
    description = f", delta = {delta} {delta_unit}, {how}"
    return _result(
        "RPE", rel, values, ref.timestamps[pairs[:, 1]], ref, est, alignment, est_full,
        pairs, description,
    )  # fmt: skip
