"""DataArray out: wrapping results (arguments are unpacked by :mod:`rbm_nb._door.unpack`).

xarray is imported inside the functions that build objects, so that plain
numpy callers never pay for it.
"""

from __future__ import annotations

from collections.abc import Hashable
from typing import TYPE_CHECKING, Any

import numpy as np

# the unpacking half lives in the door; these names stay importable from here
from .._infra.time_index import time_coordinates
from .unpack import Unpacked, is_dataarray, unpack

if TYPE_CHECKING:
    import xarray as xr

__all__ = [
    "Unpacked",
    "is_dataarray",
    "unpack",
    "wrap",
    "check_directions",
    "dataset_variable",
    "dataarray_coordinate",
    "transform_dataset",
    "twist_dataset",
    "velocity_dataarray",
]


def check_directions(directions: Any) -> None:
    """A gaze.directions result: dims (time, cartesian_axis), 3 components,
    the frame they are given in named by ``attrs["representation_frame"]``."""
    if not is_dataarray(directions):
        raise ValueError(
            f"directions must be a DataArray from gaze.directions, got "
            f"{type(directions).__name__}"
        )
    if set(directions.dims) != {"time", "cartesian_axis"}:
        raise ValueError(
            f"directions must have dims ('time', 'cartesian_axis'), got {directions.dims}"
        )
    if directions.sizes["cartesian_axis"] != 3:
        raise ValueError("directions must have 3 components along 'cartesian_axis'")
    if "representation_frame" not in directions.attrs:
        raise ValueError(
            "directions has no 'representation_frame' attribute naming the frame "
            "they are given in"
        )


def dataset_variable(ds: xr.Dataset, name: Hashable, argument: str) -> Any:
    """``ds[name].data``, with an error naming the argument if it is missing."""
    if name not in ds.variables:
        raise ValueError(
            f"{argument}={name!r} is not a variable or coordinate of the dataset "
            f"(it has {', '.join(repr(str(v)) for v in ds.variables)})"
        )
    return ds[name].data


def dataarray_coordinate(da: xr.DataArray, name: Hashable) -> Any:
    if name not in da.coords:
        raise ValueError(
            f"timestamps={name!r} is not a coordinate of the DataArray "
            f"(it has {', '.join(repr(str(c)) for c in da.coords)})"
        )
    return da[name].data


def wrap(
    unpacked: Unpacked, data: np.ndarray, ts_out: Any, attrs: dict | None
) -> xr.DataArray:
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


def transform_dataset(
    translation: np.ndarray,
    rotation: np.ndarray,
    frame_name: str | None,
    timestamps: Any,
    pose: bool = False,
) -> xr.Dataset:
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
            time_coordinates(
                timestamps,
                cartesian_axis=["x", "y", "z"],
                quaternion_axis=["w", "x", "y", "z"],
            ),
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


def twist_dataset(
    linear: np.ndarray,
    angular: np.ndarray,
    moving: str | None,
    reference: str | None,
    represent_in: str | None,
    timestamps: Any,
) -> xr.Dataset:
    """A Dataset with angular_velocity and linear_velocity over time."""
    import xarray as xr

    ds = xr.Dataset(
        {
            "angular_velocity": (["time", "cartesian_axis"], angular),
            "linear_velocity": (["time", "cartesian_axis"], linear),
        },
        time_coordinates(timestamps, cartesian_axis=["x", "y", "z"]),
    )
    for kind in ("angular", "linear"):
        ds[f"{kind}_velocity"].attrs.update(
            _velocity_attrs(kind, moving, reference, represent_in)
        )
    return ds


def velocity_dataarray(
    velocity: np.ndarray,
    kind: str,
    moving: str | None,
    reference: str | None,
    represent_in: str | None,
    timestamps: Any,
) -> xr.DataArray:
    """A (time, cartesian_axis) DataArray of linear or angular velocity."""
    import xarray as xr

    name = f"{kind}_velocity"
    attrs = _velocity_attrs(kind, moving, reference, represent_in)
    # (through a Dataset: the DataArray constructor deep-copies its
    # coordinates, the time index included)
    ds = xr.Dataset(
        {name: (("time", "cartesian_axis"), velocity, attrs)},
        time_coordinates(timestamps, cartesian_axis=["x", "y", "z"]),
    )
    return ds[name]
