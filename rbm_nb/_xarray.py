"""DataArray in, DataArray out: unpacking arguments and wrapping results.

xarray is imported inside the functions that build objects, so that plain
numpy callers never pay for it.
"""

from __future__ import annotations

import sys

import numpy as np


def is_dataarray(obj) -> bool:
    xr = sys.modules.get("xarray")
    return xr is not None and isinstance(obj, xr.DataArray)


def dataset_variable(ds, name, argument: str):
    """``ds[name].data``, with an error naming the argument if it is missing."""
    if name not in ds.variables:
        raise ValueError(
            f"{argument}={name!r} is not a variable or coordinate of the dataset "
            f"(it has {', '.join(repr(str(v)) for v in ds.variables)})"
        )
    return ds[name].data


def dataarray_coordinate(da, name):
    if name not in da.coords:
        raise ValueError(
            f"timestamps={name!r} is not a coordinate of the DataArray "
            f"(it has {', '.join(repr(str(c)) for c in da.coords)})"
        )
    return da[name].data


class Unpacked:
    """An array argument split into data and what is needed to wrap it again."""

    __slots__ = ("data", "axis", "time_axis", "time_dim", "timestamps", "source")

    def __init__(self, data, axis, time_axis, time_dim, timestamps, source):
        self.data = data
        self.axis = axis
        self.time_axis = time_axis
        self.time_dim = time_dim
        self.timestamps = timestamps
        self.source = source  # the DataArray, or None for plain arrays

    @property
    def attrs(self):
        return None if self.source is None else self.source.attrs


def unpack(arr, dim=None, axis=None, time_axis=None, timestamps=None) -> Unpacked:
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
        if dim is not None:
            raise ValueError("dim can only be given for DataArray input; use axis")
        data = np.asarray(arr)
        if data.dtype.name == "quaternion":
            # numpy-quaternion dtype: four float64 per element, as a last axis
            data = (
                np.ascontiguousarray(data).view(np.float64).reshape(data.shape + (4,))
            )
        ndim = data.ndim
        axis = -1 if axis is None else axis
        time_axis = 0 if time_axis is None else time_axis
        if timestamps is not None and ndim > 0 and axis % ndim == time_axis % ndim:
            raise ValueError(
                f"axis={axis} and time_axis={time_axis} refer to the same axis of the array"
            )
        return Unpacked(data, axis, time_axis, None, timestamps, None)

    if dim is not None and axis is not None:
        raise ValueError("give either dim or axis, not both")
    if dim is not None:
        axis = _dim_index(arr, dim, "dim")
    elif axis is None:
        axis = -1
    time_dim = None
    if isinstance(timestamps, str):
        time_axis = _dim_index(arr, timestamps, "timestamps")
        time_dim = timestamps
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


def _dim_index(arr, dim, argument) -> int:
    try:
        return arr.dims.index(dim)
    except ValueError:
        raise ValueError(
            f"{argument}={dim!r} is not a dimension of the DataArray (dims: {arr.dims})"
        ) from None


def wrap(unpacked: Unpacked, data, ts_out, attrs):
    """A DataArray like the input, holding ``data`` at timestamps ``ts_out``.

    If the transformation changed the timestamps, coordinates along the time
    dimension are interpolated (numeric) or taken from the nearest sample.
    Without a time dimension in the input but timestamps in the output, a
    leading ``time`` dimension is added.
    """
    import xarray as xr

    source = unpacked.source
    time_dim = unpacked.time_dim
    if time_dim is None:
        coords = dict(source.coords)
        dims = source.dims
        if ts_out is not None:
            coords["time"] = ts_out
            dims = ("time",) + dims
        return xr.DataArray(data, coords, dims, source.name, attrs)
    old = source.coords[time_dim]
    if len(old) == len(ts_out) and np.array_equal(old.values, ts_out):
        out = source.copy(data=data)
        out.attrs = attrs
        return out
    coords = {}
    for name, coord in source.coords.items():
        if name != time_dim and time_dim in coord.dims:
            if np.issubdtype(coord.dtype, np.number):
                coord = coord.interp({time_dim: ts_out})
            else:
                coord = coord.sel({time_dim: ts_out}, method="nearest")
            coord = coord.drop_vars(time_dim)
        coords[name] = coord
    coords[time_dim] = ts_out
    return xr.DataArray(data, coords, source.dims, source.name, attrs)


def transform_dataset(translation, rotation, frame_name, timestamps, pose=False):
    """A Dataset with translation/rotation (or position/orientation)."""
    import xarray as xr

    linear, angular = (
        ("position", "orientation") if pose else ("translation", "rotation")
    )
    if timestamps is not None:
        ds = xr.Dataset(
            {
                linear: (["time", "cartesian_axis"], translation),
                angular: (["time", "quaternion_axis"], rotation),
            },
            {
                "time": timestamps,
                "cartesian_axis": ["x", "y", "z"],
                "quaternion_axis": ["w", "x", "y", "z"],
            },
        )
    else:
        ds = xr.Dataset(
            {
                linear: ("cartesian_axis", translation),
                angular: ("quaternion_axis", rotation),
            },
            {
                "cartesian_axis": ["x", "y", "z"],
                "quaternion_axis": ["w", "x", "y", "z"],
            },
        )
    common = {"representation_frame": frame_name, "reference_frame": frame_name}
    ds[linear].attrs.update(
        common, motion_type=linear, long_name=linear.capitalize(), units="m"
    )
    ds[angular].attrs.update(
        common, motion_type=angular, long_name=angular.capitalize()
    )
    return ds


def _velocity_attrs(kind, moving, reference, represent_in):
    return {
        "representation_frame": represent_in,
        "reference_frame": reference,
        "moving_frame": moving,
        "motion_type": f"{kind}_velocity",
        "long_name": f"{kind.capitalize()} velocity",
        "units": "rad/s" if kind == "angular" else "m/s",
    }


def twist_dataset(linear, angular, moving, reference, represent_in, timestamps):
    """A Dataset with angular_velocity and linear_velocity over time."""
    import xarray as xr

    ds = xr.Dataset(
        {
            "angular_velocity": (["time", "cartesian_axis"], angular),
            "linear_velocity": (["time", "cartesian_axis"], linear),
        },
        {"time": timestamps, "cartesian_axis": ["x", "y", "z"]},
    )
    for kind in ("angular", "linear"):
        ds[f"{kind}_velocity"].attrs.update(
            _velocity_attrs(kind, moving, reference, represent_in)
        )
    return ds


def velocity_dataarray(velocity, kind, moving, reference, represent_in, timestamps):
    """A (time, cartesian_axis) DataArray of linear or angular velocity."""
    import xarray as xr

    return xr.DataArray(
        velocity,
        coords={"time": timestamps, "cartesian_axis": ["x", "y", "z"]},
        dims=("time", "cartesian_axis"),
        name=f"{kind}_velocity",
        attrs=_velocity_attrs(kind, moving, reference, represent_in),
    )
