"""The explorer's gaze yaw in one pass per eye (issue 35: the 3 h build).

:func:`rbm_nb.explorer.gaze_yaw` is :func:`rbm_nb.gaze.directions`, then
:func:`~rbm_nb.gaze.angles`, per eye, keeping the azimuth: at 3 h (3.7 M
samples per eye) that made a masked copy of the eye's rotations, the
directions (n, 3), their representation in the head, the angles (n, 2) and
their validity masks, for one column kept. In the explorer's frames the
eyes' parent reaches the head through static frames only; then
:func:`yaw_columns` makes the same values (bit for bit: the same
operations in the same order, ``_kernels.gaze_rows.sight_components``,
and numpy's own ``arctan2``) writing only the (n, 2) result. Anything else
(a moving frame between, eyes on two clocks, no confidence, an argument
the gaze calls would refuse) returns None, and the caller takes the gaze
calls themselves.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._engine import chain as _chain
from .._infra.frozen import kernel_alias
from .._infra.frozen import kernel_readable as _readable
from .._kernels import gaze_rows as _gk
from .._kernels._arrays import kernel_array
from ..core import frames as registry

# the eye frame's line of sight (camera convention: z forward), and the
# head's axes (x forward, y left, z up) whose azimuth is the yaw
_LINE_OF_SIGHT = np.array([0.0, 0.0, 1.0])
_FORWARD = np.array([1.0, 0.0, 0.0])
_RIGHT = np.cross(_FORWARD, np.array([0.0, 0.0, 1.0]))


def yaw_columns(
    eyes: list[Any],
    names: list[str],
    head: str,
    min_confidence: float,
    max_angle: float | None,
) -> tuple[np.ndarray, Any] | None:
    """The eyes' yaw (n, 2; deg, + left) and the confidence DataArray whose
    time index they share, or None where this route does not apply."""
    if max_angle is not None and not (
        isinstance(max_angle, (int, float)) and 0 < max_angle <= 180
    ):
        return None  # the gaze calls word the error
    if head not in registry.registry or any(n not in registry.registry for n in names):
        return None
    if any(ds is None or "confidence" not in ds for ds in eyes):
        return None
    confidences = [ds.confidence for ds in eyes]
    first = confidences[0]
    if first.dims != ("time",) or "time" not in first.indexes:
        return None
    if any(
        c.dims != ("time",) or "time" not in c.indexes
        or not c.indexes["time"].equals(first.indexes["time"])
        for c in confidences[1:]
    ):  # fmt: skip
        return None
    into = registry.registry[head].data
    check = max_angle is not None
    min_z = float(np.cos(np.radians(max_angle))) if max_angle is not None else 0.0
    times = first["time"].values
    out = np.empty((len(times), len(eyes)))
    xy = np.empty((2, len(times)))
    for k, (name, confidence) in enumerate(zip(names, confidences, strict=True)):
        eye = registry.registry[name].data
        if eye.track is None or eye.parent is None:
            return None
        static = _chain.static_transform(eye.parent, into)
        if static is None or not np.array_equal(eye.track.values, times):
            return None
        samples = eye.samples
        missing = samples.missing_rows
        if missing is None:
            missing = np.zeros(len(times), dtype=bool)
        _gk.sight_components(
            _readable(samples.stored_rotation), kernel_alias(missing),
            _readable(np.asarray(confidence.values, dtype=float)),
            float(min_confidence), _LINE_OF_SIGHT, min_z, check,
            kernel_array(static[1][0]), _RIGHT, _FORWARD, xy,
        )  # fmt: skip
        # gaze.angles' azimuth, as it makes it, negated (+ left)
        azimuth = np.arctan2(xy[0], xy[1], out=xy[0])
        np.degrees(azimuth, out=azimuth)
        np.negative(azimuth, out=out[:, k])
    return out, first
