"""The dataset layout of every motion recording rbm_nb reads or makes.

Dims ``time`` (datetime64[ns]), ``cartesian_axis`` (x, y, z) and
``quaternion_axis`` (w, x, y, z), as in the reference package's example data.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

if TYPE_CHECKING:
    import xarray as xr

STANDARD_ATTRS = {
    "position": {"long_name": "Position", "units": "m"},
    "orientation": {"long_name": "Orientation"},
    "linear_velocity": {"long_name": "Linear velocity", "units": "m/s"},
    "angular_velocity": {"long_name": "Angular velocity", "units": "rad/s"},
}


def motion_dataset(
    time: npt.ArrayLike,
    variables: dict,
    attrs: dict | None = None,
    variable_attrs: dict | None = None,
) -> xr.Dataset:
    """An :class:`xarray.Dataset` of time series in the shared layout.

    Parameters
    ----------
    time : array_like, shape (n,)
        datetime64 timestamps.
    variables : dict
        name -> array of shape (n,), (n, 3) (cartesian) or (n, 4) (w, x, y, z).
    attrs : dict, optional
        Dataset attributes.
    variable_attrs : dict, optional
        name -> attributes, replacing the standard ones for that name.
    """
    import xarray as xr

    variable_attrs = variable_attrs or {}
    data_vars = {}
    for name, values in variables.items():
        dims = {
            1: ("time",),
            3: ("time", "cartesian_axis"),
            4: ("time", "quaternion_axis"),
        }[1 if values.ndim == 1 else values.shape[1]]
        data_vars[name] = (
            dims,
            values,
            variable_attrs.get(name, STANDARD_ATTRS.get(name, {})),
        )
    # fixed-width strings and long names, as in the example recordings' files
    coords = {
        "time": ("time", np.asarray(time), {"long_name": "Time"}),
        "cartesian_axis": (
            "cartesian_axis",
            np.array(["x", "y", "z"], dtype="<U1"),
            {"long_name": "Axis"},
        ),
        "quaternion_axis": (
            "quaternion_axis",
            np.array(["w", "x", "y", "z"], dtype="<U1"),
            {"long_name": "Axis"},
        ),
    }
    return xr.Dataset(data_vars, coords, attrs)
