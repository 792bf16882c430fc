"""Lazy changes of frame: transforms and velocity transforms, per time chunk.

The frames come resolved, and the graph carries their values (a
:class:`rbm_nb.core._frame_snapshot.FrameTree` snapshot), each task only the
samples its chunk's times need; the per-block function is the door's eager
call on one block (:mod:`rbm_nb._door.inputs`). The result is cropped to the
time range where every moving frame of the chain is defined.
"""

from __future__ import annotations

import functools
from collections.abc import Callable

import numpy as np

from .._engine import twist as tw
from .._engine.chain import chain
from .._engine.time import as_track
from .coverage import combined
from .dask_chunks import MARGIN, as_dataarray, over_time
from .unpack import resolve_axis


def frame_time_range(outof, into):
    """First and last time at which every continuous moving frame of the chain is defined."""
    firsts, lasts = [], []
    for frame, _ in chain(outof, into):
        ts = frame.timestamps
        if ts is not None and not frame.discrete:
            firsts.append(ts[0])
            lasts.append(ts[-1])
    if not firsts:
        return None
    return max(firsts), min(lasts)


def transform(
    block: Callable,
    arr,
    source,
    to_frame,
    dim,
    axis,
    timestamps,
    time_axis,
    return_timestamps: bool,
    snapshot: Callable,
    attr: str,
    quaternions: bool,
):
    """A transform of dask-backed data, one task per time chunk.

    The frames come resolved (``source``, ``to_frame``) and the graph
    carries their values (``snapshot``,
    :meth:`rbm_nb.core._frame_snapshot.FrameTree.of`), each task only the
    samples its chunk's times need: tasks run wherever dask sends them,
    with or without the client's registry, and a frame registered after
    this call does not change the result.

    ``block(block, frames, dim=, time_dim=, attr=, origin=)`` is the door's
    eager call on one block (:func:`rbm_nb._door.inputs.transform_block`).
    """
    series = _TimeSeries.of(arr, dim, axis, timestamps, time_axis)
    per_block = functools.partial(
        block,
        dim=series.comp_dim,
        time_dim=series.time_dim,
        attr=attr,
        origin=_origin(series.arr[series.time_dim].values),
    )
    span = frame_time_range(source, to_frame)
    return series.run(
        per_block,
        snapshot([source, to_frame]),
        [] if span is None else [span],
        quaternions,
        return_timestamps,
    )


class _TimeSeries:
    """A dask-backed argument of a transform as a DataArray along time."""

    def __init__(self, arr, plain: bool, time_dim: str, comp_dim: str):
        self.arr = arr
        self.plain = plain
        self.time_dim = time_dim
        self.comp_dim = comp_dim

    @classmethod
    def of(cls, arr, dim, axis, timestamps, time_axis) -> _TimeSeries:
        plain = not hasattr(arr, "dims")
        if plain:
            if timestamps is None:
                raise ValueError(
                    "a dask array needs timestamps= to be transformed lazily "
                    "(without them the result would follow the frames' own times)"
                )
            arr = as_dataarray(arr, time_axis, timestamps)
            comp_dim = arr.dims[resolve_axis(-1 if axis is None else axis, arr.ndim)]
            return cls(arr, True, "time", comp_dim)
        time_dim = time_dim_of(arr, timestamps, time_axis)
        if time_dim is None or time_dim not in arr.coords:
            raise ValueError(
                f"the dask-backed DataArray needs a coordinate for its time "
                f"dimension {time_dim!r} to be transformed lazily"
            )
        comp_dim = dim if dim is not None else arr.dims[-1 if axis is None else axis]
        return cls(arr, False, time_dim, comp_dim)

    def run(self, block, frames, spans, quaternions: bool, return_timestamps: bool):
        """``block`` over the chunks, cropped to the (first, last) ``spans``."""
        times = self.arr[self.time_dim].values
        start, stop = 0, len(times)
        if spans:
            first = max(s[0] for s in spans)
            last = min(s[1] for s in spans)
            start = int(np.searchsorted(times, first, side="left"))
            stop = int(np.searchsorted(times, last, side="right"))
            if stop <= start:
                raise ValueError(
                    f"the array's times ({times[0]} to {times[-1]}) and the frames' "
                    f"({first} to {last}) do not overlap"
                )
        fill = {self.comp_dim: (1.0, 0.0, 0.0, 0.0) if quaternions else 0.0}
        out = over_time(
            block,
            self.arr,
            self.time_dim,
            start=start,
            stop=stop,
            fill=fill,
            context=frames,
        )
        if self.plain:
            data = out.data
            return (data, times[start:stop]) if return_timestamps else data
        return out


def velocity_transform(
    arr,
    frame,
    to_frame,
    extras,
    dim,
    axis,
    timestamps,
    time_axis,
    return_timestamps: bool,
    snapshot: Callable,
    block: Callable,
):
    """A change of frame of dask-backed velocities, lazily per time chunk.

    ``extras`` are the looked-up terms, estimated once for the whole array
    (:func:`rbm_nb._engine.twist.velocity_terms`); each task carries the
    frames' samples and the terms' values around its chunk's times (see
    :func:`transform`) and runs ``block(block, context, dim=, time_dim=,
    origin=)``, the door's eager call on one block
    (:func:`rbm_nb._door.inputs.velocity_block`).
    """
    series = _TimeSeries.of(arr, dim, axis, timestamps, time_axis)
    whole = series.arr[series.time_dim].values
    # the whole array's matchings, before the graph is built
    combined(frame, to_frame, as_track(whole), [t for _, t in extras])
    context = VelocityContext(
        snapshot([frame, to_frame]),
        tuple(extras),
        tuple(tw.interpolated_terms(frame, to_frame, as_track(whole), extras)),
    )
    per_block = functools.partial(
        block,
        dim=series.comp_dim,
        time_dim=series.time_dim,
        origin=_origin(whole),
    )
    spans = [(t.values[0], t.values[-1]) for _, t in extras if t is not None]
    span = frame_time_range(frame, to_frame)
    return series.run(
        per_block,
        context,
        spans + ([] if span is None else [span]),
        False,
        return_timestamps,
    )


class VelocityContext:
    """What a block of a velocity transform needs: frames and the looked-up terms."""

    def __init__(self, frames, extras, interpolated):
        self.frames = frames
        self.extras = extras
        self.interpolated = interpolated

    def window(self, first, last) -> VelocityContext:
        extras = []
        for values, track in self.extras:
            if track is None:
                extras.append((values, track))
                continue
            n = len(track)
            lo = int(np.searchsorted(track.values, first, side="right")) - 1 - MARGIN
            hi = int(np.searchsorted(track.values, last, side="left")) + 1 + MARGIN
            lo, hi = max(0, lo), min(n, hi)
            # the same origin: the block interpolates in the eager call's seconds
            extras.append((values[lo:hi], track.slice(lo, hi)))
        return VelocityContext(
            self.frames.window(first, last), tuple(extras), self.interpolated
        )


def time_dim_of(arr, timestamps, time_axis) -> str | None:
    """The time dimension of a DataArray argument (None for a plain array)."""
    if not hasattr(arr, "dims"):
        return None
    if isinstance(timestamps, str):
        return timestamps
    return arr.dims[0 if time_axis is None else time_axis]


def _origin(times) -> int | None:
    """Nanoseconds of the first of datetime64 ``times`` (None for numbers)."""
    first = as_track(np.asarray(times)[:1])
    return first.origin if first.is_datetime else None
