"""Whether an array can be trusted not to change: kept as a view instead of copied.

A frame must not change after it is made, so it used to copy every array it
was given. A copy is needed only when someone can still write the memory.
An array is *frozen* when nothing holding it can: the array is read-only
and so is every array it views (numpy's ``base`` chain), down to memory that
is itself read-only (``bytes``, a read-only ``mmap`` or buffer) or owned by
a read-only array. A read-only view of a writeable array is not frozen: its
owner can still write through the base.

A read-only array that owns its memory is its owner's promise: numpy lets
the owner set ``writeable`` back to True (and nobody else). rbm_nb keeps
that promise's terms -- what you hand over read-only, you do not write
again -- as numpy's own views do.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["is_frozen", "kernel_alias", "kernel_readable", "freeze_dataset"]


def is_frozen(arr: Any) -> bool:
    """True if ``arr`` is an ndarray whose memory nobody can write any more."""
    node = arr
    while isinstance(node, np.ndarray):
        if node.flags.writeable:
            return False
        node = node.base
    if node is None:
        return True  # a read-only array owning its memory
    if isinstance(node, bytes):
        return True
    try:
        return memoryview(node).readonly
    except TypeError:
        return False  # memory of an object that does not say


class _Alias:
    """Presents a frozen array's memory as writeable, keeping the array alive."""

    __slots__ = ("__array_interface__", "_owner")

    def __init__(self, arr: np.ndarray) -> None:
        interface = dict(arr.__array_interface__)
        interface["data"] = (interface["data"][0], False)
        self.__array_interface__ = interface
        self._owner = arr


def kernel_alias(arr: np.ndarray) -> np.ndarray:
    """A writeable-flagged view of a frozen C-contiguous array's memory.

    The kernels are compiled for writeable arrays only (one signature each,
    :mod:`rbm_nb._kernels._jit`); a read-only array would make numba refuse
    the call. A frame hands them this alias of the caller's frozen array:
    the same memory, read and never written (a frame's samples are read by
    every kernel and written by none, as before when they were copies).
    ``arr`` itself when it is already writeable.
    """
    if arr.flags.writeable:
        return arr
    return np.asarray(_Alias(arr))


def kernel_readable(arr: Any) -> np.ndarray:
    """``arr`` for a kernel declared on writeable arrays that only reads it.

    A C-contiguous float64 array goes through as :func:`kernel_alias` gives
    it (a read-only one, a frame's or a DataArray's, is not copied: the
    kernel never writes it); anything else as a writeable C-contiguous
    float64 copy.
    """
    arr = np.asarray(arr)
    if arr.dtype == np.float64 and arr.flags.c_contiguous:
        return kernel_alias(arr)
    return np.array(arr, dtype=np.float64, order="C")


def _freeze(arr: np.ndarray) -> None:
    """Make ``arr`` and every array it views read-only (down to the owner)."""
    node: Any = arr
    while isinstance(node, np.ndarray):
        node.setflags(write=False)
        node = node.base


def freeze_dataset(ds: Any) -> Any:
    """Make every array of a freshly loaded xarray Dataset frozen; returns ``ds``.

    For loaders that made ``ds`` and hold its only reference: nobody else
    can write its memory, so once it is read-only frames keep its arrays
    instead of copies (:func:`is_frozen`). The time coordinate's memory is
    the pandas index's own array, which pandas never writes (an index is
    immutable); it is marked read-only too. A user who wants to change the
    data works on ``ds.copy(deep=True)``, which is writeable.
    """
    for var in ds.variables.values():
        _freeze(np.asarray(var.values))
    return ds
