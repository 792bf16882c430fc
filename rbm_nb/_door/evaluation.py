"""The trajectory evaluation's one door call each: ``ape``, ``rpe``, ``umeyama_alignment``.

:func:`evaluation_inputs` turns the two trajectories (frames, Datasets or
``(timestamps, positions, quaternions)`` tuples) and every option into one
checked, frozen value: the reference's poses inside the estimate's span, the
estimate looked up at their times, the whole estimate, and the options. The
facade then only aligns (numpy) and calls the error kernels.

Array trajectories become engine values (:class:`~rbm_nb._engine.frame_data.FrameData`)
here, with the checks and messages a ``ReferenceFrame`` built from them
gives (``frame 'estimate': rotation[3] ...``), so the facade never builds
frames or calls the lookup facades. The frames' registry lives above the
door, so the facade hands its ``resolve_frame`` in (as the lookups do).
"""

from __future__ import annotations

import numbers
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any, NamedTuple

import numpy as np

from .._engine import at_time as _at_time
from .._engine import chain as _chain
from .._engine import time as _time
from .._engine.frame_data import FrameData, Samples
from .._infra.frozen import is_frozen
from .._kernels import quaternion as kq
from . import coverage as _coverage
from .at_times import requested_at
from .unpack import float_array
from .validation import check_missing_rows, moving_samples, normalize_quaternions
from .xarray import transform_dataset

__all__ = [
    "POSE_RELATIONS",
    "Trajectory",
    "EvaluationInputs",
    "evaluation_inputs",
    "umeyama_points",
]

#: Canonical pose relation -> unit of the error.
POSE_RELATIONS = {
    "translation": "m",
    "rotation": "",
    "full": "",
    "angle_deg": "deg",
    "angle_rad": "rad",
    "point_distance": "m",
    "point_distance_error_ratio": "%",
}

# evo's enum values and member names
_ALIASES = {
    "translation part": "translation",
    "translation_part": "translation",
    "rotation part": "rotation",
    "rotation_part": "rotation",
    "full transformation": "full",
    "full_transformation": "full",
    "rotation angle in degrees": "angle_deg",
    "rotation_angle_deg": "angle_deg",
    "rotation angle in radians": "angle_rad",
    "rotation_angle_rad": "angle_rad",
    "point distance": "point_distance",
    "point distance error ratio": "point_distance_error_ratio",
}

_DELTA_UNITS = ("frames", "meters", "degrees", "radians")


@dataclass(frozen=True)
class Trajectory:
    """Poses over time: what :func:`~rbm_nb.evaluation.ape` and
    :func:`~rbm_nb.evaluation.rpe` compare.

    Attributes
    ----------
    timestamps : ndarray, shape (n,)
        Strictly increasing, numeric (seconds) or datetime64.
    positions : ndarray, shape (n, 3)
    orientations : ndarray, shape (n, 4)
        Unit quaternions ``w, x, y, z``.
    name : str
    """

    timestamps: np.ndarray
    positions: np.ndarray
    orientations: np.ndarray
    name: str = "trajectory"
    # the moving frame the poses come from and the frame they are wrt
    _frames: tuple = field(default=(), repr=False, compare=False)

    def __len__(self) -> int:
        return len(self.timestamps)

    def _with_poses(
        self, positions: np.ndarray, orientations: np.ndarray
    ) -> Trajectory:
        """The same times, name and frames with other poses (an aligned estimate)."""
        return replace(self, positions=positions, orientations=orientations)

    def to_dataset(self, frame_name: str | None = None):
        """The trajectory as an rbm-style Dataset (position, orientation, time)."""
        return transform_dataset(
            self.positions, self.orientations, frame_name, self.timestamps, pose=True
        )


class EvaluationInputs(NamedTuple):
    """``ape``/``rpe``'s checked inputs: matched trajectories and options."""

    relation: str
    reference: Trajectory  # the reference's poses inside the estimate's span
    estimate: Trajectory  # the estimate looked up at those times
    estimate_full: Trajectory  # every sample of the estimate
    n_to_align: int | None  # rows to align (None: no alignment)
    radians: float | None  # an RPE angle delta, in radians


# ---------------------------------------------------------------------------
# umeyama
# ---------------------------------------------------------------------------


def umeyama_points(source: Any, target: Any) -> tuple[np.ndarray, np.ndarray]:
    """``source`` and ``target`` as (n, 3) float arrays of finite numbers."""
    x = np.asarray(source, dtype=float)
    y = np.asarray(target, dtype=float)
    if x.ndim != 2 or x.shape[1] != 3 or x.shape != y.shape:
        raise ValueError(
            f"source and target must both have shape (n, 3), got {x.shape} and {y.shape}"
        )
    for name, arr in (("source", x), ("target", y)):
        # a NaN or infinity would make every number of the fit NaN (or the
        # SVD raise a LinAlgError that names nothing)
        finite = np.isfinite(arr)
        if not finite.all():
            row = int(np.argwhere(~finite)[0][0])
            raise ValueError(
                f"{name}[{row}] is not finite ({arr[row]}): the alignment needs "
                "finite points"
            )
    return x, y


# ---------------------------------------------------------------------------
# options
# ---------------------------------------------------------------------------


def _relation(pose_relation: Any, metric: str) -> str:
    rel = _ALIASES.get(pose_relation, pose_relation)
    if rel not in POSE_RELATIONS or (
        metric == "APE" and rel == "point_distance_error_ratio"
    ):
        valid = [
            r
            for r in POSE_RELATIONS
            if metric == "RPE" or r != "point_distance_error_ratio"
        ]
        raise ValueError(f"pose_relation must be one of {valid}, got {pose_relation!r}")
    return rel


def _delta(delta: Any, delta_unit: Any) -> float | None:
    """Check an RPE ``delta``; an angle's value in radians (else None)."""
    if delta_unit not in _DELTA_UNITS:
        raise ValueError(
            f"delta_unit must be one of {list(_DELTA_UNITS)}, got {delta_unit!r}"
        )
    if (
        not isinstance(delta, numbers.Real)
        or not np.isfinite(float(delta))
        or delta <= 0
    ):
        raise ValueError(f"delta must be a positive number, got {delta!r}")
    if delta_unit == "frames":
        if isinstance(delta, bool) or not float(delta).is_integer() or delta < 1:
            raise ValueError(
                f"delta must be a positive integer for frames, got {delta!r}"
            )
        return None
    if delta_unit == "meters":
        return None
    # the value as given (a float32 delta is converted in float32, as before)
    given: Any = delta
    radians = np.deg2rad(given) if delta_unit == "degrees" else float(delta)
    if not 0 <= radians <= np.pi:
        raise ValueError(
            f"delta must be an angle in [0, 180] degrees, got {delta!r} {delta_unit}"
        )
    return float(radians)


def _n_to_align(align: Any, correct_scale: Any, n_to_align: Any, n: int) -> int | None:
    """How many matched poses to align (None: no alignment)."""
    if not (align or correct_scale):
        if n_to_align is not None:
            raise ValueError("n_to_align needs align=True or correct_scale=True")
        return None
    if n_to_align is None:
        return n
    if not isinstance(n_to_align, numbers.Integral) or isinstance(n_to_align, bool):
        raise ValueError(f"n_to_align must be an integer, got {n_to_align!r}")
    if not 3 <= int(n_to_align) <= n:
        raise ValueError(
            f"n_to_align must lie between 3 and the {n} matched poses, got {n_to_align}"
        )
    return int(n_to_align)


# ---------------------------------------------------------------------------
# trajectories
# ---------------------------------------------------------------------------


def _unit(q: Any) -> np.ndarray:
    """Orientations of a frame or lookup as unit quaternions.

    Frames hand back recorded quaternions as given (|q| - 1 up to the unit
    tolerance, ~1e-4 in recordings); the error kernels rotate with them, so
    they get the unit quaternions the frame itself computes with.
    """
    return normalize_quaternions(float_array(q, "orientations"), "orientations", True)


def _from_frame(resolve: Callable, value: Any, name: str, frame: Any) -> Trajectory:
    moving = resolve(value, name)
    if moving.timestamps is None:
        raise ValueError(
            f"{name}: frame {moving.name!r} is static; a trajectory needs a moving frame"
        )
    if frame is None:
        if moving.parent is None:
            raise ValueError(f"{name}: frame {moving.name!r} is a root; pass frame=")
        into = moving.parent
    else:
        into = resolve(frame, "frame")
    # what lookup_pose(moving, into) checks and looks up
    to_frame = resolve(into, "reference")
    _coverage.chain_samples(moving, to_frame)
    p, q, t = _chain.lookup_transform(moving, to_frame)
    return Trajectory(
        np.asarray(t), np.asarray(p), _unit(q), moving.name or name, (moving, to_frame)
    )


def _samples(label: str, track: Any, translation: Any, rotation: Any) -> Samples:
    """A moving frame's samples, checked as ``ReferenceFrame`` checks them."""
    n = len(track)
    t = float_array(translation, f"{label}translation")
    if t.shape != (n, 3):
        raise ValueError(_shape_message(label, "translation", t.shape, (n, 3)))
    stored = float_array(rotation, f"{label}rotation")
    if stored.shape != (n, 4):
        raise ValueError(_shape_message(label, "rotation", stored.shape, (n, 4)))
    if n > 1:
        fused = moving_samples(t, stored)
        if fused is not None:
            t_fused, public, unit, missing = fused
            return Samples(track, t_fused, unit, public, missing)
    # one check at a time, each naming the row it finds
    check_missing_rows(t, f"{label}translation")
    missing = check_missing_rows(stored, f"{label}rotation")
    r = normalize_quaternions(stored, f"{label}rotation", allow_nan=True)
    t = np.array(t, dtype=np.float64, order="C")
    public = np.array(stored, dtype=np.float64, order="C")
    r = np.ascontiguousarray(r, dtype=np.float64)
    return Samples(track, t, kq.unflip(r) if n > 1 else r, public, missing)


def _shape_message(label: str, name: str, got: tuple, expected: tuple) -> str:
    hint = ""
    if len(got) >= 1 and got[-1] == expected[1]:
        hint = f" (one row per timestamp: {expected[0]} timestamps given)"
    return f"{label}{name} must have shape {expected}, got {got}{hint}"


def _from_arrays(t: Any, p: Any, q: Any, name: str) -> Trajectory:
    t = np.asarray(getattr(t, "values", t))
    if t.ndim != 1 or t.dtype.kind not in "iufM":
        raise ValueError(
            f"{name}: timestamps must be a 1-d numeric or datetime64 array, "
            f"got shape {t.shape} and dtype {t.dtype}"
        )
    if len(t) < 2:
        raise ValueError(f"{name}: a trajectory needs at least 2 poses, got {len(t)}")
    label = f"frame {name!r}: "
    track = _time.as_track(t, f"{label}timestamps", copy=not is_frozen(t))
    samples = _samples(label, track, p, q)
    # the value a ReferenceFrame(name, parent=root, ...) hands the engine
    identity = np.array([[1.0, 0.0, 0.0, 0.0]])
    root = FrameData(
        f"{name} world", None, Samples(None, np.zeros((1, 3)), identity, identity)
    )
    moving = FrameData(name, root, samples)
    return Trajectory(
        np.asarray(moving.timestamps), np.asarray(samples.t),
        _unit(samples.rotation), name, (moving, root),
    )  # fmt: skip


def _trajectory(resolve: Callable, value: Any, name: str, frame: Any) -> Trajectory:
    if isinstance(value, Trajectory):
        return _from_arrays(value.timestamps, value.positions, value.orientations, name)
    # a ReferenceFrame (above the door) is known by the engine value it holds
    if isinstance(value, str) or isinstance(getattr(value, "data", None), FrameData):
        return _from_frame(resolve, value, name, frame)
    if type(value).__name__ == "Dataset" and type(value).__module__.startswith(
        "xarray"
    ):
        missing = [v for v in ("position", "orientation") if v not in value.data_vars]
        if missing:
            raise ValueError(
                f"{name}: the Dataset has no {' or '.join(missing)} variable "
                f"(expected position (time, cartesian_axis) and orientation "
                f"(time, quaternion_axis); has {sorted(value.data_vars)})"
            )
        dim = value["position"].dims[0]
        if dim not in value.coords:
            raise ValueError(
                f"{name}: the Dataset has no coordinate for dimension {dim!r}"
            )
        return _from_arrays(
            value[dim].values,
            value["position"].transpose(dim, ...).values,
            value["orientation"].transpose(dim, ...).values,
            name,
        )
    if isinstance(value, (tuple, list)) and len(value) == 3:
        timestamps, positions, quaternions = value
        return _from_arrays(timestamps, positions, quaternions, name)
    raise TypeError(
        f"{name} must be a frame name, a ReferenceFrame, an xarray Dataset with "
        f"position/orientation or a (timestamps, positions, quaternions) tuple, "
        f"got {type(value).__name__}"
    )


def _match(ref: Trajectory, est: Trajectory) -> tuple[Trajectory, Trajectory]:
    """Reference poses inside the estimate's time span, and the estimate there."""
    if (ref.timestamps.dtype.kind == "M") != (est.timestamps.dtype.kind == "M"):
        raise ValueError(
            "reference and estimate timestamps must both be datetime64 or both "
            f"numeric, got {ref.timestamps.dtype} and {est.timestamps.dtype}"
        )
    t = ref.timestamps
    inside = (t >= est.timestamps[0]) & (t <= est.timestamps[-1])
    if inside.sum() < 2:
        raise ValueError(
            f"reference ({t[0]} to {t[-1]}) and estimate ({est.timestamps[0]} to "
            f"{est.timestamps[-1]}) overlap in {int(inside.sum())} reference "
            "timestamp(s); at least 2 are needed"
        )
    times = t[inside]
    moving, into = est._frames
    # inside the estimate's span by construction: the lookup cannot extrapolate
    p, q, _ = _at_time.transform_at_times(
        moving, into, requested_at(moving, into, times)
    )
    matched_ref = Trajectory(
        times, ref.positions[inside], ref.orientations[inside], ref.name, ref._frames
    )
    matched_est = Trajectory(times, p, _unit(q), est.name, est._frames)
    _check_complete(matched_ref, "reference")
    _check_complete(matched_est, "estimate")
    return matched_ref, matched_est


def _check_complete(traj: Trajectory, name: str) -> None:
    """Refuse a matched pose that is missing (a NaN row of a frame or array).

    Frames keep NaN rows as missing samples and lookups hand them on; an
    error or an alignment over them would be NaN (or an SVD that does not
    converge), not a number of the trajectories.
    """
    # one sum per array first (a NaN row makes it NaN): the row-wise test,
    # a reduction along the short axis, costs ~2 ms on a 66k-pose recording
    if not (np.isnan(traj.positions.sum()) or np.isnan(traj.orientations.sum())):
        return
    missing = np.isnan(traj.positions).any(axis=1) | np.isnan(traj.orientations).any(
        axis=1
    )
    if missing.any():
        i = int(np.argmax(missing))
        raise ValueError(
            f"{name}: {int(missing.sum())} of the {len(traj)} matched poses are "
            f"missing (NaN), the first at time {traj.timestamps[i]} (matched pose "
            f"{i}): ape and rpe compare complete poses; drop or fill the missing "
            "samples first"
        )


def evaluation_inputs(
    resolve: Callable,
    metric: str,
    reference: Any,
    estimate: Any,
    frame: Any,
    pose_relation: Any,
    align: Any,
    correct_scale: Any,
    n_to_align: Any,
    delta: Any = None,
    delta_unit: Any = None,
) -> EvaluationInputs:
    """``ape`` (``metric`` "APE") or ``rpe`` ("RPE", with ``delta``/``delta_unit``)
    inputs checked, in the order the messages come: options, trajectories,
    the match, the alignment rows."""
    rel = _relation(pose_relation, metric)
    radians = _delta(delta, delta_unit) if metric == "RPE" else None
    ref = _trajectory(resolve, reference, "reference", frame)
    est_full = _trajectory(resolve, estimate, "estimate", frame)
    ref, est = _match(ref, est_full)
    n = _n_to_align(align, correct_scale, n_to_align, len(ref))
    return EvaluationInputs(rel, ref, est, est_full, n, radians)
