"""Lazy functions of each sample alone, and squad at new times, per chunk.

:func:`elementwise` and :func:`blockwise` run a function that reads one
sample at a time (coordinate systems, one-array quaternion functions) on
each chunk, the components in one chunk. :func:`qinterp` interpolates
quaternions at new times, one output chunk per task, each reading the input
samples around its times plus the squad neighbours.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from .dask_chunks import SQUAD_HALO, filled, one_block, over_time
from .unpack import resolve_axis


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
    stand_in = filled(
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
        filled(stand_in.shape, (1.0, 0.0, 0.0, 0.0), stand_in.dims.index(qdim)),
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
            one_block(piece.data),
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
