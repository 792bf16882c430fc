"""Velocities of sampled series: finite differences, outliers, low-pass.

The scheme follows rigid-body-motion: finite differences on (possibly
uneven) timestamps, optional suppression of outliers found by second-order
differences (the rejected samples are re-interpolated), and an optional
7th-order Butterworth low-pass applied forwards and backwards with
``cutoff`` as a fraction of the Nyquist frequency (the reference's
``filtfilt`` filter, run in second-order sections: ``sosfiltfilt``). Linear velocity uses numpy's gradient scheme; angular velocity
uses the derivative of the not-a-knot cubic spline through the quaternions
("quaternion" mode) or the gradient of the rotation vectors
("rotation_vector" mode).

:func:`linear_velocity` and :func:`angular_velocity` are the array-level
entry points used by the velocity lookups and by
:mod:`rbm_nb.estimators`, which adds axis handling and DataArrays.
"""

from __future__ import annotations

import math

import numpy as np

from .._kernels import differences as _dk
from .._kernels import quaternion as _qk
from .._kernels import rotations as _rk
from .._kernels import velocity_fused as _vf
from .._kernels._arrays import kernel_array
from . import time as _time

__all__ = [
    "MODES",
    "FILTER_PADLEN",
    "linear_series",
    "angular_series",
    "linear_velocity",
    "angular_velocity",
    "lowpass",
    "lowpass_reach",
]

MODES = ("quaternion", "rotation_vector")
_BUTTER_ORDER = 7
# filtfilt's default padding, 3 * (number of filter coefficients)
FILTER_PADLEN = 3 * (_BUTTER_ORDER + 1)


# ---------------------------------------------------------------------------
# the filter's reach (the options are checked at the door: _door.series)
# ---------------------------------------------------------------------------


def lowpass_reach(cutoff: float) -> int:
    """Samples beyond which the forward-backward low-pass's response is below 1e-16.

    What a chunk of a longer series must read on each side (besides the
    padding) for its filtered values to equal those of the whole series.
    """
    from scipy.signal import butter

    _, poles, _ = butter(_BUTTER_ORDER, cutoff, output="zpk")
    radius = float(np.max(np.abs(poles)))
    return FILTER_PADLEN + int(math.ceil(math.log(1e-16) / math.log(radius)))


# ---------------------------------------------------------------------------
# numerics on (n, b, k) arrays: time first, b independent series
# ---------------------------------------------------------------------------


def _reject_outliers(t, values, score, thresh) -> np.ndarray:
    keep = score <= thresh  # NaN scores are rejected too
    kept = keep.sum(axis=0)
    if kept.min() < 2:
        raise ValueError(
            f"outlier_thresh={thresh} keeps only {kept.min()} sample(s) of a series; "
            f"at least 2 are needed to interpolate the others"
        )
    # a rejected run at either end has no kept sample on one side to
    # interpolate from: refuse it rather than return NaN rows
    lead = ~keep[0]
    tail = ~keep[-1]
    if lead.any() or tail.any():
        where = "first" if lead.any() else "last"
        kept_rows = np.flatnonzero(keep.any(axis=1))
        edge = kept_rows[0] if where == "first" else len(keep) - 1 - kept_rows[-1]
        raise ValueError(
            f"outlier_thresh={thresh} rejects the {where} {max(int(edge), 1)} "
            f"sample(s) of a series, which have no kept sample on that side to be "
            f"interpolated from; raise outlier_thresh or trim the series"
        )
    return _dk.interpolate_rejected(t, kernel_array(values), keep)


def lowpass(values: np.ndarray, cutoff: float) -> np.ndarray:
    """Zero-phase Butterworth low-pass along axis 0 of (n, ...).

    Stretches of NaN (from gaps in the data or from rejected samples at the
    ends) are left out: every finite stretch is filtered on its own, and those
    too short for the filter become NaN, instead of the NaN spreading over
    the whole series.
    """
    from scipy.signal import butter, sosfiltfilt

    # second-order sections, not the transfer function (b, a) that
    # rigid-body-motion hands to filtfilt: the same filter, but a 7th-order
    # polynomial's rounding noise (~1e-10, depending on where a pass starts)
    # drops to that of each section, so a chunked series filters like the
    # whole one (rbm_nb._door.dask_blocks); both pad by the same 3 * 8 samples
    sos = butter(_BUTTER_ORDER, cutoff, output="sos")
    finite = np.isfinite(values)
    if finite.all():
        return sosfiltfilt(sos, values, axis=0)
    flat = values.reshape(values.shape[0], -1)
    out = np.full(flat.shape, np.nan)
    for col in range(flat.shape[1]):
        ok = np.isfinite(flat[:, col])
        edges = np.flatnonzero(np.diff(np.concatenate(([0], ok.view(np.int8), [0]))))
        for start, stop in zip(edges[::2], edges[1::2], strict=True):
            if stop - start > FILTER_PADLEN:
                out[start:stop, col] = sosfiltfilt(sos, flat[start:stop, col])
    return out.reshape(values.shape)


def _runs(valid: np.ndarray, breaks: np.ndarray | None = None) -> list[tuple[int, int]]:
    """(start, stop) of every run of True in ``valid``, also split where
    ``breaks[k]`` says samples k and k + 1 must not be differenced."""
    edges = np.flatnonzero(np.diff(np.concatenate(([0], valid.view(np.int8), [0]))))
    runs = list(zip(edges[::2].tolist(), edges[1::2].tolist(), strict=True))
    if breaks is None or not breaks.any():
        return runs
    cuts = np.flatnonzero(breaks) + 1
    out: list[tuple[int, int]] = []
    for start, stop in runs:
        inner = cuts[(cuts > start) & (cuts < stop)].tolist()
        bounds = [start, *inner, stop]
        out.extend(zip(bounds[:-1], bounds[1:], strict=True))
    return out


def _gradient_by_runs(
    values: np.ndarray, t: np.ndarray, breaks: np.ndarray | None
) -> np.ndarray:
    """:func:`_dk.gradient` of (n, k) values on each run of rows without NaN
    (also split at ``breaks``): numpy's three-point rule inside a run and
    one-sided first differences at its ends, so a missing sample makes only
    itself NaN, and a present sample with no present neighbour (nothing to
    difference it with). Nothing is differenced across a missing sample."""
    out = np.full(values.shape, np.nan)
    for start, stop in _runs(~_dk.nan_rows(kernel_array(values)), breaks):
        if stop - start >= 2:
            out[start:stop] = _dk.gradient(
                kernel_array(values[start:stop]), kernel_array(t[start:stop])
            )
    return out


def linear_series(
    x: np.ndarray,
    t: np.ndarray,
    outlier_thresh,
    cutoff,
    breaks: np.ndarray | None = None,
) -> np.ndarray:
    # at least 2 samples (_door.series.enough_samples), intervals that do not
    # underflow (_door.series.check_intervals)
    n = x.shape[0]
    flat = kernel_array(x.reshape(n, -1))
    if (breaks is None or not breaks.any()) and not _dk.nan_rows(flat).any():
        v = _dk.gradient(flat, t).reshape(x.shape)
    else:
        # each item's series on its own: its missing samples split it
        width = x.shape[-1] if x.ndim > 1 else 1
        v = np.empty(flat.shape)
        for c in range(0, flat.shape[1], width):
            v[:, c : c + width] = _gradient_by_runs(flat[:, c : c + width], t, breaks)
        v = v.reshape(x.shape)
    if outlier_thresh is not None:
        score = _dk.second_difference_score(kernel_array(x))
        v = _reject_outliers(t, v, score, outlier_thresh)
    if cutoff is not None:
        v = lowpass(v, cutoff)
    return v


def angular_series(
    q: np.ndarray,
    t: np.ndarray,
    mode,
    outlier_thresh,
    cutoff,
    breaks: np.ndarray | None = None,
) -> np.ndarray:
    # at least 2 samples, intervals that do not underflow: as linear_series
    n, nb, _ = q.shape
    # no zero row: the door refuses quaternions far from unit norm
    # (_door.validation.check_unit_norms) and frames' rotations are unit
    need_rv = mode == "rotation_vector" or outlier_thresh is not None
    no_breaks = breaks is None or not breaks.any()
    fused = not need_rv and mode == "quaternion" and n >= 4 and no_breaks
    if fused and nb == 1:
        # one series (a lookup's): the kernel's rates are the result, no copy
        rates, bad = _vf.body_rates(kernel_array(q[:, 0, :]), t)
        if not bad:
            w = rates.reshape(n, 1, 3)
            return w if cutoff is None else lowpass(w, cutoff)
    w = np.empty((n, nb, 3))
    # rotation vectors, needed by that mode and by the outlier score
    rv = np.empty((n, nb, 3) if need_rv else (0, nb, 3))
    for b in range(nb):
        if fused and nb > 1:
            # unflip, spline slopes and 2 q⁻¹ dq/dt in one kernel, unless a
            # sample is missing (then the runs below)
            rates, bad = _vf.body_rates(kernel_array(q[:, b, :]), t)
            if not bad:
                w[:, b, :] = rates
                continue
        # q and -q are the same rotation: differentiate a sign-continuous series
        qb = _qk.unflip(kernel_array(q[:, b, :]))
        if need_rv:
            rv[:, b, :] = _rk.rotation_vectors(qb)
        if mode == "rotation_vector":
            w[:, b, :] = _gradient_by_runs(rv[:, b, :], t, breaks)
            continue
        missing = _dk.nan_rows(qb)
        if not missing.any() and (breaks is None or not breaks.any()):
            w[:, b, :] = _dk.angular_velocity_from_derivative(
                qb, _dk.spline_derivative(qb, t)
            )
            continue
        valid = ~missing
        if valid.sum() < 2:
            raise ValueError(
                f"arr needs at least 2 samples without NaN to estimate a velocity, "
                f"got {valid.sum()}"
            )
        # missing samples split the series: no derivative is taken across
        # them (the motion may have jumped while nothing was recorded); runs
        # of a single sample have no velocity
        w[:, b, :] = np.nan
        for start, stop in _runs(valid, breaks):
            if stop - start < 2:
                continue
            qv = kernel_array(qb[start:stop])
            dq = _dk.spline_derivative(qv, kernel_array(t[start:stop]))
            w[start:stop, b, :] = _dk.angular_velocity_from_derivative(qv, dq)
    if outlier_thresh is not None:
        score = _dk.second_difference_score(rv)
        w = _reject_outliers(t, w, score, outlier_thresh)
    if cutoff is not None:
        w = lowpass(w, cutoff)
    return w


def linear_velocity(
    arr, timestamps, outlier_thresh=None, cutoff=None, breaks=None
) -> np.ndarray:
    """Linear velocity of positions sampled in time (array level).

    Parameters
    ----------
    arr : ndarray, shape (n, 3)
        Positions, time along axis 0 (float64).
    timestamps : ndarray, shape (n,)
        Strictly increasing times in seconds (float64).
    outlier_thresh, cutoff : float, optional
        As in :func:`estimate_linear_velocity`.
    Returns
    -------
    ndarray, shape (n, 3)
    """
    x = np.asarray(arr, dtype=np.float64)
    t = _time.seconds(timestamps, x.shape[0])
    return linear_series(
        x.reshape(x.shape[0], 1, -1), t, outlier_thresh, cutoff, breaks
    ).reshape(x.shape)


def angular_velocity(
    q,
    timestamps,
    mode="quaternion",
    outlier_thresh=None,
    cutoff=None,
    breaks=None,
) -> np.ndarray:
    """Angular velocity of orientations sampled in time (array level).

    Parameters
    ----------
    q : ndarray, shape (n, 4)
        Quaternions (w, x, y, z), time along axis 0 (float64).
    timestamps : ndarray, shape (n,)
        Strictly increasing times in seconds (float64).
    mode, outlier_thresh, cutoff
        As in :func:`estimate_angular_velocity`.

    Returns
    -------
    ndarray, shape (n, 3)
        In "quaternion" mode the vector part of ``2 q⁻¹ dq/dt``, i.e. the
        angular velocity in the rotated (body) frame.
    """
    qa = np.asarray(q, dtype=np.float64)  # (n, 4): the engine's own lookups
    t = _time.seconds(timestamps, qa.shape[0])
    return angular_series(qa[:, None, :], t, mode, outlier_thresh, cutoff, breaks)[
        :, 0, :
    ]
