"""The door of the velocity estimators: a sampled series and its options.

:func:`series` unpacks what :func:`rbm_nb.estimate_linear_velocity` and
:func:`rbm_nb.estimate_angular_velocity` take (an array or DataArray, the
spatial ``dim``/``axis``, the ``time_axis`` and the timestamps, or for a
DataArray the coordinate naming them) and checks it once: numbers, a time
axis besides the spatial one, rows finite or a missing sample (NaN), one
timestamp per sample, strictly increasing. :func:`velocity_options` checks
the options (``mode``, ``outlier_thresh``, ``cutoff`` and, given the number
of samples, whether the low-pass filter has enough of them); the velocity
lookups check the values of the same options here. The engine
(:mod:`rbm_nb._engine.velocity`) then computes on what comes out.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._engine import time as _time
from .._engine.velocity import FILTER_PADLEN, MODES
from .._kernels._arrays import is_scalar
from .unpack import dim_axis, is_dataarray, kernel_array, moveaxis, resolve_axis
from .validation import check_no_inf

__all__ = ["Series", "series", "check_intervals", "enough_samples", "velocity_options"]


class Series:
    """A checked series: data (float64), its axes (non-negative) and seconds."""

    __slots__ = ("data", "axis", "time_axis", "t")

    def __init__(self, data: np.ndarray, axis: int, time_axis: int, t: np.ndarray):
        self.data = data
        self.axis = axis
        self.time_axis = time_axis
        self.t = t

    def __iter__(self):
        return iter((self.data, self.axis, self.time_axis, self.t))


def series(arr: Any, dim: Any, axis: Any, timestamps: Any, time_axis: Any) -> Series:
    """Data, spatial axis, time axis and timestamps (seconds) of a series argument.

    Raises
    ------
    ValueError
        Naming ``arr``, ``dim``, ``axis``, ``time_axis`` or ``timestamps``:
        not numeric, no time axis besides the spatial one, both axes the
        same, a dim or coordinate the DataArray does not have, missing
        timestamps, timestamps of another length or not increasing, an
        infinity in a row.
    """
    if is_dataarray(arr):
        data = np.asarray(arr.values)
        axis = dim_axis(arr, dim, axis)
        if isinstance(timestamps, str):
            if timestamps in arr.dims:
                t_axis = arr.dims.index(timestamps)
            elif timestamps in arr.coords and arr.coords[timestamps].ndim == 1:
                t_axis = arr.dims.index(arr.coords[timestamps].dims[0])
            else:
                raise ValueError(
                    f"timestamps {timestamps!r} is not a coordinate of arr"
                )
            if (
                time_axis is not None
                and resolve_axis(time_axis, data.ndim, "time_axis") != t_axis
            ):
                raise ValueError(
                    f"time_axis={time_axis} contradicts timestamps={timestamps!r}"
                )
            if timestamps not in arr.coords:
                raise ValueError(f"dimension {timestamps!r} of arr has no coordinate")
            time_axis, timestamps = t_axis, arr.coords[timestamps].values
        elif timestamps is None:
            time_axis = 0 if time_axis is None else time_axis
            if data.ndim < 2:
                raise ValueError("arr needs a time axis besides the spatial one")
            time_dim = arr.dims[resolve_axis(time_axis, data.ndim, "time_axis")]
            if time_dim not in arr.coords:
                raise ValueError(
                    f"arr's time dimension {time_dim!r} has no coordinate; pass timestamps"
                )
            timestamps = arr.coords[time_dim].values
    else:
        dim_axis(arr, dim, axis)  # raises for a dim
        data = np.asarray(arr)
        if timestamps is None:
            raise ValueError(
                "timestamps must be given unless arr is a DataArray with a time coordinate"
            )
        if isinstance(timestamps, str):
            raise ValueError(
                "timestamps can only name a coordinate when arr is a DataArray"
            )
    if data.dtype.kind not in "biuf":
        raise ValueError(f"arr must be numeric, got dtype {data.dtype}")
    if data.ndim < 2:
        raise ValueError(
            f"arr must have a time axis and a spatial axis, got shape {data.shape}"
        )
    axis = resolve_axis(-1 if axis is None else axis, data.ndim, "axis")
    time_axis = resolve_axis(
        0 if time_axis is None else time_axis, data.ndim, "time_axis"
    )
    if axis == time_axis:
        raise ValueError(f"the spatial axis and the time axis are both axis {axis}")
    t = _time.seconds(timestamps, data.shape[time_axis])
    check_intervals(t)
    data = kernel_array(data)
    # NaN rows are missing samples (gaps); infinities are mistakes
    check_no_inf(moveaxis(data, (time_axis, axis), (0, -1)), "arr")
    return Series(data, axis, time_axis, t)


# Velocities divide by sampling intervals and by their products (numpy's
# three-point weights use h0 h1 (h0 + h1), the spline's system h²): below
# this interval those underflow and the results are silently wrong (at
# 1e-300 s: NaN rows and slopes off by 1e3). No clock samples this finely.
MIN_INTERVAL = 1e-90


def check_intervals(t: np.ndarray, what: str = "timestamps") -> None:
    """Refuse sampling intervals a velocity cannot be computed from."""
    if len(t) < 2:
        return
    steps = np.subtract(t[1:], t[:-1])
    if steps.min() >= MIN_INTERVAL:
        return  # (one pass when it is fine; below: where it is not)
    k = int(np.argmin(steps))
    if steps[k] < MIN_INTERVAL:
        raise ValueError(
            f"{what}: samples {k} and {k + 1} are {steps[k]:.3g} s apart; a velocity "
            f"needs sampling intervals of at least {MIN_INTERVAL:g} s (its formulas "
            f"multiply intervals, which underflows below that)"
        )


def enough_samples(n: int) -> None:
    """A velocity reads two samples at least (numpy's gradient, the spline's
    derivative): refuse fewer, as the door knows ``n`` before the engine."""
    if n < 2:
        raise ValueError(
            f"arr needs at least 2 samples to estimate a velocity, got {n}"
        )


def velocity_options(
    outlier_thresh: Any, cutoff: Any, n: int | None = None, mode: Any = None
) -> Any:
    """Check a velocity's options; ``n`` (samples), if known, against the filter.

    Returns ``mode`` (for calls that pass it on).

    Raises
    ------
    ValueError
        For a ``mode`` other than "quaternion" or "rotation_vector" (when
        given), a negative or non-numeric ``outlier_thresh``, a ``cutoff``
        outside (0, 1), or ``n`` too few samples for the low-pass filter.
    """
    if mode is not None and mode not in MODES:
        raise ValueError(
            f"mode must be 'quaternion' or 'rotation_vector', got {mode!r}"
        )
    if outlier_thresh is not None:
        if not is_scalar(outlier_thresh) or not outlier_thresh >= 0:
            raise ValueError(
                f"outlier_thresh must be a non-negative number, got {outlier_thresh!r}"
            )
    if cutoff is not None:
        if not is_scalar(cutoff) or not 0 < cutoff < 1:
            raise ValueError(
                f"cutoff must be a fraction of the Nyquist frequency in (0, 1), got {cutoff!r}"
            )
        if n is not None and n <= FILTER_PADLEN:
            raise ValueError(
                f"cutoff: the low-pass filter needs more than {FILTER_PADLEN} samples, got {n}"
            )
    return mode
