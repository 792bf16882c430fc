"""The coordinate converters' one door call each.

:func:`components` is what each of the four converters
(``cartesian_to_polar``, ...) calls; :func:`coordinate_change` is what
:func:`rbm_nb.transform_coordinates` calls. Both route dask-backed data to a
lazy per-chunk call of the eager function (:func:`rbm_nb._door.dask_blocks.
elementwise`), and otherwise check the argument once and hand back a frozen
value: the float64 data with the coordinate axis moved last, and the axis
(non-negative) to put it back.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping
from typing import Any, NamedTuple

import numpy as np

from . import dask_blocks as _dask
from .shapes import along_axis
from .unpack import dim_axis, is_dataarray, resolve_axis

__all__ = ["Components", "components", "CoordinateChange", "coordinate_change"]


class Components(NamedTuple):
    """Checked coordinates: ``data`` with the coordinate axis last, its ``axis``
    in the argument; or, for dask-backed data, only the ``lazy`` result."""

    data: Any
    axis: int
    lazy: Any = None


def components(
    convert: Callable, arr: Any, axis: Any, length: int, what: str
) -> Components:
    """``arr`` with an axis of ``length`` coordinates (``what``) at ``axis``.

    ``convert(data, axis)`` is the converter's math on checked coordinates:
    dask-backed data is converted chunk by chunk, each chunk checked here
    (:func:`_converted_block`), not by the facade again.
    """
    if _dask.is_dask(arr):
        block = functools.partial(
            _converted_block, convert=convert, length=length, what=what
        )
        lazy = _dask.elementwise(block, getattr(arr, "data", arr), axis, axis=axis)
        return Components(None, 0, lazy)
    data, ax = along_axis(arr, "arr", axis, length, what)
    return Components(data, ax)


def _converted_block(
    block: Any, axis: Any, convert: Callable, length: int, what: str
) -> Any:
    """One chunk of a lazy conversion: checked as an eager call's argument."""
    data, ax = along_axis(block, "arr", axis, length, what)
    return convert(data, ax)


class CoordinateChange(NamedTuple):
    """A checked change of coordinate system (or, for dask, its ``lazy`` result).

    ``data`` holds the coordinates last, ``axis`` is their axis in ``arr``;
    ``outof`` is the system resolved (from ``attrs["coordinate_system"]``
    when not given); ``attrs`` a copy of a DataArray's, else None.
    """

    data: Any
    axis: int
    outof: Any
    attrs: dict | None
    dataarray: bool
    lazy: Any = None


def coordinate_change(
    eager: Callable,
    arr: Any,
    into: Any,
    outof: Any,
    dim: Any,
    axis: Any,
    replace_dim: bool,
    systems: Mapping[tuple[str, str], tuple[int, str]],
) -> CoordinateChange:
    """The one door call of :func:`rbm_nb.transform_coordinates`.

    ``systems`` maps each supported ``(outof, into)`` to the number of
    coordinates and what they are (``(3, "x, y, z")``).
    """
    if _dask.is_dask(arr):
        return CoordinateChange(
            None, 0, outof, None, False,
            _lazy(eager, arr, into, outof, dim, axis, replace_dim),
        )  # fmt: skip
    is_da = is_dataarray(arr)
    ax = _dim_or_axis(arr, dim, axis)
    attrs = dict(arr.attrs) if is_da else None
    if outof is None:
        if attrs is None or "coordinate_system" not in attrs:
            raise ValueError(
                "outof must be given unless arr is a DataArray whose attrs contain "
                "'coordinate_system'"
            )
        outof = attrs["coordinate_system"]
    try:
        length, what = systems[(outof, into)]
    except KeyError:
        known = ", ".join(f"{a} -> {b}" for a, b in systems)
        raise ValueError(
            f"cannot transform coordinates from {outof!r} into {into!r}; "
            f"supported: {known}"
        ) from None
    data, ax = along_axis(arr.values if is_da else arr, "arr", ax, length, what)
    return CoordinateChange(data, ax, outof, attrs, is_da)


def _lazy(eager, arr, into, outof, dim, axis, replace_dim):
    if not is_dataarray(arr):
        return _dask.elementwise(
            eager, arr, -1 if axis is None else axis, into=into, outof=outof, axis=axis
        )
    core = arr.dims[_dim_or_axis(arr, dim, axis)]
    return _dask.elementwise(
        eager, arr, core, into=into, outof=outof, dim=core, replace_dim=replace_dim
    )


def _dim_or_axis(arr: Any, dim: str | None, axis: int | None) -> int:
    """The axis of a DataArray (or array) meant by ``dim`` or ``axis``."""
    ax = dim_axis(arr, dim, axis)
    return resolve_axis(-1 if ax is None else ax, np.ndim(arr), "axis")
