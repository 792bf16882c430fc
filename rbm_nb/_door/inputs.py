"""The door of the transforms: what their arguments become before the engine.

A facade (:mod:`rbm_nb.transforms`, the transform methods of
:class:`~rbm_nb.frames.ReferenceFrame`) calls one function here and hands
the engine what comes back; the engine checks nothing again
(:mod:`rbm_nb._engine.transform`):

* :func:`blocks`: an array argument checked (numbers, the spatial axis of
  length 3 or 4, rows finite or entirely NaN, unit quaternions, timestamps
  one per sample) and laid out as the engine's (n, k, c)
  :class:`~rbm_nb._engine.transform.Blocks`;
* :func:`arguments`: the whole call of a public transform -- the array
  unpacked (:func:`rbm_nb._door.unpack`: DataArray dims, axes, timestamps),
  the frames resolved (``outof`` from the DataArray's attrs when not
  given), and either Blocks or, for a one-point-sized call through a static
  chain, the checked rows the engine's short way takes;
* :func:`transform_block`, :func:`velocity_block`: the same door for one
  block of dask-backed data, so that the lazy path (:mod:`rbm_nb._door.dask_blocks`)
  runs exactly the eager engine call on each chunk and never calls back
  into a facade.

Frame names are resolved by the caller's ``resolve`` (``frames.resolve_frame``):
the frames module sits above this one and uses it too.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np

from .._engine import chain as _chain
from .._engine import time as _time
from .._engine import transform as _engine_transform
from .._engine import twist as _twist
from .._engine.transform import SIZES, Blocks
from .._kernels.rows import MAX_COORDINATE
from .coverage import chain_samples, combined, connected
from .unpack import Unpacked, float_array, kernel_array, moveaxis, resolve_axis, unpack
from .validation import check_whole_rows, normalize_quaternions
from .xarray import wrap

__all__ = [
    "blocks",
    "Arguments",
    "arguments",
    "method_arguments",
    "frames",
    "transform_block",
    "velocity_block",
]

# At most this many values take the short check of :func:`_plain_rows`
# (a comparison per value in Python) instead of two numpy reductions,
# whose fixed cost (~1 µs each) is a third of a one-point transform.
_FEW = 12


def blocks(
    arr: Any, size: int, axis: Any, time_axis: Any, timestamps: Any, kind: str
) -> Blocks:
    """An array argument checked and laid out as (n, k, ``size``) blocks.

    Parameters
    ----------
    arr : array_like
        Numbers (or numpy-quaternion dtype), an axis of length ``size``.
    axis, time_axis : int
        The spatial and the time axis (negative counts from the end).
    timestamps : array_like, Track or None
        One per sample along ``time_axis``; None: the array is not a series.
    kind : str
        What the values are ("points", "vectors", "quaternions"), for messages.

    Raises
    ------
    ValueError
        Naming ``arr``, ``axis``, ``time_axis`` or ``timestamps`` and what was
        expected: not numeric, no axis of length ``size``, a partly NaN or
        infinite row, a quaternion far from unit norm, timestamps of another
        length or not increasing, both axes the same.
    """
    arr = float_array(arr, "arr")
    if arr.ndim == 0:
        raise ValueError(f"arr must have an axis of length {size}, got a scalar")
    ndim = arr.ndim
    spatial = resolve_axis(axis, ndim, "axis")
    if arr.shape[spatial] != size:
        raise ValueError(
            f"arr must have length {size} along axis {axis} (the {kind}' "
            f"coordinates), got shape {arr.shape}"
        )
    # NaN rows are missing samples and pass through; infinities and
    # partly NaN rows are mistakes
    check_whole_rows(moveaxis(arr, spatial, -1), "arr")
    if size == 4:
        arr = normalize_quaternions(moveaxis(arr, spatial, -1), "arr", allow_nan=True)
        arr = moveaxis(arr, -1, spatial)
    if timestamps is None:
        moved = moveaxis(arr, spatial, -1)
        data = kernel_array(moved.reshape(1, -1, size))
        return Blocks(data, None, moved.shape, spatial, None, ndim)
    time = resolve_axis(time_axis, ndim, "time_axis")
    if time == spatial:
        raise ValueError(
            f"time_axis={time_axis} and axis={axis} are the same axis of arr"
        )
    if isinstance(timestamps, _time.Track):
        if len(timestamps) != arr.shape[time]:
            raise ValueError("timestamps and arr differ in length")
        track = timestamps
    else:
        track = _time.as_track(
            timestamps, "timestamps", length=arr.shape[time], copy=False
        )
    moved = moveaxis(arr, (time, spatial), (0, -1))
    data = kernel_array(moved.reshape(moved.shape[0], -1, size))
    return Blocks(data, track, moved.shape, spatial, time, ndim)


def _plain_rows(arr: Any, axis: Any) -> np.ndarray | None:
    """(1, n, 3) float64 rows of a (3,) or (n, 3) numeric ndarray whose values
    are all finite and within ±MAX_COORDINATE, else None (then
    :func:`blocks` checks it and names what is wrong)."""
    # the one-point call's short way (bench_small_call.py): each numpy
    # attribute read, reshape and numpy scalar comparison here is ~0.1-0.3 µs
    # of a ~3.5 µs call, so the tests are ordered to read each once and the
    # few values are compared as Python floats
    if type(arr) is not np.ndarray:
        return None
    ndim = arr.ndim
    if ndim == 1:
        if arr.shape[0] != 3 or (axis != -1 and axis != 0):
            return None
    elif ndim != 2 or arr.shape[1] != 3 or (axis != -1 and axis != 1):
        return None
    if arr.dtype.kind not in "fiu":
        return None
    if arr.size <= _FEW:
        # NaN fails both comparisons, as do infinities
        for v in arr.tolist() if ndim == 1 else arr.ravel().tolist():
            if not -MAX_COORDINATE <= v <= MAX_COORDINATE:
                return None
    elif arr.size and not (
        -MAX_COORDINATE <= arr.min() and arr.max() <= MAX_COORDINATE
    ):
        return None
    data = kernel_array(arr)
    # new leading axes of length 1: a C-contiguous view, as reshape(1, -1, 3)
    return data[None, None] if ndim == 1 else data[None]


def _source(
    resolve: Callable, outof: Any, attrs: dict | None, attr: str, stacklevel: int = 5
) -> Any:
    """``outof`` resolved, or the frame a DataArray's ``attrs[attr]`` names."""
    if outof is None:
        if attrs is not None and attr in attrs:
            return resolve(attrs[attr], f"the DataArray's {attr} attribute")
        raise ValueError(
            f"outof must be given unless arr is a DataArray whose attrs name a "
            f"registered frame under {attr!r}"
        )
    frame = resolve(outof, "outof")
    if attrs is not None and attr in attrs and attrs[attr] != frame.name:
        warnings.warn(
            f"transforming the {attr!r} of the array out of {frame.name!r}, but "
            f"its attrs say its {attr} is {attrs[attr]!r}",
            stacklevel=stacklevel,  # the user's call of the public function
        )
    return frame


class Arguments:
    """A public transform's call, checked: frames, and blocks or static rows."""

    __slots__ = (
        "outof",
        "into",
        "unpacked",
        "attrs",
        "blocks",
        "rows",
        "static",
        "shape",
    )

    def __init__(self, outof, into, unpacked, attrs, blocks, rows, static, shape=None):
        self.outof = outof
        self.into = into
        self.unpacked = unpacked  # None on the short way
        self.attrs = attrs  # a copy of a DataArray's attrs, None for arrays
        self.blocks = blocks  # Blocks, or None on the short way
        self.rows = rows  # (1, n, 3) checked rows on the short way
        self.static = static  # the static chain's (t, r) on the short way
        self.shape = shape  # the input's shape on the short way

    def result(self, out: np.ndarray, ts_out: Any, attr: str, return_timestamps: bool):
        """The public result: a DataArray for one, else the array (and times)."""
        if self.attrs is not None:  # a DataArray came in: one goes out
            attrs = self.attrs
            attrs[attr] = attrs["representation_frame"] = self.into.name
            return wrap(self.unpacked, out, ts_out, attrs)
        return (out, ts_out) if return_timestamps else out


def arguments(
    kind: str,
    arr: Any,
    into: Any,
    outof: Any,
    dim: Any,
    axis: Any,
    timestamps: Any,
    time_axis: Any,
    attr: str,
    resolve: Callable,
    velocity: bool = False,
) -> Arguments | ShortWay:
    """Everything a public transform checks, once, for an eager call.

    ``kind`` is "points", "vectors" or "quaternions" (velocities are
    vectors); ``attr`` the DataArray attribute naming the frame they are in
    now (``outof``'s default). On the short way (``rows`` set) a plain (3,)
    or (n, 3) array goes through a static chain without being laid out.
    The array's and the chain's times must share a sample, unless
    ``velocity`` (a change of a velocity's frames, whose terms the caller
    checks first: :func:`rbm_nb._door.coverage.velocity_transform`).
    """
    if type(arr) is np.ndarray and outof is not None:
        # a plain array (most calls): no attrs to read outof from
        if timestamps is None and dim is None and kind != "quaternions":
            # the short way, taken by most one-point calls (widgets, the
            # tf2-style Transformer)
            source = resolve(outof, "outof")
            to_frame = resolve(into, "into")
            short = _short_way(source, arr, to_frame, -1 if axis is None else axis)
            if short is not None:
                return short
            # no dim, no timestamps: nothing here can raise after the frames
            unpacked = unpack(arr, axis=axis, time_axis=time_axis)
        else:
            unpacked = unpack(
                arr, dim=dim, axis=axis, time_axis=time_axis, timestamps=timestamps
            )
            source = resolve(outof, "outof")
            to_frame = resolve(into, "into")
        laid_out = _blocks_of(unpacked, kind, unpacked.timestamps)
        if not velocity:
            chain_samples(source, to_frame, [laid_out.track])
        return Arguments(source, to_frame, unpacked, None, laid_out, None, None)
    unpacked = unpack(
        arr, dim=dim, axis=axis, time_axis=time_axis, timestamps=timestamps
    )
    attrs = None if unpacked.source is None else dict(unpacked.attrs)
    source = _source(resolve, outof, attrs, attr)
    to_frame = resolve(into, "into")
    laid_out = _blocks_of(unpacked, kind, unpacked.timestamps)
    if not velocity:
        chain_samples(source, to_frame, [laid_out.track])
    return Arguments(source, to_frame, unpacked, attrs, laid_out, None, None)


def method_arguments(
    kind: str, frame: Any, arr: Any, to_frame: Any, axis: Any, time_axis: Any,
    timestamps: Any,
) -> Arguments | ShortWay:  # fmt: skip
    """The checked call of a frame's transform method (frames resolved; no
    DataArray unpacking: a DataArray gives its data, ``timestamps`` as given)."""
    if timestamps is None and kind != "quaternions":
        short = _short_way(frame, arr, to_frame, axis)
        if short is not None:
            return short
    laid_out = blocks(arr, SIZES[kind], axis, time_axis, timestamps, kind)
    chain_samples(frame, to_frame, [laid_out.track])
    return Arguments(frame, to_frame, None, None, laid_out, None, None)


class ShortWay:
    """A checked call on the short way: plain ``rows`` (1, n, 3) through the
    ``static`` chain's (t, r), the result of the input's ``shape``. Three
    slots, not :class:`Arguments`' eight: made once per one-point call."""

    __slots__ = ("rows", "static", "shape")

    def __init__(self, rows: np.ndarray, static: Any, shape: tuple) -> None:
        self.rows = rows
        self.static = static
        self.shape = shape


def _short_way(source: Any, arr: Any, to_frame: Any, axis: Any) -> ShortWay | None:
    connected(source, to_frame)
    static = _chain.static_transform(source, to_frame)
    if static is None:
        return None
    rows = _plain_rows(arr, axis)
    if rows is None:
        return None
    return ShortWay(rows, static, arr.shape)


def _blocks_of(unpacked: Unpacked, kind: str, timestamps: Any) -> Blocks:
    return blocks(
        unpacked.data,
        SIZES[kind],
        unpacked.axis,
        unpacked.time_axis,
        timestamps,
        kind,
    )


def frames(
    resolve: Callable, outof: Any, into: Any, attrs: dict | None, attr: str
) -> tuple[Any, Any]:
    """(outof, into) resolved as :func:`arguments` resolves them (the lazy path)."""
    return _source(resolve, outof, attrs, attr, 6), resolve(into, "into")


# ---------------------------------------------------------------------------
# one block of dask-backed data: the eager engine call on a chunk
# ---------------------------------------------------------------------------


def transform_block(block, frames, kind: str, dim, time_dim, attr, origin):
    """The eager transform of one NumPy-backed block, on frames from their values.

    ``origin`` is the nanosecond the whole array's times count from (None
    for numeric times), so that the block interpolates in the eager call's
    seconds (:func:`_track_from`).
    """
    unpacked = unpack(block, dim=dim, timestamps=time_dim)
    laid_out = _blocks_of(unpacked, kind, _track_from(unpacked.timestamps, origin))
    with _task_values(frames) as (outof, into):
        # a chunk's times may miss the chain's span where the whole array's do not
        chain_samples(outof, into, [laid_out.track])
        out, ts_out = _engine_transform.transform(outof, kind, laid_out, into)
    attrs = dict(unpacked.attrs)
    attrs[attr] = attrs["representation_frame"] = into.name
    return wrap(unpacked, out, ts_out, attrs)


def velocity_block(block, context, what: str, dim, time_dim, origin):
    """The eager velocity transform of one NumPy-backed block.

    ``context`` (:class:`rbm_nb._door.dask_blocks.VelocityContext`) holds the frames'
    values and the looked-up terms around the block's times, and which
    terms the whole array's call interpolates; ``what`` is the frame being
    changed.
    """
    unpacked = unpack(block, dim=dim, timestamps=time_dim)
    laid_out = _blocks_of(unpacked, "vectors", _track_from(unpacked.timestamps, origin))
    with _task_values(context.frames) as (frame, to_frame):
        # the matchings of velocity_parts: the chunk with the chain, then
        # with the terms looked up around it
        combined(frame, to_frame, laid_out.track, [t for _, t in context.extras])
        rotated, matched, final = _twist.velocity_parts(
            laid_out, frame, to_frame, context.extras, context.interpolated
        )
    out = laid_out.restore(_twist.combine(rotated, matched), final)
    attrs = dict(unpacked.attrs)
    attrs[what] = attrs["representation_frame"] = to_frame.name
    return wrap(unpacked, out, final.timestamps, attrs)


@contextmanager
def _task_values(frames: Any) -> Iterator[list[Any]]:
    """The values of a task's frames (``FrameTree.values``: made from the
    records, nothing checked again), let go of when the task ends.

    The engine caches chains by pairs of values; a task's values serve one
    block, so its entries are dropped with them (as a frame that changes
    drops them), or a worker would hold every finished window's samples.
    """
    try:
        yield frames.values()
    finally:
        _chain.forget()


def _track_from(timestamps: Any, origin: int | None) -> _time.Track:
    """A chunk's timestamps as a Track counted from the whole array's first sample.

    Interpolation reads times as float seconds from an origin; with the
    chunk's own first sample as origin they would differ from the eager
    call's by rounding, which fast-changing velocities turn into ~1e-10.
    """
    track = _time.as_track(timestamps, copy=False)
    if origin is None or not track.is_datetime:
        return track
    return _time.Track(
        track.values, track.key, (track.key - origin) / 1e9, origin, track.kind
    )
