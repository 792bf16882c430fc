"""The ``DataArray.rbm`` accessor: quaternion operations on labelled arrays.

This module is imported as soon as xarray is (see ``rbm_nb.__init__``), so at
module level it imports xarray only; the numerics are imported on first use.
"""

from __future__ import annotations

import xarray as xr

from ..errors import UnsupportedError


@xr.register_dataarray_accessor("rbm")
class DataArrayAccessor:
    """Quaternion helpers for a DataArray, reached as ``da.rbm``."""

    def __init__(self, obj: xr.DataArray):
        self._obj = obj

    def qinterp(self, coords=None, qdim: str = "quaternion_axis", **coords_kwargs):
        """Interpolate quaternions along one dimension with squad.

        Parameters
        ----------
        coords : dict, optional
            ``{dim: new_coordinate}`` for exactly one dimension; the new
            coordinate may be a scalar, array-like or DataArray (numbers or
            datetime64, like the existing coordinate of ``dim``).
        qdim : str, default "quaternion_axis"
            Dimension holding w, x, y, z.
        **coords_kwargs
            The keyword form of ``coords``; give one or the other.

        Returns
        -------
        xarray.DataArray
            The quaternions at the new coordinate, same name and attrs. Other
            coordinates along ``dim`` are interpolated linearly (numbers) or
            take the nearest value (anything else). As with
            ``DataArray.interp``, new coordinates outside the sampled range
            give NaN.

        Raises
        ------
        rbm_nb.errors.UnsupportedError
            (a NotImplementedError and a ValueError) if more than one
            dimension is given or the new coordinate is not one-dimensional.
        ValueError
            If no dimension is given, a dimension is missing, or ``qdim``
            does not have length 4.

        Examples
        --------
        >>> import numpy as np, xarray as xr
        >>> da = xr.DataArray(
        ...     [[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]],
        ...     {"time": [0.0, 1.0], "quaternion_axis": list("wxyz")},
        ...     ("time", "quaternion_axis"),
        ... )
        >>> da.rbm.qinterp(time=[0.5]).values.round(6)
        array([[0.707107, 0.      , 0.      , 0.707107]])
        """
        # lazy (import time): registered at xarray's import; numba (~0.5 s) on use
        from .quaternions import _qinterp_dataarray

        if coords is not None and coords_kwargs:
            raise ValueError(
                "give the new coordinates either as coords or as keywords, not both"
            )
        coords = dict(coords if coords is not None else coords_kwargs)
        if len(coords) != 1:
            # several dimensions at once is unsupported (as in the reference);
            # none at all is a wrong call
            error = UnsupportedError if coords else ValueError
            raise error(
                f"coords: qinterp interpolates along exactly one dimension, got "
                f"{list(coords)}"
            )
        ((dim, new),) = coords.items()
        return _qinterp_dataarray(self._obj, dim, qdim, new, out_of_range="nan")

    def qinv(self, qdim: str = "quaternion_axis"):
        """Invert the quaternions along ``qdim``.

        Parameters
        ----------
        qdim : str, default "quaternion_axis"
            Dimension holding w, x, y, z.

        Returns
        -------
        xarray.DataArray
            Same coordinates, name and attrs, inverted quaternions.

        Raises
        ------
        ValueError
            If ``qdim`` is missing or not of length 4, or for a zero quaternion.

        Examples
        --------
        >>> import xarray as xr
        >>> da = xr.DataArray([0.0, 0.0, 0.0, 1.0], dims="quaternion_axis")
        >>> da.rbm.qinv().values
        array([ 0., -0., -0., -1.])
        """
        # lazy (import time): as above, numba loads on first use
        from .quaternions import qinv

        if qdim not in self._obj.dims:
            raise ValueError(
                f"qdim {qdim!r} is not a dimension of this DataArray {self._obj.dims}"
            )
        return qinv(self._obj, qaxis=self._obj.dims.index(qdim))
