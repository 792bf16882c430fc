"""Coordinate systems: cartesian, polar (2-D) and spherical (3-D, ISO 80000-2).

The four converters work on plain arrays along one axis; ``transform_coordinates``
is the entry point that also understands DataArrays: it reads the current system
from ``attrs["coordinate_system"]`` and swaps the coordinate dimension for one that
names the new axes (``spherical_axis: [r, theta, phi]``, ...).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._door.coordinates import components, coordinate_change
from .._door.unpack import ArrayInput

# system name -> (dimension name, axis labels) per dimensionality
_SYSTEM_AXES: dict[tuple[str, int], tuple[str, list[str]]] = {
    ("cartesian", 2): ("cartesian_axis", ["x", "y"]),
    ("polar", 2): ("polar_axis", ["r", "phi"]),
    ("cartesian", 3): ("cartesian_axis", ["x", "y", "z"]),
    ("spherical", 3): ("spherical_axis", ["r", "theta", "phi"]),
    ("quaternion", 4): ("quaternion_axis", ["w", "x", "y", "z"]),
}


def cartesian_to_polar(arr: ArrayInput, axis: int = -1) -> np.ndarray:
    """Convert 2-D cartesian coordinates (x, y) into polar coordinates (r, phi).

    Parameters
    ----------
    arr : array_like, shape (..., 2, ...)
        Cartesian coordinates along ``axis``.
    axis : int, default -1
        Axis of ``arr`` holding x and y.

    Returns
    -------
    ndarray, shape (..., 2, ...)
        Radius ``r >= 0`` and azimuth ``phi`` in (-pi, pi] along ``axis``.

    Raises
    ------
    ValueError
        If ``arr`` does not have length 2 along ``axis``.

    Examples
    --------
    >>> cartesian_to_polar([0.0, 2.0])
    array([2.        , 1.57079633])
    """
    args = components(_polar, arr, axis, 2, "x, y")
    if args.lazy is not None:
        return args.lazy
    return _polar(args.data, args.axis)


def _polar(arr: np.ndarray, axis: int) -> np.ndarray:
    """The math of :func:`cartesian_to_polar` on checked coordinates (last axis)."""
    x, y = arr[..., 0], arr[..., 1]
    return np.stack((np.hypot(x, y), np.arctan2(y, x)), axis=axis)


def polar_to_cartesian(arr: ArrayInput, axis: int = -1) -> np.ndarray:
    """Convert polar coordinates (r, phi) into 2-D cartesian coordinates (x, y).

    Parameters
    ----------
    arr : array_like, shape (..., 2, ...)
        Radius and azimuth (radians) along ``axis``.
    axis : int, default -1
        Axis of ``arr`` holding r and phi.

    Returns
    -------
    ndarray, shape (..., 2, ...)
        x and y along ``axis``.

    Raises
    ------
    ValueError
        If ``arr`` does not have length 2 along ``axis``.

    Examples
    --------
    >>> polar_to_cartesian([2.0, 0.0])
    array([2., 0.])
    """
    args = components(_cartesian_2d, arr, axis, 2, "r, phi")
    if args.lazy is not None:
        return args.lazy
    return _cartesian_2d(args.data, args.axis)


def _cartesian_2d(arr: np.ndarray, axis: int) -> np.ndarray:
    """The math of :func:`polar_to_cartesian` on checked coordinates (last axis)."""
    r, phi = arr[..., 0], arr[..., 1]
    return np.stack((r * np.cos(phi), r * np.sin(phi)), axis=axis)


def cartesian_to_spherical(arr: ArrayInput, axis: int = -1) -> np.ndarray:
    """Convert 3-D cartesian coordinates into spherical coordinates (ISO 80000-2).

    Parameters
    ----------
    arr : array_like, shape (..., 3, ...)
        x, y and z along ``axis``.
    axis : int, default -1
        Axis of ``arr`` holding x, y and z.

    Returns
    -------
    ndarray, shape (..., 3, ...)
        Radius ``r``, polar angle ``theta`` in [0, pi] measured from +z and
        azimuth ``phi`` in (-pi, pi] along ``axis``. The origin maps to
        ``(0, 0, 0)``.

    Raises
    ------
    ValueError
        If ``arr`` does not have length 3 along ``axis``.

    Examples
    --------
    >>> cartesian_to_spherical([0.0, 0.0, 2.0])
    array([2., 0., 0.])
    """
    args = components(_spherical, arr, axis, 3, "x, y, z")
    if args.lazy is not None:
        return args.lazy
    return _spherical(args.data, args.axis)


def _spherical(arr: np.ndarray, axis: int) -> np.ndarray:
    """The math of :func:`cartesian_to_spherical` on checked coordinates (last axis)."""
    x, y, z = arr[..., 0], arr[..., 1], arr[..., 2]
    rho = np.hypot(x, y)
    # arctan2 rather than arccos(z / r): defined at the origin and accurate near
    # the poles, where arccos loses half of the digits.
    return np.stack((np.hypot(rho, z), np.arctan2(rho, z), np.arctan2(y, x)), axis=axis)


def spherical_to_cartesian(arr: ArrayInput, axis: int = -1) -> np.ndarray:
    """Convert spherical coordinates (ISO 80000-2) into 3-D cartesian coordinates.

    Parameters
    ----------
    arr : array_like, shape (..., 3, ...)
        Radius, polar angle from +z and azimuth (radians) along ``axis``.
    axis : int, default -1
        Axis of ``arr`` holding r, theta and phi.

    Returns
    -------
    ndarray, shape (..., 3, ...)
        x, y and z along ``axis``.

    Raises
    ------
    ValueError
        If ``arr`` does not have length 3 along ``axis``.

    Examples
    --------
    >>> spherical_to_cartesian([1.0, np.pi / 2, 0.0]).round(12)
    array([1., 0., 0.])
    """
    args = components(_cartesian_3d, arr, axis, 3, "r, theta, phi")
    if args.lazy is not None:
        return args.lazy
    return _cartesian_3d(args.data, args.axis)


def _cartesian_3d(arr: np.ndarray, axis: int) -> np.ndarray:
    """The math of :func:`spherical_to_cartesian` on checked coordinates (last axis)."""
    r, theta, phi = arr[..., 0], arr[..., 1], arr[..., 2]
    rho = r * np.sin(theta)
    return np.stack(
        (rho * np.cos(phi), rho * np.sin(phi), r * np.cos(theta)), axis=axis
    )


# (outof, into) -> the math, the number of coordinates and what they are
_CONVERTERS = {
    ("cartesian", "polar"): (_polar, 2, "x, y"),
    ("polar", "cartesian"): (_cartesian_2d, 2, "r, phi"),
    ("cartesian", "spherical"): (_spherical, 3, "x, y, z"),
    ("spherical", "cartesian"): (_cartesian_3d, 3, "r, theta, phi"),
}
_SYSTEMS = {pair: (n, what) for pair, (_, n, what) in _CONVERTERS.items()}


def _replace_dim(
    coords: dict, dims: tuple, axis: int, system: str, length: int
) -> tuple[dict, tuple]:
    """Swap the dimension at ``axis`` for the one naming ``system``'s axes.

    Coordinates that depend on the old dimension are dropped, since their values
    describe axes that no longer exist.
    """
    try:
        new_dim, labels = _SYSTEM_AXES[(system, length)]
    except KeyError:
        raise ValueError(
            f"no {length}-axis dimension is known for {system!r}"
        ) from None
    old_dim = dims[axis]
    dims = tuple(new_dim if d == old_dim else d for d in dims)
    coords = {k: c for k, c in coords.items() if old_dim not in c.dims}
    coords[new_dim] = labels
    return coords, dims


def transform_coordinates(
    arr: ArrayInput,
    into: str,
    outof: str | None = None,
    dim: str | None = None,
    axis: int | None = None,
    replace_dim: bool = True,
) -> Any:
    """Convert an array between coordinate systems.

    Supported pairs: cartesian <-> polar (2-D) and cartesian <-> spherical (3-D).

    Parameters
    ----------
    arr : array_like or xarray.DataArray, shape (..., 2 or 3, ...)
        The coordinates to convert.
    into : str
        Target system: ``"cartesian"``, ``"polar"`` or ``"spherical"``.
    outof : str, optional
        Current system. May be omitted for a DataArray whose ``attrs`` contain
        ``"coordinate_system"``.
    dim : str, optional
        For a DataArray, the dimension holding the coordinates.
    axis : int, optional
        The axis holding the coordinates; defaults to the last one.
    replace_dim : bool, default True
        For a DataArray, replace the coordinate dimension by one naming the
        new axes (e.g. ``spherical_axis: [r, theta, phi]``), dropping every
        coordinate that depended on the old dimension. If False, dimensions
        and coordinates are kept as they are.

    Returns
    -------
    ndarray or xarray.DataArray
        The converted coordinates, a DataArray if ``arr`` was one. Its
        ``attrs["coordinate_system"]`` is updated to ``into`` when present.

    Raises
    ------
    ValueError
        For an unknown pair of systems, a missing ``outof``, or an axis of the
        wrong length.

    Examples
    --------
    >>> transform_coordinates([1.0, 1.0], "polar", outof="cartesian")
    array([1.41421356, 0.78539816])
    """
    args = coordinate_change(
        transform_coordinates, arr, into, outof, dim, axis, replace_dim, _SYSTEMS
    )
    if args.lazy is not None:
        return args.lazy
    ax, attrs = args.axis, args.attrs
    out = _CONVERTERS[(args.outof, into)][0](args.data, ax)
    if not args.dataarray or attrs is None:
        return out

    import xarray as xr

    if "coordinate_system" in attrs:
        attrs["coordinate_system"] = into
    coords, dims = dict(arr.coords), tuple(arr.dims)
    if replace_dim:
        coords, dims = _replace_dim(coords, dims, ax, into, out.shape[ax])
    return xr.DataArray(out, coords, dims, arr.name, attrs)
