"""The arrays kernels take: writeable, C-contiguous float64 (or read-only views).

Below the engine and the door, both of which hand arrays to kernels:
:func:`kernel_array` converts (copying only when needed), :func:`read_only`
views an array for the kernels declared on read-only input, and
:func:`moveaxis` puts an axis where a kernel wants it without numpy's
argument handling when nothing moves. The door re-exports them with its
checks (:mod:`rbm_nb._door.unpack`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["is_scalar", "kernel_array", "kernel_ready", "moveaxis", "read_only"]


def kernel_ready(arr: Any) -> bool:
    """Whether ``arr`` is a writeable C-contiguous ndarray, the layout every
    kernel signature takes (the dtype is the caller's to check)."""
    return type(arr) is np.ndarray and arr.flags.c_contiguous and arr.flags.writeable


def read_only(arr: Any) -> np.ndarray | None:
    """A read-only view of a C-contiguous ndarray, or None if ``arr`` is not one.

    For the kernels declared on read-only arrays (``_jit.RF1``, ``RI1``): a
    writeable array is viewed read-only rather than handed over as it is,
    which would make numba compile a second, writeable variant.
    """
    if type(arr) is not np.ndarray or not arr.flags.c_contiguous:
        return None
    if not arr.flags.writeable:
        return arr
    view = arr.view()
    view.flags.writeable = False
    return view


def kernel_array(arr: Any) -> np.ndarray:
    """``arr`` as a writeable C-contiguous float64 array (a copy only if needed)."""
    if kernel_ready(arr) and arr.dtype == np.float64:
        return arr
    return np.array(arr, dtype=np.float64, order="C")


def moveaxis(arr: np.ndarray, source, destination) -> np.ndarray:
    """``np.moveaxis``, or ``arr`` itself where no axis moves.

    The usual argument, (n, 3) with time first and coordinates last, moves
    nothing; numpy's argument handling alone costs about 5 µs a call, a
    tenth of a one-point transform.
    """
    n = arr.ndim
    if isinstance(source, tuple):
        for s, d in zip(source, destination, strict=True):
            if s % n != d % n:
                return np.moveaxis(arr, source, destination)
        return arr
    return (
        arr if source % n == destination % n else np.moveaxis(arr, source, destination)
    )


def is_scalar(value: Any) -> bool:
    """Whether ``value`` is one real number (not a bool, string or array)."""
    return isinstance(value, int | float | np.integer | np.floating) and not isinstance(
        value, bool | np.bool_
    )
