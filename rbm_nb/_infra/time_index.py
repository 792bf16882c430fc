"""DataArrays along timestamps nobody can change: the time index is a view.

xarray's ``DataArray(values, coords={"time": times})`` keeps two copies of
``times`` with pandas 3: the pandas index copies the array it is built from,
and the constructor deep-copies every coordinate variable. For a result along
an hour of 340 Hz samples that is 20 MB the caller never asked for, kept as
long as the result lives (the explorer's plots keep theirs for as long as the
dashboard is open). When the times are frozen (:mod:`rbm_nb._infra.frozen`:
read-only down to memory nobody can write, as the loaders' arrays and the
frames' timestamps are) nothing needs a copy: :func:`dataarray_on` builds the
index over them and the DataArray from a Dataset, which takes coordinates as
they are.
"""

from __future__ import annotations

from collections.abc import Hashable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from .frozen import is_frozen

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["dataarray_on", "time_coordinates"]


def dataarray_on(
    values: np.ndarray,
    times: np.ndarray,
    dims: Sequence[Hashable],
    coords: Mapping[Hashable, Any] | None = None,
    *,
    attrs: dict | None = None,
    name: Hashable | None = None,
) -> xr.DataArray:
    """``values`` as a DataArray whose ``time`` coordinate is ``times``.

    Parameters
    ----------
    values : ndarray
        The data, its first axis along ``times`` (not copied).
    times : ndarray, shape (n,)
        The time coordinate: shared by the result when frozen, else copied
        as xarray always does (the caller may still change its array).
    dims : sequence of str
        The result's dims, ``"time"`` first.
    coords : mapping, optional
        The other dims' coordinates.
    attrs, name : optional
        The result's attributes and name.
    """
    import xarray as xr

    other = dict(coords or {})
    if not is_frozen(times) or not hasattr(xr, "Coordinates"):
        return xr.DataArray(
            values, coords={"time": times, **other}, dims=dims, attrs=attrs, name=name
        )
    shared = time_coordinates(times)
    # a Dataset keeps the coordinates it is given; the DataArray constructor
    # would deep-copy them
    key = "__values__"
    ds = xr.Dataset({key: (tuple(dims), values)}, coords=shared).assign_coords(other)
    out = ds[key]
    out.name, out.attrs = name, dict(attrs or {})
    return out


def time_coordinates(times: Any, **others: Any) -> xr.Coordinates:
    """Coordinates whose ``time`` index holds ``times`` themselves, and ``others``.

    For times nobody will change (frozen, or a result's own): pandas 3 copies
    an array made into an index unless told not to, and the index is
    immutable, so it needs no copy of its own. Hand them to a Dataset (the
    DataArray constructor deep-copies its coordinates).
    """
    import pandas as pd
    import xarray as xr

    index = pd.Index(np.asarray(times), copy=False, name="time")
    coords = xr.Coordinates.from_xindex(xr.indexes.PandasIndex(index, "time"))
    return coords.assign(others)
