"""Lazy evaluation of rbm_nb's array functions on dask-backed data.

A public function that receives a dask-backed DataArray (or a dask array)
hands it here instead of converting it to NumPy. The work is cut along time
into one task per chunk; each task runs the ordinary eager function on its
chunk, read with enough neighbouring samples (the *halo*) that its result
equals the eager result on the whole array:

- transforms look the frames up at each sample's own time, so a chunk needs
  no neighbours (halo 0);
- finite differences need the next samples, the not-a-knot spline through
  quaternions about 30 (its influence decays by 2 - sqrt(3) per sample), and
  the Butterworth low-pass as many as its slowest pole needs to decay to
  1e-16;
- quaternion series whose velocity is estimated are made sign-continuous
  once, lazily, before they are cut (the eager estimators make them
  sign-continuous from the first sample on, which a chunk cannot see).

Frames are resolved once, when the graph is built, on the client: the
graph holds their values (:mod:`rbm_nb.core._frame_snapshot`), not their names,
so the tasks run on any scheduler -- threads, worker processes, workers on
other machines, whose registries are empty. **A graph is a snapshot of the
registry**: a frame registered, replaced or removed after a lazy call does
not change its result (call the function again to use the new frames).
Each task carries only the samples of each moving frame that its chunk's
time window needs (:data:`MARGIN` more on each side), so a task's size
grows with its chunk, not with the recording, and every sample of a frame
travels about once, whatever the number of tasks. The per-block function
calls the engine directly, on frames built from those values.

Nothing is computed until the caller computes the result; dask is imported
only when dask-backed data arrives.
"""

from __future__ import annotations

import functools
import sys
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from .._engine import twist as tw
from .._engine import velocity as _velocity
from .._engine.chain import chain
from .._engine.time import as_track, seconds
from .._kernels import differences as dk
from .._kernels import quaternion as qk
from .._kernels import rotations as rk
from .coverage import combined
from .unpack import kernel_array, resolve_axis

# samples of not-a-knot spline influence kept on each side: 0.268**32 < 1e-18
SPLINE_HALO = 32
# samples beyond a chunk that a finite difference (np.gradient scheme) reads
GRADIENT_HALO = 2
# samples of squad neighbours (q[i-1] .. q[i+2]) plus one for safety
SQUAD_HALO = 3
# samples of a frame (or a looked-up term) kept beyond those bracketing a
# task's time window, on each side: SQUAD reads samples i-1 .. i+2, so 4
# leaves two samples between any sample the window's interpolation -- or a
# rule about missing samples next to it -- reads and the cut
MARGIN = 4


def is_dask(obj: Any) -> bool:
    """Whether ``obj`` is a dask array or a DataArray backed by one."""
    module = sys.modules.get("dask.array")
    if module is None:
        return False
    if isinstance(obj, module.Array):
        return True
    xarray = sys.modules.get("xarray")
    return (
        xarray is not None
        and isinstance(obj, xarray.DataArray)
        and isinstance(obj.data, module.Array)
    )


# ---------------------------------------------------------------------------
# the engine: one task per time chunk
# ---------------------------------------------------------------------------


def over_time(
    func: Callable,
    arr,
    time_dim: str,
    *,
    halo: int = 0,
    start: int = 0,
    stop: int | None = None,
    fill: Any = 0.0,
    global_seconds: bool = False,
    context: Any = None,
):
    """Apply an eager DataArray function lazily, one time chunk at a time.

    Parameters
    ----------
    func : callable
        ``func(block) -> DataArray`` on a NumPy-backed DataArray; it must
        return the block's samples along ``time_dim`` (same count, same order).
    arr : xarray.DataArray
        Dask-backed input.
    time_dim : str
        The dimension cut into chunks (its own chunks are kept).
    halo : int
        Samples read beyond each chunk edge and dropped from its result.
    start, stop : int
        Only samples ``start:stop`` along ``time_dim`` are processed.
    fill : float or {dim: sequence}
        Values of the stand-in data used to learn the result's layout without
        computing anything (e.g. the identity quaternion along the quaternion
        dimension).
    global_seconds : bool
        Hand each block a datetime64 time coordinate as float seconds from
        the first sample of the whole array, computed as the eager functions
        compute them, so that time differences -- and what is divided by
        them -- are the same to the bit as in one eager call (for functions
        that need no other timestamps, e.g. the velocity estimators).
    context : object with ``window(first, last)``, optional
        What the function needs besides the block, cut to each block's time
        window: ``func(block, context.window(first, last))`` is called with
        the first and last time the block reads. Frames travel this way
        (:class:`rbm_nb.core._frame_snapshot.FrameTree`): each task carries the
        samples of its window, not the frames' whole recordings.

    Returns
    -------
    xarray.DataArray
        Dask-backed, chunked along ``time_dim`` like ``arr``.
    """
    import dask
    import dask.array as dsa
    import xarray as xr

    n = arr.sizes[time_dim]
    stop = n if stop is None else stop
    arr = arr.chunk({d: -1 for d in arr.dims if d != time_dim})
    t_axis = arr.dims.index(time_dim)
    times = arr[time_dim].values
    stand_in = _stand_in(arr, time_dim, start, stop, fill)
    layout = _apply(func, stand_in, _window(context, stand_in[time_dim].values))
    out_axis = layout.dims.index(time_dim)

    source = arr
    if global_seconds and arr[time_dim].dtype.kind == "M":
        source = arr.assign_coords(
            {time_dim: _seconds_from_first(arr[time_dim].values)}
        )
    blocks = []
    run = dask.delayed(_run_block, pure=True)
    for lo, hi in _chunk_bounds(arr.chunks[t_axis], start, stop):
        read_lo, read_hi = max(0, lo - halo), min(n, hi + halo)
        piece = source.isel({time_dim: slice(read_lo, read_hi)})
        task = run(
            func,
            _one_block(piece.data),
            {k: v.variable for k, v in piece.coords.items()},
            piece.dims,
            piece.name,
            piece.attrs,
            time_dim,
            layout.dims,
            lo - read_lo,
            hi - read_lo,
            _window(context, times[read_lo:read_hi]),
        )
        shape = list(layout.shape)
        shape[out_axis] = hi - lo
        blocks.append(dsa.from_delayed(task, tuple(shape), dtype=layout.dtype))
    data = dsa.concatenate(blocks, axis=out_axis)

    kept = arr.isel({time_dim: slice(start, stop)})
    coords = {k: v.variable for k, v in kept.coords.items() if time_dim in v.dims}
    coords.update(
        {k: v.variable for k, v in layout.coords.items() if time_dim not in v.dims}
    )
    return xr.DataArray(data, coords, layout.dims, layout.name, layout.attrs)


def _one_block(data):
    """A dask array as one Delayed block, its graph left as it is.

    Handing the array itself to a delayed call would optimise (fuse and
    rename) its graph once per call: every chunk's task would then carry
    its own copy of what the array depends on -- for a cumulative fill,
    every chunk before it.
    """
    whole = data.rechunk(tuple(-1 for _ in data.shape))
    return whole.to_delayed(optimize_graph=False).ravel()[0]


def _seconds_from_first(times: np.ndarray) -> np.ndarray:
    """datetime64 times as float seconds from the first, as rbm_nb._engine.time does."""
    return seconds(times, len(times), "time")


def _chunk_bounds(
    chunks: Sequence[int], start: int, stop: int
) -> list[tuple[int, int]]:
    bounds, edge = [], 0
    for size in chunks:
        lo, hi = max(edge, start), min(edge + size, stop)
        if lo < hi:
            bounds.append((lo, hi))
        edge += size
    return bounds


def _stand_in(arr, time_dim: str, start: int, stop: int, fill):
    """A small NumPy DataArray shaped like ``arr`` (real coordinates, fill data)."""
    import xarray as xr

    rows = min(stop - start, 64)
    part = arr.isel({time_dim: slice(start, start + rows)})
    if isinstance(fill, dict):
        ((dim, values),) = fill.items()
        data = _filled(part.shape, values, part.dims.index(dim))
    else:
        data = _filled(part.shape, fill, 0)
    coords = {k: v.variable.compute() for k, v in part.coords.items()}
    return xr.DataArray(data, coords, part.dims, part.name, part.attrs)


def _window(context, times: np.ndarray):
    """The context of a block reading ``times`` (None without a context)."""
    if context is None or not len(times):
        return context
    return context.window(times[0], times[-1])


def _apply(func, block, context):
    return func(block) if context is None else func(block, context)


def _run_block(
    func, data, coords, dims, name, attrs, time_dim, out_dims, lo, hi, context=None
):
    import xarray as xr

    block = xr.DataArray(np.asarray(data), coords, dims, name, attrs)
    out = _apply(func, block, context).transpose(*out_dims)
    return np.asarray(out.isel({time_dim: slice(lo, hi)}).data)


# ---------------------------------------------------------------------------
# what the public functions call
# ---------------------------------------------------------------------------


def as_dataarray(arr, time_axis: int | None, timestamps):
    """A plain dask array as a DataArray with a ``time`` coordinate."""
    import xarray as xr

    time_axis = resolve_axis(
        0 if time_axis is None else time_axis, arr.ndim, "time_axis"
    )
    dims = [f"dim_{k}" for k in range(arr.ndim)]
    dims[time_axis] = "time"
    coords = {}
    if timestamps is not None:
        coords["time"] = np.asarray(timestamps)
    return xr.DataArray(arr, coords, dims)


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


def frame_time_range(outof, into):
    """First and last time at which every continuous moving frame of the chain is defined."""
    firsts, lasts = [], []
    for frame, _ in chain(outof, into):
        ts = frame.timestamps
        if ts is not None and not frame.discrete:
            firsts.append(ts[0])
            lasts.append(ts[-1])
    if not firsts:
        return None
    return max(firsts), min(lasts)


def transform(
    block: Callable,
    arr,
    source,
    to_frame,
    dim,
    axis,
    timestamps,
    time_axis,
    return_timestamps: bool,
    snapshot: Callable,
    attr: str,
    quaternions: bool,
):
    """A transform of dask-backed data, one task per time chunk.

    The frames come resolved (``source``, ``to_frame``) and the graph
    carries their values (``snapshot``,
    :meth:`rbm_nb.core._frame_snapshot.FrameTree.of`), each task only the
    samples its chunk's times need: tasks run wherever dask sends them,
    with or without the client's registry, and a frame registered after
    this call does not change the result.

    ``block(block, frames, dim=, time_dim=, attr=, origin=)`` is the door's
    eager call on one block (:func:`rbm_nb._door.inputs.transform_block`).
    """
    series = _TimeSeries.of(arr, dim, axis, timestamps, time_axis)
    per_block = functools.partial(
        block,
        dim=series.comp_dim,
        time_dim=series.time_dim,
        attr=attr,
        origin=_origin(series.arr[series.time_dim].values),
    )
    span = frame_time_range(source, to_frame)
    return series.run(
        per_block,
        snapshot([source, to_frame]),
        [] if span is None else [span],
        quaternions,
        return_timestamps,
    )


class _TimeSeries:
    """A dask-backed argument of a transform as a DataArray along time."""

    def __init__(self, arr, plain: bool, time_dim: str, comp_dim: str):
        self.arr = arr
        self.plain = plain
        self.time_dim = time_dim
        self.comp_dim = comp_dim

    @classmethod
    def of(cls, arr, dim, axis, timestamps, time_axis) -> _TimeSeries:
        plain = not hasattr(arr, "dims")
        if plain:
            if timestamps is None:
                raise ValueError(
                    "a dask array needs timestamps= to be transformed lazily "
                    "(without them the result would follow the frames' own times)"
                )
            arr = as_dataarray(arr, time_axis, timestamps)
            comp_dim = arr.dims[resolve_axis(-1 if axis is None else axis, arr.ndim)]
            return cls(arr, True, "time", comp_dim)
        time_dim = time_dim_of(arr, timestamps, time_axis)
        if time_dim is None or time_dim not in arr.coords:
            raise ValueError(
                f"the dask-backed DataArray needs a coordinate for its time "
                f"dimension {time_dim!r} to be transformed lazily"
            )
        comp_dim = dim if dim is not None else arr.dims[-1 if axis is None else axis]
        return cls(arr, False, time_dim, comp_dim)

    def run(self, block, frames, spans, quaternions: bool, return_timestamps: bool):
        """``block`` over the chunks, cropped to the (first, last) ``spans``."""
        times = self.arr[self.time_dim].values
        start, stop = 0, len(times)
        if spans:
            first = max(s[0] for s in spans)
            last = min(s[1] for s in spans)
            start = int(np.searchsorted(times, first, side="left"))
            stop = int(np.searchsorted(times, last, side="right"))
            if stop <= start:
                raise ValueError(
                    f"the array's times ({times[0]} to {times[-1]}) and the frames' "
                    f"({first} to {last}) do not overlap"
                )
        fill = {self.comp_dim: (1.0, 0.0, 0.0, 0.0) if quaternions else 0.0}
        out = over_time(
            block,
            self.arr,
            self.time_dim,
            start=start,
            stop=stop,
            fill=fill,
            context=frames,
        )
        if self.plain:
            data = out.data
            return (data, times[start:stop]) if return_timestamps else data
        return out


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
        seconds = _seconds_from_first(arr[time_dim].values)
        out = reinterpolate(out, score <= thresh, seconds, time_dim, thresh)
        if cutoff is not None:
            out = lowpass(out, time_dim, cutoff)
    return out.data if plain else out


# ---------------------------------------------------------------------------
# outlier rejection: a rejected sample may be re-interpolated from kept
# samples any distance away, which no halo covers; the previous and next kept
# samples are carried across chunks by cumulative fills instead
# ---------------------------------------------------------------------------


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


def elementwise(eager: Callable, arr, core_dim: str | int, fill: Any = 0.0, **kwargs):
    """A function acting on each sample alone (coordinate systems, one-array
    quaternion functions), lazily per chunk.

    ``core_dim`` (a dimension name, or an axis of a plain dask array) holds
    the components and is put in one chunk; other chunks stay as they are.
    """
    if hasattr(arr, "dims"):
        others = [d for d in arr.dims if d != core_dim]
        if not others:
            raise ValueError(
                f"a dask-backed DataArray with only the dimension {core_dim!r} "
                f"has nothing to process in chunks; call .compute() first"
            )
        chunked = max(others, key=lambda d: len(arr.chunksizes.get(d, (1,))))
        return over_time(
            lambda block: eager(block, **kwargs), arr, chunked, fill={core_dim: fill}
        )
    axis = resolve_axis(core_dim, arr.ndim)
    data = arr.rechunk({axis: -1})
    stand_in = _filled(
        tuple(s if k == axis else 1 for k, s in enumerate(data.shape)), fill, axis
    )
    layout = np.asarray(eager(stand_in, **kwargs))
    if layout.ndim != data.ndim:
        raise ValueError(
            "this function changes the number of dimensions; it cannot be "
            "applied lazily per chunk"
        )
    chunks = tuple(
        (layout.shape[k],) if k == axis else c for k, c in enumerate(data.chunks)
    )
    return data.map_blocks(
        lambda block: np.asarray(eager(block, **kwargs)),
        dtype=layout.dtype,
        chunks=chunks,
    )


def blockwise(
    eager: Callable,
    arrays: Sequence[Any],
    core_dims: Sequence[str],
    out_core_dim: str,
    **kwargs,
):
    """A function of several aligned DataArrays that acts on each sample alone.

    ``eager(*blocks, **kwargs)`` receives NumPy arrays whose last axis is the
    corresponding ``core_dims`` entry and returns one with ``out_core_dim`` last.
    """
    import xarray as xr

    return xr.apply_ufunc(
        lambda *blocks: np.asarray(eager(*blocks, **kwargs)),
        *arrays,
        input_core_dims=[[d] for d in core_dims],
        output_core_dims=[[out_core_dim]],
        dask="parallelized",
        output_dtypes=[np.float64],
        dask_gufunc_kwargs={"allow_rechunk": True},
        keep_attrs=True,
    )


def _filled(shape: tuple[int, ...], fill: Any, axis: int) -> np.ndarray:
    data = np.empty(shape)
    values = np.asarray(fill, dtype=float)
    if values.ndim:
        view = [1] * len(shape)
        view[axis] = values.size
        data[...] = values.reshape(view)
    else:
        data[...] = values
    return data


def qinterp(eager: Callable, da, dim: str, qdim: str, t_out, out_of_range: str):
    """Squad of dask-backed quaternions at new times, one output chunk per task.

    ``eager(da, dim, qdim, t_out, out_of_range=...)`` is the in-memory
    interpolation. Each output chunk reads the input samples around its
    times plus the squad neighbours. No sign correction is needed across
    chunks: the eager version gives each value the sign of the stored sample
    its segment starts from, which a chunk has.
    """
    import dask
    import dask.array as dsa
    import xarray as xr

    if dim not in da.coords:
        raise ValueError(f"dimension {dim!r} has no coordinate to interpolate from")
    t_in = da[dim].values
    t_new = np.asarray(getattr(t_out, "values", t_out))
    if t_new.ndim != 1:
        raise NotImplementedError(
            "lazy qinterp of dask-backed data takes a one-dimensional new "
            f"coordinate, got shape {t_new.shape}"
        )
    if (
        out_of_range == "raise"
        and t_new.size
        and (t_new.min() < t_in[0] or t_new.max() > t_in[-1])
    ):
        raise ValueError(
            f"the new times ({t_new.min()} to {t_new.max()}) leave the sampled "
            f"range of {dim!r} ({t_in[0]} to {t_in[-1]})"
        )
    others = [d for d in da.dims if d not in (dim, qdim)]
    # the layout and coordinates of the result, from one series of identity
    # quaternions (in memory, so nothing of the user's data is computed)
    stand_in = da.isel({d: slice(0, 1) for d in others})
    stand_in = xr.DataArray(
        _filled(stand_in.shape, (1.0, 0.0, 0.0, 0.0), stand_in.dims.index(qdim)),
        {k: v.variable.compute() for k, v in stand_in.coords.items()},
        stand_in.dims,
        da.name,
        da.attrs,
    )
    layout = eager(stand_in, dim, qdim, t_out, out_of_range=out_of_range)

    q = da.chunk({d: -1 for d in da.dims if d != dim})
    size = max(q.chunksizes[dim])
    axis = layout.dims.index(dim)
    run = dask.delayed(_run_qinterp, pure=True)
    blocks = []
    for j0 in range(0, t_new.size, size):
        part = t_new[j0 : j0 + size]
        lo = int(np.searchsorted(t_in, part.min(), side="right")) - 1 - SQUAD_HALO
        hi = int(np.searchsorted(t_in, part.max(), side="left")) + 1 + SQUAD_HALO
        piece = q.isel({dim: slice(max(lo, 0), min(hi, len(t_in)))})
        task = run(
            eager,
            _one_block(piece.data),
            {k: v.variable for k, v in piece.coords.items()},
            piece.dims,
            da.name,
            da.attrs,
            dim,
            qdim,
            part,
            out_of_range,
            layout.dims,
        )
        shape = [da.sizes.get(d, 0) for d in layout.dims]
        shape[axis] = part.size
        shape[layout.dims.index(qdim)] = 4
        blocks.append(dsa.from_delayed(task, tuple(shape), dtype=np.float64))
    data = dsa.concatenate(blocks, axis=axis)
    coords = {
        k: v.variable for k, v in layout.coords.items() if not set(v.dims) & set(others)
    }
    coords.update(
        {
            k: v.variable
            for k, v in da.coords.items()
            if set(v.dims) <= set(others) and v.dims
        }
    )
    return xr.DataArray(data, coords, layout.dims, layout.name, layout.attrs)


def _run_qinterp(
    eager, data, coords, dims, name, attrs, dim, qdim, part, out_of_range, out_dims
):
    import xarray as xr

    block = xr.DataArray(np.asarray(data), coords, dims, name, attrs)
    out = eager(block, dim, qdim, part, out_of_range=out_of_range)
    return np.asarray(out.transpose(*out_dims).data)


# ---------------------------------------------------------------------------
# velocity transforms: the frames' own velocities once, then per chunk
# ---------------------------------------------------------------------------


def velocity_transform(
    arr,
    frame,
    to_frame,
    extras,
    dim,
    axis,
    timestamps,
    time_axis,
    return_timestamps: bool,
    snapshot: Callable,
    block: Callable,
):
    """A change of frame of dask-backed velocities, lazily per time chunk.

    ``extras`` are the looked-up terms, estimated once for the whole array
    (:func:`rbm_nb._engine.twist.velocity_terms`); each task carries the
    frames' samples and the terms' values around its chunk's times (see
    :func:`transform`) and runs ``block(block, context, dim=, time_dim=,
    origin=)``, the door's eager call on one block
    (:func:`rbm_nb._door.inputs.velocity_block`).
    """
    series = _TimeSeries.of(arr, dim, axis, timestamps, time_axis)
    whole = series.arr[series.time_dim].values
    # the whole array's matchings, before the graph is built
    combined(frame, to_frame, as_track(whole), [t for _, t in extras])
    context = VelocityContext(
        snapshot([frame, to_frame]),
        tuple(extras),
        tuple(tw.interpolated_terms(frame, to_frame, as_track(whole), extras)),
    )
    per_block = functools.partial(
        block,
        dim=series.comp_dim,
        time_dim=series.time_dim,
        origin=_origin(whole),
    )
    spans = [(t.values[0], t.values[-1]) for _, t in extras if t is not None]
    span = frame_time_range(frame, to_frame)
    return series.run(
        per_block,
        context,
        spans + ([] if span is None else [span]),
        False,
        return_timestamps,
    )


class VelocityContext:
    """What a block of a velocity transform needs: frames and the looked-up terms."""

    def __init__(self, frames, extras, interpolated):
        self.frames = frames
        self.extras = extras
        self.interpolated = interpolated

    def window(self, first, last) -> VelocityContext:
        extras = []
        for values, track in self.extras:
            if track is None:
                extras.append((values, track))
                continue
            n = len(track)
            lo = int(np.searchsorted(track.values, first, side="right")) - 1 - MARGIN
            hi = int(np.searchsorted(track.values, last, side="left")) + 1 + MARGIN
            lo, hi = max(0, lo), min(n, hi)
            # the same origin: the block interpolates in the eager call's seconds
            extras.append((values[lo:hi], track.slice(lo, hi)))
        return VelocityContext(
            self.frames.window(first, last), tuple(extras), self.interpolated
        )


def time_dim_of(arr, timestamps, time_axis) -> str | None:
    """The time dimension of a DataArray argument (None for a plain array)."""
    if not hasattr(arr, "dims"):
        return None
    if isinstance(timestamps, str):
        return timestamps
    return arr.dims[0 if time_axis is None else time_axis]


def _origin(times) -> int | None:
    """Nanoseconds of the first of datetime64 ``times`` (None for numbers)."""
    first = as_track(np.asarray(times)[:1])
    return first.origin if first.is_datetime else None
