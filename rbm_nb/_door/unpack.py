"""The door: every array argument enters the core through here.

One place decides what an argument is and turns it into what the kernels
take, so that each kernel compiles one signature
(:mod:`rbm_nb._kernels._jit`):

* :func:`is_dataarray`: an ``xarray.DataArray`` (checked without importing
  xarray: if it is not loaded, nothing can be a DataArray);
* :func:`float_array`: numbers (or numpy-quaternion dtype, which gains a
  trailing axis of length 4) as **writeable, C-contiguous float64**, copying
  only when the input is not that already (read-only views, other dtypes,
  strided views);
* :func:`kernel_array`: the same for arrays the core built itself;
* :func:`read_only`: a C-contiguous array as the read-only view the few
  kernels that only read it take (no copy, writeable or not);
* :func:`resolve_axis`: an axis argument checked and made non-negative
  (the one axis rule of the package);
* :func:`dim_axis`: the axis a ``dim`` argument names (the one rule of
  ``dim`` and ``axis``);
* :func:`moveaxis`: ``np.moveaxis`` without its cost where nothing moves;
* :func:`unpack`: the spatial and time axes of an array or DataArray
  argument, and its timestamps (from a coordinate for DataArrays).
"""

from __future__ import annotations

import operator
import sys
from typing import Any, TypeAlias

import numpy as np

from .._kernels._arrays import kernel_array, kernel_ready, moveaxis, read_only

# An array argument of the public API: anything numpy turns into numbers
# (lists, arrays, numpy-quaternion arrays) or an xarray.DataArray. Spelled
# Any because the functions look at it (DataArray or not) before converting.
ArrayInput: TypeAlias = Any

__all__ = [
    "ArrayInput",
    "is_dataarray",
    "float_array",
    "kernel_array",
    "kernel_ready",
    "read_only",
    "resolve_axis",
    "dim_axis",
    "moveaxis",
    "Unpacked",
    "unpack",
]


def is_dataarray(obj: Any) -> bool:
    """Whether ``obj`` is an ``xarray.DataArray`` (xarray is never imported here)."""
    xr = sys.modules.get("xarray")
    return xr is not None and isinstance(obj, xr.DataArray)


def float_array(value: Any, name: str) -> np.ndarray:
    """A numeric argument as a writeable C-contiguous float64 array.

    DataArrays give their data; numpy-quaternion arrays gain a trailing
    axis of length 4 (w, x, y, z); booleans and integers are converted.

    Raises
    ------
    ValueError
        If the values are not numeric (the message names ``name``).
    """
    if is_dataarray(value):
        value = value.data
    arr = np.asarray(value)
    if arr.dtype.kind not in "fiub" and arr.dtype.name == "quaternion":
        # numpy-quaternion stores four contiguous float64 per element
        flat = np.array(arr, order="C").view(np.float64)
        return flat.reshape(arr.shape + (4,))
    if arr.dtype.kind not in "iufb":
        raise ValueError(f"{name} must be numeric, got dtype {arr.dtype}")
    return kernel_array(arr)


def resolve_axis(axis: Any, ndim: int, name: str = "axis") -> int:
    """Turn a possibly negative axis into a valid non-negative one."""
    try:
        axis = operator.index(axis)
    except TypeError:
        raise ValueError(f"{name} must be an integer, got {axis!r}") from None
    if not -ndim <= axis < ndim:
        raise ValueError(
            f"{name}={axis} is out of range for an array with {ndim} dimension(s)"
        )
    return int(axis % ndim)


def dim_axis(arr: Any, dim: str | None, axis: Any, name: str = "arr") -> Any:
    """The axis ``dim`` names in a DataArray, else ``axis`` as given (maybe None).

    The one rule of ``dim`` and ``axis`` arguments: ``dim`` only for a
    DataArray, not both, and a name the DataArray has.
    """
    if dim is None:
        return axis
    if not is_dataarray(arr):
        raise ValueError(f"dim can only be given when {name} is a DataArray; use axis")
    if axis is not None:
        raise ValueError("give either dim or axis, not both")
    return _dim_index(arr, dim, "dim")


class Unpacked:
    """An array argument split into data and what is needed to wrap it again."""

    __slots__ = ("data", "axis", "time_axis", "time_dim", "timestamps", "source")

    def __init__(
        self,
        data: Any,
        axis: int,
        time_axis: int | None,
        time_dim: str | None,
        timestamps: Any,
        source: Any,
    ) -> None:
        self.data = data
        self.axis = axis
        self.time_axis = time_axis
        self.time_dim = time_dim
        self.timestamps = timestamps
        self.source = source  # the DataArray, or None for plain arrays

    @property
    def attrs(self) -> Any:
        return None if self.source is None else self.source.attrs


def unpack(
    arr: Any,
    dim: str | None = None,
    axis: int | None = None,
    time_axis: int | None = None,
    timestamps: Any = None,
) -> Unpacked:
    """Resolve the spatial and time axes of an array or DataArray argument.

    For a DataArray, ``dim`` names the spatial dimension (default: the last),
    and the timestamps come from the coordinate of the time dimension
    (``timestamps`` may name it; default: the first dimension, if the array
    has more than one; ``False``: none).

    Raises
    ------
    ValueError
        For ``dim`` without a DataArray, both ``dim`` and ``axis``, unknown
        dimension names, or spatial and time axis being the same.
    """
    if not is_dataarray(arr):
        dim_axis(arr, dim, axis)  # raises for a dim
        data = np.asarray(arr)
        if data.dtype.kind not in "fiub" and data.dtype.name == "quaternion":
            data = float_array(data, "arr")
        ndim = data.ndim
        axis = -1 if axis is None else axis
        time_axis = 0 if time_axis is None else time_axis
        if timestamps is not None and ndim > 0 and axis % ndim == time_axis % ndim:
            raise ValueError(
                f"axis={axis} and time_axis={time_axis} refer to the same axis of the array"
            )
        return Unpacked(data, axis, time_axis, None, timestamps, None)

    axis = dim_axis(arr, dim, axis)
    if axis is None:
        axis = -1
    time_dim = None
    if isinstance(timestamps, str):
        time_axis = _dim_index(arr, timestamps, "timestamps")
        time_dim = timestamps
        if timestamps not in arr.coords:
            # xarray would hand out 0, 1, 2, ...: positions are not times
            raise ValueError(
                f"timestamps={timestamps!r}: the time dimension of the DataArray has "
                f"no coordinate; assign one (da.assign_coords({timestamps}=...))"
            )
        timestamps = arr[timestamps].data
    elif timestamps is None:
        if arr.ndim > 1:
            time_axis = 0 if time_axis is None else time_axis
            time_dim = arr.dims[time_axis]
            timestamps = arr.coords[time_dim].data if time_dim in arr.coords else None
            if timestamps is None:
                time_dim = None
    elif timestamps is False:
        timestamps = None
    else:
        raise ValueError(
            "for DataArray input, timestamps must be the name of a dimension, "
            "None (the first dimension) or False (no timestamps)"
        )
    if time_dim is not None and axis % arr.ndim == time_axis % arr.ndim:
        raise ValueError(
            f"the spatial dimension {arr.dims[axis]!r} cannot also be the time dimension"
        )
    return Unpacked(arr.data, axis, time_axis, time_dim, timestamps, arr)


def _dim_index(arr: Any, dim: str, argument: str) -> int:
    try:
        return int(arr.dims.index(dim))
    except ValueError:
        raise ValueError(
            f"{argument}={dim!r} is not a dimension of the DataArray (dims: {arr.dims})"
        ) from None
