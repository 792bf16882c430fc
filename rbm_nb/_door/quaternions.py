"""The quaternion functions' door: one call each for qinv, qmul, qinterp, rotate_vectors.

Each entry routes dask-backed data to its lazy path (``lazy``: the caller's
lazy builder is handed back as a marker, the door does not call the facade),
recognises the one-pass fast case (plain C-contiguous float64 rows: the
kernels count infinities and zeros while they compute, and a count makes
the facade ask :func:`check_no_inf` or name the zero row), and otherwise
checks the arguments once: quaternion axes (``split``), times
(``check_times``), norms, broadcasting. What comes back is a frozen value
the facade hands to the kernels as it is.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np

from .._engine import time as _time
from .._infra.config import UNIT_QUATERNION_TOLERANCE
from .._kernels import squad_walk as _sw
from ..errors import UnsupportedError
from . import dask_blocks as _dask
from .shapes import along_axis
from .unpack import float_array, is_dataarray, kernel_array, resolve_axis
from .validation import check_finite, check_missing_rows, check_unit_norms

__all__ = [
    "split",
    "broadcast",
    "is_plain_rows",
    "check_times",
    "fast_times",
    "Inverse",
    "inverse",
    "Product",
    "product",
    "Interpolation",
    "interpolation",
    "Rotation",
    "rotation",
    "Mean",
    "mean",
    "EulerAngles",
    "euler_angles",
]


def is_quaternion_dtype(arr: np.ndarray) -> bool:
    return arr.dtype.name == "quaternion"


def split(q: Any, qaxis: int, name: str) -> tuple[np.ndarray, bool]:
    """Quaternions as a float array with the components last, and whether
    the input was of quaternion dtype (whose ``qaxis`` is then ignored)."""
    arr = np.asarray(q)
    if is_quaternion_dtype(arr):
        import quaternion

        return quaternion.as_float_array(arr), True
    moved, _ = along_axis(arr, name, qaxis, 4, "w, x, y, z", "qaxis")
    return moved, False


def broadcast(a: tuple[int, ...], b: tuple[int, ...], what: str) -> tuple[int, ...]:
    try:
        return tuple(np.broadcast_shapes(a, b))
    except ValueError:
        raise ValueError(
            f"{what}: shapes {a} and {b} cannot be broadcast together"
        ) from None


def is_plain_rows(q: Any, qaxis: Any) -> bool:
    """(n, 4) C-contiguous float64 with the default quaternion axis."""
    return (
        type(q) is np.ndarray
        and type(qaxis) is int
        and qaxis in (-1, 1)
        and q.dtype == np.float64
        and q.ndim == 2
        and q.shape[1] == 4
        and q.flags.c_contiguous
    )


def check_times(t_in: np.ndarray, t_out: np.ndarray, n: int) -> None:
    """Squad's times: ``t_in`` one per sample, finite, increasing; ``t_out`` inside."""
    if t_in.ndim != 1 or t_in.shape[0] != n:
        raise ValueError(
            f"t_in must be one-dimensional with one time per sample ({n}), got shape {t_in.shape}"
        )
    if n == 0:
        raise ValueError("q has no samples to interpolate along axis")
    if not np.all(np.isfinite(t_in)):
        raise ValueError("t_in must be finite")
    if np.any(np.diff(t_in) <= 0):
        raise ValueError("t_in must be strictly increasing")
    if t_out.ndim > 1:
        raise ValueError(
            f"t_out must be a scalar or one-dimensional, got shape {t_out.shape}"
        )
    if not np.all(np.isfinite(t_out)):
        raise ValueError("t_out must be finite")
    if t_out.size and (t_out.min() < t_in[0] or t_out.max() > t_in[-1]):
        raise ValueError(
            f"t_out must lie within the range of t_in [{t_in[0]}, {t_in[-1]}], got "
            f"[{t_out.min()}, {t_out.max()}] (squad cannot extrapolate)"
        )


def fast_times(t_in: Any, t_out: Any) -> tuple[np.ndarray, np.ndarray] | None:
    """Both time arrays as seconds on ``t_in[0]`` when they are plain 1-D
    float64 or datetime64[ns] arrays (one pass each), else None."""
    if type(t_in) is not np.ndarray or type(t_out) is not np.ndarray:
        return None
    if t_in.ndim != 1 or t_out.ndim != 1 or t_in.dtype != t_out.dtype:
        return None
    if t_in.dtype == np.float64 or (
        t_in.dtype == np.dtype("datetime64[ns]") and t_in.size
    ):
        # a NaT becomes NaN, which the one-pass check sends to the general
        # path (that names it)
        return _time.seconds_pair(t_in, t_out)
    return None


# ---------------------------------------------------------------------------
# qinv
# ---------------------------------------------------------------------------


class Inverse(NamedTuple):
    """``rows`` (n, 4) to invert; ``plain``: they are the argument itself (the
    kernel counts its faults); else ``qf`` (components last) and how to join."""

    rows: Any
    plain: bool
    qf: Any = None
    was_quaternion: bool = False
    template: Any = None
    lazy: Any = None


def inverse(q: Any, qaxis: Any, invert: Callable | None = None) -> Inverse:
    """The one door call of :func:`rbm_nb.qinv`.

    For dask-backed ``q``, ``lazy`` is the lazy result: each chunk comes
    through this door again (from here, not from the facade) and is
    inverted by ``invert(checked, chunk, qaxis)``, the facade's eager step
    on a checked value.
    """
    if _dask.is_dask(q):
        assert invert is not None  # (the facade hands its eager step)
        core = q.dims[qaxis] if is_dataarray(q) else qaxis
        block = functools.partial(_inverse_block, qaxis=qaxis, invert=invert)
        return Inverse(
            None,
            False,
            lazy=_dask.elementwise(block, q, core, fill=(1.0, 0.0, 0.0, 0.0)),
        )
    if is_plain_rows(q, qaxis):
        return Inverse(q, True)
    template = q if is_dataarray(q) else None
    qf, was_quaternion = split(q, qaxis, "q")
    return Inverse(kernel_array(qf.reshape(-1, 4)), False, qf, was_quaternion, template)


def _inverse_block(block: Any, qaxis: Any, invert: Callable) -> Any:
    """One chunk of a lazy qinv: checked here, inverted by the facade's step."""
    return invert(inverse(block, qaxis), block, qaxis)


# ---------------------------------------------------------------------------
# qmul
# ---------------------------------------------------------------------------


class Product(NamedTuple):
    """Checked factors of a Hamilton product.

    ``plain``: two plain row arrays (``parts``) for the one-pass kernel;
    otherwise ``parts`` are the factors with their components last and
    ``shapes[i]`` the broadcast shape after multiplying by ``parts[i]``.
    ``dataarrays``: the DataArray factors, whose layout the result may take.
    """

    parts: tuple
    plain: bool
    shapes: tuple = ()
    was_quaternion: bool = False
    dataarrays: tuple = ()
    lazy: bool = False


def product(q: tuple, qaxis: Any, general: bool = False) -> Product:
    """The one door call of :func:`rbm_nb.qmul`; ``general``: skip the fast case
    (after the kernel counted an infinity, the general checks name it)."""
    if len(q) < 2:
        raise ValueError(f"qmul needs at least 2 quaternion arrays, got {len(q)}")
    if any(_dask.is_dask(x) for x in q):
        return Product((), False, lazy=True)
    if (
        not general
        and len(q) == 2
        and is_plain_rows(q[0], qaxis)
        and is_plain_rows(q[1], qaxis)
        and (q[0].shape[0] == q[1].shape[0] or 1 in (q[0].shape[0], q[1].shape[0]))
    ):
        return Product((kernel_array(q[0]), kernel_array(q[1])), True)
    kinds = {is_quaternion_dtype(np.asarray(x)) for x in q}
    if len(kinds) > 1:
        raise ValueError(
            "q: either all or none of the arrays must be of quaternion dtype"
        )
    parts = tuple(split(x, qaxis, f"q[{i}]")[0] for i, x in enumerate(q))
    shape = parts[0].shape[:-1]
    shapes = [shape]
    for i, nxt in enumerate(parts[1:], start=1):
        shape = broadcast(shape, nxt.shape[:-1], f"q[{i}]")
        shapes.append(shape)
    dataarrays = tuple(x for x in q if is_dataarray(x))
    return Product(parts, False, tuple(shapes), kinds.pop(), dataarrays)


# ---------------------------------------------------------------------------
# qinterp
# ---------------------------------------------------------------------------


class SampledDataArray(NamedTuple):
    """A DataArray's squad along ``dim``, checked: ``lazy`` (dask-backed,
    interpolated chunk by chunk, ``da`` carrying ``t_in`` as its coordinate),
    or ``data`` (components last, float64) sampled along axis ``ax`` at
    ``t_in`` (seconds), to be interpolated to ``t_out`` (flat seconds; the
    given values ``t_out_values``), only where ``inside`` (None: everywhere)."""

    lazy: bool
    da: Any
    dim: Any
    qdim: Any
    data: Any = None
    ax: int = 0
    t_in: Any = None
    t_out: Any = None
    inside: Any = None
    t_out_values: Any = None


def dataarray_interpolation(
    da: Any, dim: Any, qdim: Any, t_out: Any, t_in: Any = None,
    out_of_range: str = "raise",
) -> SampledDataArray:  # fmt: skip
    """The one door call of a DataArray's squad (``qinterp`` of a DataArray,
    the ``.rbm.qinterp`` accessor): dims, times and values checked.

    ``t_in`` defaults to the coordinate of ``dim``; ``out_of_range="nan"``
    leaves times outside the sampled range out (NaN there) instead of
    refusing them.
    """
    if dim not in da.dims:
        raise ValueError(
            f"{dim!r} is not a dimension of this DataArray {tuple(da.dims)}"
        )
    if _dask.is_dask(da) and qdim in da.dims and dim != qdim:
        if t_in is not None:
            da = da.assign_coords({dim: np.asarray(getattr(t_in, "values", t_in))})
        return SampledDataArray(True, da, dim, qdim)
    if qdim not in da.dims:
        raise ValueError(
            f"qdim {qdim!r} is not a dimension of this DataArray {tuple(da.dims)}"
        )
    if dim == qdim:
        raise ValueError(f"cannot interpolate along the quaternion dimension {qdim!r}")
    if da.sizes[qdim] != 4:
        raise ValueError(
            f"dimension {qdim!r} must have length 4 (w, x, y, z), got {da.sizes[qdim]}"
        )
    if t_in is None:
        if dim not in da.coords:
            raise ValueError(f"dimension {dim!r} has no coordinate to interpolate from")
        t_in = da.coords[dim].values
    t_out_values = np.asarray(getattr(t_out, "values", t_out))
    if t_out_values.ndim > 1:
        raise UnsupportedError(
            f"the new coordinate for {dim!r} must be a scalar or one-dimensional, "
            f"got shape {t_out_values.shape}"
        )
    times = fast_times(np.asarray(getattr(t_in, "values", t_in)), t_out_values)
    t_in_f, t_out_f = (
        times if times is not None else _time.seconds_pair(t_in, t_out_values)
    )
    flat_out = t_out_f.reshape(-1)
    inside = None  # None: every time is inside the sampled range
    if out_of_range == "nan" and t_in_f.ndim == 1 and t_in_f.size:
        inside = (flat_out >= t_in_f[0]) & (flat_out <= t_in_f[-1])
        if inside.all():
            inside = None
    check_times(t_in_f, flat_out if inside is None else flat_out[inside], da.sizes[dim])
    data = np.moveaxis(float_array(da.values, "q"), da.dims.index(qdim), -1)
    ax = [d for d in da.dims if d != qdim].index(dim)
    return SampledDataArray(
        False, da, dim, qdim, data, ax, t_in_f, flat_out, inside, t_out_values
    )


class Interpolation(NamedTuple):
    """A checked squad interpolation, by ``kind``:

    * "dataarray" (also a plain dask array, wrapped as one in ``q``): ``dim``
      and ``qdim`` name the sample and component dimensions;
    * "rows": ``q`` plain (n, 4) rows, times checked in one pass (``t_in``,
      ``t_out`` in seconds);
    * "general": ``q`` with components last, sampled along ``axis`` (counted
      without the quaternion axis), the result's quaternion axis ``qpos``.
    """

    kind: str
    q: Any
    t_in: Any = None
    t_out: Any = None
    axis: int = 0
    qpos: int = -1
    given_axis: int = 0
    was_quaternion: bool = False
    dim: Any = None
    qdim: Any = None
    dask: bool = False
    sampled: Any = None  # "dataarray": its SampledDataArray


def interpolation(
    q: Any, t_in: Any, t_out: Any, axis: Any, qaxis: Any
) -> Interpolation:
    """The one door call of :func:`rbm_nb.qinterp`."""
    if _dask.is_dask(q) and not is_dataarray(q):
        import xarray as xr

        ax = resolve_axis(axis, q.ndim, "axis")
        qa = resolve_axis(qaxis, q.ndim, "qaxis")
        dims = [f"dim_{k}" for k in range(q.ndim)]
        dims[ax] = "time"
        wrapped = xr.DataArray(q, {"time": np.asarray(t_in)}, dims)
        sampled = dataarray_interpolation(wrapped, "time", dims[qa], t_out)
        return Interpolation("dataarray", wrapped, dask=True, sampled=sampled)
    if is_dataarray(q):
        dim = q.dims[resolve_axis(axis, q.ndim, "axis")]
        qdim = q.dims[resolve_axis(qaxis, q.ndim, "qaxis")]
        sampled = dataarray_interpolation(q, dim, qdim, t_out, t_in)
        return Interpolation("dataarray", q, sampled=sampled)
    fast = _fast_rows(q, t_in, t_out, axis, qaxis)
    if fast is not None:
        return fast
    arr = np.asarray(q)
    qf, was_quaternion = split(arr, qaxis, "q")
    ax = resolve_axis(axis, arr.ndim, "axis")
    qpos = -1
    if not was_quaternion:
        qpos = resolve_axis(qaxis, arr.ndim, "qaxis")
        # axis counts the axes of q without qaxis when both name the same
        # axis (qinterp(q.T, ..., qaxis=0) with the default axis=0), as in
        # rigid-body-motion; otherwise it counts all axes of q
        ax_without_q = ax - 1 if ax > qpos else ax
    else:
        ax_without_q = ax
    if ax_without_q >= qf.ndim - 1:
        raise ValueError(
            f"axis={axis} and qaxis={qaxis} refer to the same axis of q, and q of "
            f"shape {arr.shape} has no axis {axis} besides its quaternion axis"
        )
    t_in_f, t_out_f = _time.seconds_pair(t_in, t_out)
    check_times(t_in_f, t_out_f.reshape(-1), qf.shape[ax_without_q])
    check_unit_norms(qf, "q")
    return Interpolation(
        "general", qf, t_in_f, t_out_f, ax_without_q, qpos, ax, was_quaternion
    )


def _fast_rows(q, t_in, t_out, axis, qaxis) -> Interpolation | None:
    """A C-contiguous float64 (n, 4) array with 1-D times along axis 0,
    checked in one pass per array; None if it is not that case or the input
    is bad (the general path then names what is wrong)."""
    if not (type(axis) is int and axis in (0, -2) and is_plain_rows(q, qaxis)):
        return None
    times = fast_times(t_in, t_out)
    if times is None or times[0].shape[0] != q.shape[0]:
        return None
    q = kernel_array(q)
    tol = UNIT_QUATERNION_TOLERANCE
    if _sw.squad_input_fault(q, times[0], times[1], tol) != 0:
        return None
    return Interpolation("rows", q, times[0], times[1])


# ---------------------------------------------------------------------------
# rotate_vectors
# ---------------------------------------------------------------------------


class Rotation(NamedTuple):
    """Checked quaternions and vectors to rotate, by ``kind``:

    * "rows": plain (n|1, 4) and (n|1, 3) rows for the one-pass kernel;
    * "broadcast": one quaternion per vector over the broadcast ``shape``;
    * "each": one quaternion (or none with a leading shape) for every vector;
    * "outer": every vector by every quaternion.

    ``q`` and ``v`` have their components last (``vax``: the vectors' axis);
    ``template`` is a DataArray ``v`` whose layout the result takes.
    """

    kind: str
    q: Any
    v: Any
    vax: int = -1
    shape: tuple = ()
    template: Any = None
    lazy: bool = False


def rotation(q: Any, v: Any, axis: Any, qaxis: Any, one_to_one: Any) -> Rotation:
    """The one door call of :func:`rbm_nb.rotate_vectors`."""
    if _dask.is_dask(q) or _dask.is_dask(v):
        return Rotation("lazy", q, v, lazy=True)
    qa = np.asarray(q)
    v_da = is_dataarray(v)
    va = float_array(v.values if v_da else v, "v")
    template = v if v_da else None
    # Common case first: (n, 4) x (n, 3) contiguous float64, no copies at all
    # and one pass (infinities and zero quaternions are counted by the kernel).
    if (
        one_to_one
        and qa.ndim == 2
        and va.ndim == 2
        and qa.dtype == np.float64
        and qa.shape[1] == 4
        and va.shape[1] == 3
        and (axis == -1 or axis == 1)
        and (qaxis == -1 or qaxis == 1)
        and qa.flags.c_contiguous
        and (qa.shape[0] == va.shape[0] or qa.shape[0] == 1 or va.shape[0] == 1)
    ):
        return Rotation("rows", kernel_array(qa), va, template=template)
    vm, vax = along_axis(va, "v", axis, 3, "x, y, z")
    qf, _ = split(qa, qaxis, "q")
    q_shape = qf.shape[:-1]
    v_shape = vm.shape[:-1]
    if one_to_one and q_shape:
        if len(q_shape) != len(v_shape):
            raise ValueError(
                f"one_to_one rotation needs one quaternion per vector: q has shape "
                f"{q_shape} (without qaxis) and v has shape {v_shape} (without axis); "
                f"use one_to_one=False to rotate every vector by every quaternion"
            )
        shape = broadcast(q_shape, v_shape, "q and v")
        return Rotation("broadcast", qf, vm, vax, shape, template)
    kind = "each" if not q_shape else "outer"
    return Rotation(kind, qf, vm, vax, v_shape, template)


# ---------------------------------------------------------------------------
# qmean
# ---------------------------------------------------------------------------


class Mean(NamedTuple):
    """Checked quaternions to average: ``groups`` (g, n, 4), one group per
    kept index (``keep_shape``); the result's quaternion axis ``qpos``; a
    DataArray ``template`` and its quaternion dimension ``qdim``."""

    groups: np.ndarray
    keep_shape: tuple
    reduce_axes: tuple
    ndim: int
    was_quaternion: bool
    qpos: int
    template: Any
    qdim: Any


def mean(q: Any, axis: Any, qaxis: Any) -> Mean:
    """The one door call of :func:`rbm_nb.qmean`."""
    template = q if is_dataarray(q) else None
    qf, was_quaternion = split(q, qaxis, "q")
    nd = qf.ndim - 1
    reduce_axes = _reduce_axes(axis, nd)
    keep_axes = tuple(a for a in range(nd) if a not in reduce_axes)
    moved = np.transpose(qf, keep_axes + reduce_axes + (nd,))
    keep_shape = moved.shape[: len(keep_axes)]
    check_unit_norms(qf, "q")
    groups = moved.reshape(int(np.prod(keep_shape)), -1, 4)
    if groups.shape[1] == 0:
        raise ValueError(f"q has no quaternions to average along axis={axis!r}")
    qpos = -1
    if not was_quaternion:
        qin = resolve_axis(qaxis, qf.ndim, "qaxis")
        qpos = qin - sum(1 for a in reduce_axes if a < qin)
    qdim = None
    if template is not None and not was_quaternion:
        qdim = template.dims[resolve_axis(qaxis, template.ndim, "qaxis")]
    return Mean(
        groups, keep_shape, reduce_axes, qf.ndim, was_quaternion, qpos, template, qdim
    )


def _reduce_axes(axis: Any, ndim: int) -> tuple[int, ...]:
    if axis is None:
        return tuple(range(ndim))
    axes = (axis,) if np.ndim(axis) == 0 else tuple(axis)
    out = tuple(sorted({resolve_axis(a, ndim, "axis") for a in axes}))
    if len(out) != len(axes):
        raise ValueError(f"axis contains repeated axes: {axis!r}")
    return out


# ---------------------------------------------------------------------------
# from_euler_angles
# ---------------------------------------------------------------------------

_ANGLE_NAMES = {"r": "roll", "p": "pitch", "y": "yaw"}


class EulerAngles(NamedTuple):
    """Checked roll/pitch/yaw angles (``angles``: key "r", "p" or "y" -> array),
    their broadcast ``shape`` and the result's quaternion axis ``axis``."""

    angles: dict
    shape: tuple
    axis: int


def euler_angles(
    rpy: Any, roll: Any, pitch: Any, yaw: Any, axis: Any, return_quaternion: bool
) -> EulerAngles:
    """The one door call of :func:`rbm_nb.from_euler_angles` (a quaternion
    dtype result has no axis to place)."""
    angles: dict[str, np.ndarray] = {}
    if rpy is not None:
        if roll is not None or pitch is not None or yaw is not None:
            raise ValueError("give either rpy or roll/pitch/yaw, not both")
        arr = float_array(rpy, "rpy")
        if arr.ndim == 0:
            raise ValueError(
                "rpy must have an axis of length 3 (roll, pitch, yaw), got a scalar"
            )
        ax = resolve_axis(axis, arr.ndim, "axis")
        if arr.shape[ax] != 3:
            raise ValueError(
                f"rpy must have length 3 (roll, pitch, yaw) along axis={axis}, got shape {arr.shape}"
            )
        arr = np.moveaxis(arr, ax, -1)
        # a row of NaN only is a missing sample (an untracked frame) and
        # stays NaN; a partly NaN row or an infinity is a mistake
        check_missing_rows(arr, "rpy")
        angles = {"r": arr[..., 0], "p": arr[..., 1], "y": arr[..., 2]}
    else:
        for key, value in (("r", roll), ("p", pitch), ("y", yaw)):
            if value is not None:
                name = _ANGLE_NAMES[key]
                angles[key] = float_array(value, name)
                check_finite(angles[key], name, row_axis=False)
        if not angles:
            raise ValueError("give at least one of rpy, roll, pitch or yaw")
    shape: tuple[int, ...] = ()
    for key, value in angles.items():
        shape = broadcast(shape, value.shape, _ANGLE_NAMES[key])
    if return_quaternion:
        return EulerAngles(angles, shape, -1)
    return EulerAngles(angles, shape, resolve_axis(axis, len(shape) + 1, "axis"))
