"""Quaternion utilities: inverse, product, mean, interpolation, rotation, Euler angles.

Every function accepts float arrays with the quaternion components ``w, x, y,
z`` along ``qaxis`` (any position), arrays of numpy-quaternion's ``quaternion``
dtype (returned in that dtype, as the reference package does) and DataArrays
(returned as DataArrays with the same coordinates wherever the output keeps the
input's shape). Inputs are validated here; the arithmetic runs in the numba
kernels of :mod:`rbm_nb._kernels.quaternion` and :mod:`rbm_nb._kernels.rotations`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._door import dask_blocks as _dask
from .._door import quaternions as _door
from .._door.unpack import ArrayInput, float_array, kernel_array, resolve_axis
from .._door.unpack import is_dataarray as _is_dataarray
from .._door.validation import (
    check_no_inf,
)
from .._infra import parallel as _parallel
from .._kernels import quaternion as _qk
from .._kernels import rotations as _rk
from .._kernels import squad_walk as _sw
from ..errors import UnsupportedError

__all__ = ["from_euler_angles", "qinterp", "qinv", "qmean", "qmul", "rotate_vectors"]


# ---------------------------------------------------------------------------
# result layout shared by the public functions
# ---------------------------------------------------------------------------


def _join(out: np.ndarray, was_quaternion: bool, qpos: int) -> np.ndarray:
    """Inverse of :func:`rbm_nb._door.quaternions.split` for a result with the components last:
    they move to position ``qpos`` of the result (negative counts from the end)."""
    if was_quaternion:
        import quaternion

        return quaternion.as_quat_array(np.ascontiguousarray(out))
    if out.ndim == 1:
        return out
    pos = qpos + out.ndim if qpos < 0 else qpos
    return np.moveaxis(out, -1, min(max(pos, 0), out.ndim - 1))


def _rows(arr: np.ndarray, shape: tuple[int, ...], width: int) -> np.ndarray:
    """``arr`` (shape + (width,) after broadcasting) as contiguous kernel rows:
    (prod(shape), width), or (1, width) if it holds a single row (the kernels
    reuse such a row without it being copied n times)."""
    if arr.shape[:-1] != shape:
        if arr[..., 0].size == 1:
            return kernel_array(arr.reshape(1, width))
        arr = np.broadcast_to(arr, shape + (width,))
    return kernel_array(arr.reshape(-1, width))


def _like(template: Any, data: np.ndarray) -> Any:
    """``data`` wrapped like the DataArray ``template`` when shapes agree."""
    if template is not None and data.shape == template.shape:
        return template.copy(data=data)
    return data


def _raise_zero(name: str, idx: int, what: str) -> None:
    raise ValueError(
        f"{name} contains a zero quaternion (row {idx} when flattened): {what}"
    )


# ---------------------------------------------------------------------------
# algebra
# ---------------------------------------------------------------------------


def qinv(q: ArrayInput, qaxis: int = -1) -> Any:
    """Inverse of quaternions, ``conj(q) / |q|**2``.

    Parameters
    ----------
    q : array_like, shape (..., 4, ...)
        Quaternions along ``qaxis``, or an array of quaternion dtype, or a
        DataArray.
    qaxis : int, default -1
        Axis of ``q`` holding w, x, y, z (ignored for quaternion dtype).

    Returns
    -------
    ndarray or DataArray
        Same shape and type as ``q``.

    Raises
    ------
    ValueError
        If ``q`` has no length-4 ``qaxis`` or contains a zero quaternion.

    Examples
    --------
    >>> qinv([0.0, 0.0, 0.0, 2.0])
    array([ 0. , -0. , -0. , -0.5])
    """
    args = _door.inverse(q, qaxis, _inverted)
    if args.lazy is not None:
        return args.lazy
    return _inverted(args, q, qaxis)


def _inverted(args, q, qaxis) -> Any:
    """qinv of a checked value (:class:`_door.quaternions.Inverse`) of ``q``."""
    if args.plain:
        # (n, 4) float64: one pass, no copies (infinities and zeros counted)
        return _qinv_rows(args.rows, q)
    out = _qinv_rows(args.rows, args.qf)
    return _like(
        args.template, _join(out.reshape(args.qf.shape), args.was_quaternion, qaxis)
    )


def _qinv_rows(rows: np.ndarray, given: Any) -> np.ndarray:
    """Inverses of kernel rows (n, 4), on both cores when long; rejects
    infinities and zero quaternions (named in ``given``, as passed)."""
    rows = kernel_array(rows)
    out = np.empty(rows.shape)  # numpy's allocation: huge pages when large
    zeros, infs = _parallel.launch(
        _rk.qinv_into, _rk.qinv_into_parallel, rows.shape[0], rows, out
    )
    if infs:
        check_no_inf(np.asarray(given), "q")
    if zeros:
        _raise_zero("q", _rk.first_zero_row(rows), "it has no inverse")
    return out


def _lazy_qmul(q, qaxis: int):
    """qmul of dask-backed quaternions, chunk by chunk."""
    if all(_is_dataarray(x) for x in q):
        core = [x.dims[qaxis] for x in q]
        out = _dask.blockwise(qmul, q, core, core[0], qaxis=-1)
        first = q[0]
        if set(out.dims) == set(first.dims):
            out = out.transpose(*first.dims)
        return out
    if any(_is_dataarray(x) for x in q):
        raise ValueError(
            "q: with dask-backed data pass qmul all DataArrays or all arrays, not a mix"
        )
    import dask.array as dsa

    parts = [dsa.asarray(x) for x in q]
    parts = [p.rechunk({resolve_axis(qaxis, p.ndim, "qaxis"): -1}) for p in parts]
    return dsa.map_blocks(lambda *b: qmul(*b, qaxis=qaxis), *parts, dtype=np.float64)


def qmul(*q, qaxis: int = -1) -> Any:
    """Hamilton product of two or more quaternion arrays, left to right.

    Parameters
    ----------
    *q : array_like, shape (..., 4, ...)
        Two or more arrays of quaternions along ``qaxis`` (all float) or of
        quaternion dtype (all of them). The other axes broadcast like numpy's.
    qaxis : int, default -1
        Axis holding w, x, y, z in every float array.

    Returns
    -------
    ndarray or DataArray
        ``q[0] * q[1] * ...``, of the broadcast shape; quaternion dtype if
        the inputs were; a DataArray like the first DataArray input that has
        the output's shape.

    Raises
    ------
    ValueError
        With fewer than two arrays, a mix of float and quaternion dtypes, an
        axis that is not of length 4, or shapes that do not broadcast.

    Examples
    --------
    >>> qmul([0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0])
    array([0., 0., 0., 1.])
    """
    args = _door.product(q, qaxis)
    if args.lazy:
        return _lazy_qmul(q, qaxis)
    if args.plain:
        # (n|1, 4) x (n|1, 4) float64: one pass, no copies
        out, infs = _qmul_rows(*args.parts)
        if not infs:
            return out
        # the general checks name the infinity
        args = _door.product(q, qaxis, general=True)
    result = args.parts[0]
    for nxt, shape in zip(args.parts[1:], args.shapes[1:], strict=True):
        if 0 in shape:  # the kernel reuses a single row for any length, even 0
            result = np.empty(shape + (4,))
            continue
        out, _ = _qmul_rows(_rows(result, shape, 4), _rows(nxt, shape, 4))
        result = out.reshape(shape + (4,))
    out = _join(result, args.was_quaternion, qaxis)
    for x in args.dataarrays:
        if x.shape == out.shape:
            return x.copy(data=out)
    return out


def _qmul_rows(p: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, int]:
    """p * q for kernel rows (n|1, 4), on both cores when long, and how many
    infinities the operands hold."""
    rows = 0 if 0 in (p.shape[0], q.shape[0]) else max(p.shape[0], q.shape[0])
    out = np.empty((rows, 4))  # numpy's allocation: huge pages when large
    infs = _parallel.launch(_rk.qmul_into, _rk.qmul_into_parallel, rows, p, q, out)
    return out, infs


def qmean(q: ArrayInput, axis: int | None = None, qaxis: int = -1) -> Any:
    """Mean rotation of quaternions (Markley's eigenvector method).

    The mean is the unit eigenvector of the largest eigenvalue of the mean
    outer product ``mean(q q^T)``: it does not depend on the signs of the
    inputs (q and -q are the same rotation) and weights each quaternion by
    ``|q|**2``. Its sign is chosen so that ``w >= 0``.

    Parameters
    ----------
    q : array_like, shape (..., 4, ...)
        Quaternions along ``qaxis``, or an array of quaternion dtype.
    axis : None or int or tuple of int, optional
        Axes to average over, counted on the array of quaternions (``q``
        without its ``qaxis``, as for quaternion dtype). Default: all.
    qaxis : int, default -1
        Axis of ``q`` holding w, x, y, z (ignored for quaternion dtype).

    Returns
    -------
    ndarray or DataArray
        The means, with the averaged axes removed; shape (4,) when averaging
        everything. Groups containing NaN give NaN.

    Raises
    ------
    ValueError
        For a bad ``qaxis``/``axis``, nothing to average, or a group made only
        of zero quaternions.

    Examples
    --------
    >>> qmean([[1.0, 0.0, 0.0, 0.0], [-1.0, 0.0, 0.0, 0.0]])
    array([1., 0., 0., 0.])

    Notes
    -----
    rigid-body-motion 0.9.3 picks the wrong eigenvector components (they come
    out permuted) and mixes up groups when ``axis`` leaves several; this
    implementation returns the actual eigenvector.
    """
    args = _door.mean(q, axis, qaxis)
    groups, keep_shape, reduce_axes = args.groups, args.keep_shape, args.reduce_axes
    outer = np.einsum("gni,gnj->gij", groups, groups) / groups.shape[1]
    finite = np.isfinite(outer).all(axis=(1, 2))
    outer[~finite] = np.eye(4)
    empty = np.trace(outer, axis1=1, axis2=2) == 0.0
    if empty.any():
        raise ValueError("q: every quaternion of a group to average is zero")
    _, vectors = np.linalg.eigh(outer)
    mean = vectors[:, :, -1]
    first_nonzero = np.argmax(mean != 0.0, axis=1)
    mean *= np.sign(mean[np.arange(len(mean)), first_nonzero])[:, None]
    mean[~finite] = np.nan
    out = _join(mean.reshape(keep_shape + (4,)), args.was_quaternion, args.qpos)
    if args.qdim is not None and out.ndim == args.ndim - len(reduce_axes):
        return _reduced_like(args.template, out, args.qdim, reduce_axes)
    return out


def _reduced_like(
    template: Any, out: np.ndarray, qdim: Any, reduce_axes: tuple[int, ...]
):
    """A DataArray for a reduction of ``template`` (its qdim kept, others dropped)."""
    other = [d for d in template.dims if d != qdim]
    dropped = {other[a]: 0 for a in reduce_axes}
    reduced = template.isel(dropped, drop=True)
    if reduced.shape != out.shape:
        return out
    return reduced.copy(data=out)


# ---------------------------------------------------------------------------
# interpolation
# ---------------------------------------------------------------------------


def _squad_rows(q: np.ndarray, t_in: np.ndarray, t_out: np.ndarray) -> np.ndarray:
    """Squad of one stored series (n, 4) at ``t_out`` -> (m, 4), in one pass
    (sign continuity and the stored signs included), on both cores when long."""
    return _parallel.launch(
        _sw.squad_walk, _sw.squad_walk_parallel, t_out.shape[0], q, t_in, t_out
    )


def _squad_series(
    series: np.ndarray, t_in: np.ndarray, t_out: np.ndarray
) -> np.ndarray:
    """Squad of (n, b, 4) independent series sampled at ``t_in`` -> (m, b, 4)."""
    if series.shape[1] == 1:
        return _squad_rows(kernel_array(series[:, 0, :]), t_in, t_out)[:, None, :]
    m = t_out.shape[0]
    out = np.empty((m, series.shape[1], 4))
    for b in range(series.shape[1]):
        out[:, b, :] = _squad_rows(kernel_array(series[:, b, :]), t_in, t_out)
    return out


def _squad_along(
    qf: np.ndarray, axis: int, t_in: np.ndarray, t_out: np.ndarray
) -> np.ndarray:
    """Interpolate ``qf`` (components last) along ``axis``; returns same layout."""
    moved = np.moveaxis(qf, axis, 0)
    rest = moved.shape[1:-1]
    series = moved.reshape(moved.shape[0], -1, 4)
    zero = _rk.first_zero_row(kernel_array(series.reshape(-1, 4)))
    if zero >= 0:
        _raise_zero("q", zero, "it cannot be interpolated")
    t_flat = kernel_array(t_out.reshape(-1))
    out = _squad_series(series, kernel_array(t_in), t_flat)
    out = out.reshape((t_flat.shape[0],) + rest + (4,))
    out = np.moveaxis(out, 0, axis)
    if t_out.ndim == 0:
        out = out.take(0, axis=axis)
    return out


def qinterp(
    q: ArrayInput, t_in: ArrayInput, t_out: ArrayInput, axis: int = 0, qaxis: int = -1
) -> Any:
    """Interpolate quaternions in time with squad (a cubic spline on rotations).

    Parameters
    ----------
    q : array_like, shape (..., n, ..., 4, ...)
        Quaternions along ``qaxis`` and samples along ``axis``, or an array of
        quaternion dtype, or a DataArray.
    t_in : array_like, shape (n,)
        Strictly increasing sample times of ``q`` (numbers or datetime64).
    t_out : array_like, shape (m,) or scalar
        Times to interpolate to, within ``[t_in[0], t_in[-1]]``.
    axis : int, default 0
        Axis of ``q`` along which the samples lie (counted on ``q`` as given).
    qaxis : int, default -1
        Axis of ``q`` holding w, x, y, z (ignored for quaternion dtype).

    Returns
    -------
    ndarray or DataArray
        ``q`` with ``axis`` resampled to ``t_out`` (removed for a scalar
        ``t_out``). Sign flips between successive input samples are undone
        before interpolating, so the path is the short one.

    Raises
    ------
    ValueError
        For bad axes, times that are not strictly increasing or of the wrong
        length, ``t_out`` outside the sampled range, or zero quaternions.

    Examples
    --------
    >>> q = [[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]]
    >>> qinterp(q, [0.0, 1.0], [0.5]).round(6)
    array([[0.707107, 0.      , 0.      , 0.707107]])
    """
    args = _door.interpolation(q, t_in, t_out, axis, qaxis)
    if args.kind == "dataarray":
        out = _sampled_dataarray(args.sampled, t_out, "raise")
        return out.data if args.dask else out
    if args.kind == "rows":
        return _squad_rows(args.q, args.t_in, args.t_out)
    out = _squad_along(args.q, args.axis, args.t_in, args.t_out)
    qpos = args.qpos
    if args.t_out.ndim == 0 and args.given_axis < qpos:
        qpos -= 1  # the sampled axis is gone
    return _join(out, args.was_quaternion, qpos)


def _qinterp_dataarray(
    da, dim: str, qdim: str, t_out, t_in=None, out_of_range: str = "raise"
):
    """Squad of a DataArray along ``dim``; other coordinates along ``dim`` are
    interpolated linearly (numbers) or take the nearest value (anything else).

    ``out_of_range="nan"`` gives NaN outside the sampled range (as
    ``DataArray.interp`` does) instead of raising. (The accessor's entry, and
    each chunk's on the lazy path.)
    """
    args = _door.dataarray_interpolation(da, dim, qdim, t_out, t_in, out_of_range)
    return _sampled_dataarray(args, t_out, out_of_range)


def _sampled_dataarray(args, t_out, out_of_range: str):
    """The squad of a checked DataArray (:class:`_door.quaternions.SampledDataArray`)."""
    import xarray as xr

    da, dim, qdim = args.da, args.dim, args.qdim
    if args.lazy:
        return _dask.qinterp(_qinterp_dataarray, da, dim, qdim, t_out, out_of_range)
    data, ax, t_in_f, flat_out, inside = (
        args.data, args.ax, args.t_in, args.t_out, args.inside
    )  # fmt: skip
    t_out_values = args.t_out_values
    if inside is None:
        values = _squad_along(data, ax, t_in_f, flat_out)
    else:
        shape = data.shape[:ax] + (flat_out.size,) + data.shape[ax + 1 :]
        values = np.full(shape, np.nan)
        if inside.any():
            index: list[Any] = [slice(None)] * values.ndim
            index[ax] = inside
            values[tuple(index)] = _squad_along(data, ax, t_in_f, flat_out[inside])
    values = np.moveaxis(values, -1, da.dims.index(qdim))

    coords = {}
    for name, coord in da.coords.items():
        if name == dim or dim not in coord.dims:
            if name != dim:
                coords[name] = coord
            continue
        if np.issubdtype(coord.dtype, np.number):
            coords[name] = coord.interp({dim: t_out_values.reshape(-1)})
        else:
            coords[name] = coord.sel({dim: t_out_values.reshape(-1)}, method="nearest")
        coords[name] = coords[name].drop_vars(dim, errors="ignore")
    if isinstance(t_out, xr.DataArray) and t_out.ndim == 1 and t_out.dims == (dim,):
        coords[dim] = t_out.variable
    else:
        coords[dim] = (dim, t_out_values.reshape(-1))
    result = xr.DataArray(values, coords, da.dims, da.name, dict(da.attrs))
    if t_out_values.ndim == 0:
        result = result.isel({dim: 0})
    return result


# ---------------------------------------------------------------------------
# rotation of vectors
# ---------------------------------------------------------------------------


def _lazy_rotate_vectors(q, v, axis: int, qaxis: int, one_to_one: bool):
    """rotate_vectors with dask-backed quaternions or vectors, chunk by chunk."""
    if not one_to_one:
        raise UnsupportedError(
            "one_to_one=False with dask-backed data is not lazy (its result "
            "has the shape of q times v); call .compute() first"
        )
    if not _dask.is_dask(q) and np.ndim(q) == 1:
        single = float_array(getattr(q, "values", q), "q")
        core = v.dims[axis] if _is_dataarray(v) else axis
        return _dask.elementwise(
            lambda block: rotate_vectors(single, block, axis=axis), v, core
        )
    if _is_dataarray(q) and _is_dataarray(v):
        out = _dask.blockwise(
            rotate_vectors, [q, v], [q.dims[qaxis], v.dims[axis]], v.dims[axis]
        )
        out.attrs = dict(v.attrs)
        return out.transpose(*v.dims) if set(out.dims) == set(v.dims) else out
    import dask.array as dsa

    qd = dsa.asarray(getattr(q, "data", q))
    vd = dsa.asarray(getattr(v, "data", v))
    qd = qd.rechunk({resolve_axis(qaxis, qd.ndim, "qaxis"): -1})
    vd = vd.rechunk({resolve_axis(axis, vd.ndim, "axis"): -1})
    return dsa.map_blocks(
        lambda a, b: rotate_vectors(a, b, axis=axis, qaxis=qaxis),
        qd, vd, dtype=np.float64, chunks=vd.chunks,
    )  # fmt: skip


def _rotate_rows(
    q_rows: np.ndarray, v_rows: np.ndarray, q_given: Any, v_given: Any
) -> np.ndarray:
    """q v q⁻¹ for kernel rows (n|1, 4) x (n|1, 3), on both cores when long.

    Rejects zero quaternions and infinities (named in ``q_given``/``v_given``,
    the arrays as the caller passed them) after the one pass that finds them.
    """
    v_rows = kernel_array(v_rows)
    rows = (
        0
        if 0 in (q_rows.shape[0], v_rows.shape[0])
        else max(q_rows.shape[0], v_rows.shape[0])
    )
    out = np.empty((rows, 3))  # numpy's allocation: huge pages when large
    zeros, infs = _parallel.launch(
        _rk.rotate_vectors_into,
        _rk.rotate_vectors_into_parallel,
        rows,
        q_rows,
        v_rows,
        out,
    )
    if infs:
        check_no_inf(np.asarray(v_given), "v", row_axis=False)
        check_no_inf(np.asarray(q_given, dtype=np.float64), "q")
    if zeros:
        _raise_zero("q", _rk.first_zero_row(q_rows), "it does not describe a rotation")
    return out


def rotate_vectors(
    q: ArrayInput,
    v: ArrayInput,
    axis: int = -1,
    qaxis: int = -1,
    one_to_one: bool = True,
) -> Any:
    """Rotate vectors by quaternions, ``q v q⁻¹``.

    Correct for quaternions of any non-zero norm (the rotation does not scale
    the vectors).

    Parameters
    ----------
    q : array_like, shape (..., 4, ...)
        Quaternions along ``qaxis``, or an array of quaternion dtype.
    v : array_like, shape (..., 3, ...)
        Vectors along ``axis``; a DataArray gives a DataArray back when the
        output has its shape.
    axis : int, default -1
        Axis of ``v`` holding x, y, z.
    qaxis : int, default -1
        Axis of ``q`` holding w, x, y, z (ignored for quaternion dtype).
    one_to_one : bool, default True
        If True, pair quaternions and vectors element by element: the other
        axes of ``q`` and ``v`` correspond in order and must match or be 1
        (a single quaternion rotates every vector). If False, rotate every
        vector by every quaternion.

    Returns
    -------
    ndarray or DataArray
        With ``one_to_one``: the broadcast shape of the non-vector axes, with
        the vector axis at ``axis``. Otherwise shape ``q_shape + v.shape``
        where ``q_shape`` is ``q``'s shape without ``qaxis``.

    Raises
    ------
    ValueError
        For axes of the wrong length, incompatible shapes, or zero quaternions.

    Examples
    --------
    >>> rotate_vectors([0.0, 0.0, 0.0, 2.0], [1.0, 0.0, 0.0]).round(12)
    array([-1.,  0.,  0.])
    """
    args = _door.rotation(q, v, axis, qaxis, one_to_one)
    if args.lazy:
        return _lazy_rotate_vectors(q, v, axis, qaxis, one_to_one)
    template = args.template
    if args.kind == "rows":
        return _like(template, _rotate_rows(args.q, args.v, args.q, args.v))
    qf, vm, vax = args.q, args.v, args.vax
    if args.kind == "broadcast":
        shape = args.shape
        out = _rotate_rows(_rows(qf, shape, 4), _rows(vm, shape, 3), qf, vm)
        out = np.moveaxis(out.reshape(shape + (3,)), -1, vax)
        return _like(template, out)
    q_shape, v_shape = qf.shape[:-1], args.shape
    q_rows = kernel_array(qf.reshape(-1, 4))
    v_rows = kernel_array(vm.reshape(-1, 3))
    if not q_shape:
        out = _rotate_rows(q_rows, v_rows, qf, vm)
        out = np.moveaxis(out.reshape(v_shape + (3,)), -1, vax)
        return _like(template, out)
    zero = _rk.first_zero_row(q_rows)
    if zero >= 0:
        _raise_zero("q", zero, "it does not describe a rotation")
    out = _qk.rotate_vectors_outer(q_rows, v_rows).reshape(q_shape + v_shape + (3,))
    return np.moveaxis(out, -1, len(q_shape) + vax)


# ---------------------------------------------------------------------------
# construction
# ---------------------------------------------------------------------------

_ELEMENTARY_AXIS = {"r": 1, "p": 2, "y": 3}


def from_euler_angles(
    rpy: Any = None,
    roll: Any = None,
    pitch: Any = None,
    yaw: Any = None,
    axis: int = -1,
    order: str = "rpy",
    return_quaternion: bool = False,
) -> Any:
    """Quaternions from roll, pitch and yaw angles (radians).

    Roll, pitch and yaw are rotations about the x, y and z axes. The result is
    the product of the three elementary rotations in the sequence ``order``,
    ``q = q[order[0]] * q[order[1]] * q[order[2]]``: with the default "rpy",
    ``roll * pitch * yaw``. Angles that are not given are left out.

    Parameters
    ----------
    rpy : array_like, shape (..., 3, ...), optional
        Roll, pitch and yaw along ``axis``. Excludes ``roll``, ``pitch`` and
        ``yaw``.
    roll, pitch, yaw : array_like, optional
        Separate angle arrays; their shapes broadcast together.
    axis : int, default -1
        Axis of ``rpy`` holding the angles, and the axis of the result that
        holds w, x, y, z.
    order : str, default "rpy"
        A permutation of "r", "p" and "y".
    return_quaternion : bool, default False
        Return an array of numpy-quaternion's quaternion dtype.

    Returns
    -------
    ndarray, shape (..., 4, ...)
        Unit quaternions (or quaternion dtype, without the component axis).

    Raises
    ------
    ValueError
        If no angle is given, ``rpy`` is combined with separate angles, the
        shapes disagree or ``order`` is not a permutation of "rpy".

    Examples
    --------
    >>> from_euler_angles(yaw=np.pi / 2).round(6)
    array([0.707107, 0.      , 0.      , 0.707107])
    """
    if not isinstance(order, str) or sorted(order) != ["p", "r", "y"]:
        raise ValueError(
            f"order must be a permutation of 'r', 'p' and 'y', got {order!r}"
        )
    args = _door.euler_angles(rpy, roll, pitch, yaw, axis, return_quaternion)
    angles, shape = args.angles, args.shape
    result = None
    for key in order:
        if key not in angles:
            continue
        half = np.broadcast_to(angles[key], shape).reshape(-1) / 2.0
        rotor = np.zeros((half.shape[0], 4))
        rotor[:, 0] = np.cos(half)
        rotor[:, _ELEMENTARY_AXIS[key]] = np.sin(half)
        result = rotor if result is None else _qk.qmul(result, rotor)
    assert result is not None  # at least one angle is given (checked above)
    quats = result.reshape(shape + (4,))
    if return_quaternion:
        return _join(quats, True, -1)
    return np.moveaxis(quats, -1, args.axis)
