"""Lazy velocity estimates: chunk by chunk with a halo, outliers across chunks.

A chunk's estimate reads :data:`~rbm_nb._door.dask_chunks.SPLINE_HALO` or
:data:`~rbm_nb._door.dask_chunks.GRADIENT_HALO` samples beyond its edges.
Quaternion series are made sign-continuous once, over the whole series,
before they are cut. Outlier rejection cannot be cut that way: a rejected
sample may be re-interpolated from kept samples any distance away, which no
halo covers, so the previous and next kept samples are carried across chunks
by cumulative fills; the low-pass then runs per chunk with the reach of its
slowest pole as halo.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .._engine import velocity as _velocity
from .._kernels import differences as dk
from .._kernels import quaternion as qk
from .._kernels import rotations as rk
from .dask_chunks import GRADIENT_HALO, as_dataarray, over_time, seconds_from_first
from .unpack import kernel_array, resolve_axis


def sign_continuous(q, time_dim: str, qdim: str):
    """Quaternions negated where needed so that successive ones have dot >= 0.

    The lazy counterpart of the kernels' sign correction, computed once over
    the whole series (a cumulative parity of sign changes), so that chunks
    cut from it need no correction of their own.
    """
    import dask.array as dsa
    import xarray as xr

    dots = (q * q.shift({time_dim: 1})).sum(qdim, skipna=False)
    flips = xr.where(dots < 0, 1, 0)
    parity = xr.DataArray(
        dsa.cumsum(flips.data, axis=flips.dims.index(time_dim)) % 2,
        flips.coords,
        flips.dims,
    )
    return q * (1 - 2 * parity)


def estimate(
    eager: Callable,
    arr,
    dim,
    axis,
    timestamps,
    time_axis,
    halo: int,
    quaternions: bool = False,
    **options,
):
    """A velocity estimate of dask-backed data, chunk by chunk with a halo."""
    plain = not hasattr(arr, "dims")
    if plain:
        if timestamps is None:
            raise ValueError("timestamps must be given for a dask array")
        arr = as_dataarray(arr, time_axis, timestamps)
        dim = arr.dims[resolve_axis(-1 if axis is None else axis, arr.ndim)]
        time_dim, axis = "time", None
    else:
        time_dim = (
            timestamps
            if isinstance(timestamps, str)
            else arr.dims[0 if time_axis is None else time_axis]
        )
    comp_dim = dim if dim is not None else arr.dims[-1 if axis is None else axis]
    if quaternions:
        arr = sign_continuous(arr, time_dim, comp_dim)
    fill = {comp_dim: (1.0, 0.0, 0.0, 0.0) if quaternions else 0.0}
    thresh = options.pop("outlier_thresh", None)
    cutoff = options.get("cutoff") if thresh is not None else None
    if thresh is not None:
        # the velocity without rejection and filtering, then both lazily
        options["cutoff"] = None

    def block(b):
        return eager(b, dim=dim, axis=axis, timestamps=time_dim, **options)

    out = over_time(block, arr, time_dim, halo=halo, fill=fill, global_seconds=True)
    if thresh is not None:
        score = over_time(
            lambda b: _outlier_score(b, time_dim, comp_dim, quaternions),
            arr,
            time_dim,
            halo=GRADIENT_HALO,
            fill=fill,
        )
        seconds = seconds_from_first(arr[time_dim].values)
        out = reinterpolate(out, score <= thresh, seconds, time_dim, thresh)
        if cutoff is not None:
            out = lowpass(out, time_dim, cutoff)
    return out.data if plain else out


def _outlier_score(block, time_dim: str, comp_dim: str, quaternions: bool):
    """The eager estimators' outlier score of a block, dims (time, others...).

    Second differences of the positions, or of the rotation vectors of the
    (already sign-continuous) quaternions; a sample's score reads one sample
    before it and two after, which the halo provides.
    """
    import xarray as xr

    moved = block.transpose(time_dim, ..., comp_dim)
    data = np.asarray(moved.values, dtype=np.float64)
    n, k = data.shape[0], data.shape[-1]
    series = data.reshape(n, -1, k)
    if quaternions:
        rv = np.empty((n, series.shape[1], 3))
        for b in range(series.shape[1]):
            rv[:, b, :] = rk.rotation_vectors(qk.unflip(kernel_array(series[:, b, :])))
        series = rv
    score = dk.second_difference_score(kernel_array(series))
    return xr.DataArray(
        score.reshape(data.shape[:-1]),
        {time_dim: moved[time_dim].variable},
        moved.dims[:-1],
    )


def _ffill_block(a: np.ndarray, axis: int) -> np.ndarray:
    """NaN replaced by the last non-NaN value before it along ``axis`` (in a block)."""
    moved = np.moveaxis(a, axis, 0)
    rows = np.arange(moved.shape[0]).reshape((-1,) + (1,) * (moved.ndim - 1))
    last = np.where(np.isnan(moved), 0, rows)
    np.maximum.accumulate(last, axis=0, out=last)
    return np.moveaxis(np.take_along_axis(moved, last, axis=0), 0, axis)


def _fill_from_previous_block(carried: np.ndarray, block: np.ndarray) -> np.ndarray:
    return np.where(np.isnan(block), carried, block)


def push(data, axis: int, backward: bool = False):
    """Forward (or backward) fill of NaN along ``axis`` of a dask array.

    Each block is filled on its own, then the last value of the blocks
    before it is carried in (dask's cumulative reduction), so the result is
    that of one fill over the whole array, whatever the chunks.
    """
    from dask.array.reductions import cumreduction

    index = [slice(None)] * data.ndim
    index[axis] = slice(None, None, -1)
    flip = tuple(index)
    if backward:
        data = data[flip]
    out = cumreduction(
        _ffill_block, _fill_from_previous_block, np.nan, data, axis, data.dtype
    )
    return out[flip] if backward else out


def _pushed(da, time_dim: str, backward: bool = False):
    return da.copy(data=push(da.data, da.dims.index(time_dim), backward))


def reinterpolate(v, keep, seconds: np.ndarray, time_dim: str, thresh: float):
    """Rejected samples of ``v`` interpolated in time between the kept ones.

    The lazy counterpart of the eager rejection: for a rejected sample at t,
    ``v_prev + (t - t_prev) / (t_next - t_prev) * (v_next - v_prev)`` with
    the previous and next kept samples of its series (the same arithmetic,
    so the same numbers). A series whose first or last samples are rejected,
    or that keeps fewer than 2, raises the eager path's error on compute.

    Parameters
    ----------
    v : xarray.DataArray
        Dask-backed velocities; ``time_dim`` plus components and others.
    keep : xarray.DataArray of bool
        Dask-backed, ``v``'s dims without the components, chunked alike.
    seconds : ndarray, shape (n,)
        Times of the samples in seconds from the first (as the eager path).
    """
    import dask
    import dask.array as dsa
    import xarray as xr

    n = len(seconds)
    chunks = {time_dim: v.chunksizes[time_dim]}
    t = xr.DataArray(seconds, dims=time_dim).chunk(chunks)
    rows = xr.DataArray(np.arange(n, dtype=np.float64), dims=time_dim).chunk(chunks)
    t_kept, rows_kept, v_kept = t.where(keep), rows.where(keep), v.where(keep)
    t_prev, t_next = _pushed(t_kept, time_dim), _pushed(t_kept, time_dim, True)
    v_prev, v_next = _pushed(v_kept, time_dim), _pushed(v_kept, time_dim, True)
    # kept samples (where t_next == t_prev) take v itself: divide them by 1
    w = (t - t_prev) / (t_next - t_prev).where(~keep, 1.0)
    filled = xr.where(keep, v, v_prev + w * (v_next - v_prev))
    data = filled.transpose(*v.dims).data
    # the checks read the first kept row from the start and the last from the end
    first_kept = _pushed(rows_kept, time_dim, True).isel({time_dim: 0}).data
    last_kept = _pushed(rows_kept, time_dim).isel({time_dim: -1}).data
    check = dask.delayed(_check_kept, pure=True)(first_kept, last_kept, n, thresh)
    ok = dsa.from_delayed(check, (), dtype=bool)
    data = dsa.map_blocks(_after_check, data, ok, dtype=data.dtype)
    return v.copy(data=data)


def _after_check(block: np.ndarray, ok) -> np.ndarray:
    return block


def _check_kept(first: np.ndarray, last: np.ndarray, n: int, thresh: float) -> bool:
    """The eager rejection's errors, from each series' first and last kept row."""
    first, last = np.atleast_1d(first), np.atleast_1d(last)
    counts = np.where(np.isnan(first), 0, np.where(first == last, 1, 2))
    if counts.min() < 2:
        raise ValueError(
            f"outlier_thresh={thresh} keeps only {counts.min()} sample(s) of a "
            f"series; at least 2 are needed to interpolate the others"
        )
    if (first > 0).any() or (last < n - 1).any():
        lead = (first > 0).any()
        edge = int(first.min()) if lead else int(n - 1 - last.max())
        raise ValueError(
            f"outlier_thresh={thresh} rejects the {'first' if lead else 'last'} "
            f"{max(edge, 1)} sample(s) of a series, which have no kept sample on "
            f"that side to be interpolated from; raise outlier_thresh or trim "
            f"the series"
        )
    return True


def lowpass(v, time_dim: str, cutoff: float):
    """The estimators' forward-backward low-pass of dask-backed ``v``, per chunk."""
    axis = v.dims.index(time_dim)

    def block(b):
        values = np.moveaxis(np.asarray(b.values), axis, 0)
        return b.copy(data=np.moveaxis(_velocity.lowpass(values, cutoff), 0, axis))

    return over_time(block, v, time_dim, halo=_velocity.lowpass_reach(cutoff))
