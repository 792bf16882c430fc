"""Cutting a lazy computation along time: one dask task per time chunk.

:func:`over_time` runs an eager DataArray function on each chunk of a
dask-backed array, read with a *halo* of neighbouring samples so that its
result equals the eager result on the whole array; the halos and margins the
callers need are declared here. Each task carries one Delayed block of the
input (its graph left as it is) and only the part of a context (the frames'
values) that its time window needs. The rest of the lazy path
(:mod:`rbm_nb._door.dask_blocks`) is built on this.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from .._engine.time import seconds
from .unpack import resolve_axis

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
        source = arr.assign_coords({time_dim: seconds_from_first(arr[time_dim].values)})
    blocks = []
    run = dask.delayed(_run_block, pure=True)
    for lo, hi in _chunk_bounds(arr.chunks[t_axis], start, stop):
        read_lo, read_hi = max(0, lo - halo), min(n, hi + halo)
        piece = source.isel({time_dim: slice(read_lo, read_hi)})
        task = run(
            func,
            one_block(piece.data),
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


def one_block(data):
    """A dask array as one Delayed block, its graph left as it is.

    Handing the array itself to a delayed call would optimise (fuse and
    rename) its graph once per call: every chunk's task would then carry
    its own copy of what the array depends on -- for a cumulative fill,
    every chunk before it.
    """
    whole = data.rechunk(tuple(-1 for _ in data.shape))
    return whole.to_delayed(optimize_graph=False).ravel()[0]


def seconds_from_first(times: np.ndarray) -> np.ndarray:
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
        data = filled(part.shape, values, part.dims.index(dim))
    else:
        data = filled(part.shape, fill, 0)
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


def filled(shape: tuple[int, ...], fill: Any, axis: int) -> np.ndarray:
    data = np.empty(shape)
    values = np.asarray(fill, dtype=float)
    if values.ndim:
        view = [1] * len(shape)
        view[axis] = values.size
        data[...] = values.reshape(view)
    else:
        data[...] = values
    return data


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
