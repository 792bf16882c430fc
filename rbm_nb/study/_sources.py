"""Where the recordings of a study come from, and how one is opened.

A recording is a set of named streams (``head``, ``left_eye``, ...), each an
:class:`xarray.Dataset` with a ``time`` dimension. What travels to a dask
worker is a :class:`RecordingSource` -- a few paths, or the datasets
themselves when the user passed them in memory -- and the worker opens it
there, so files are read where the work is done.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from ..ros import RosbagReader

STREAM_SUFFIXES = (".nc", ".bag")
# the message types a bag's topic must have to become a stream of a recording
POSE_MESSAGE_TYPES = frozenset(
    {"geometry_msgs/TransformStamped", "geometry_msgs/PoseStamped", "nav_msgs/Odometry"}
)


@dataclass(frozen=True)
class Recording:
    """One opened recording: its name and its streams.

    Streams are looked up by name (``rec["head"]``); a recording made of a
    single stream also offers it as :attr:`dataset`.
    """

    name: str
    streams: Mapping[str, xr.Dataset]

    def __getitem__(self, stream: str) -> xr.Dataset:
        try:
            return self.streams[stream]
        except KeyError:
            raise KeyError(
                f"recording {self.name!r} has no stream {stream!r}; "
                f"it has {sorted(self.streams)}"
            ) from None

    def __contains__(self, stream: object) -> bool:
        return stream in self.streams

    @property
    def dataset(self) -> xr.Dataset:
        """The only stream of a single-stream recording."""
        if len(self.streams) != 1:
            raise ValueError(
                f"recording {self.name!r} has {len(self.streams)} streams "
                f"({sorted(self.streams)}); pick one with rec[name]"
            )
        return next(iter(self.streams.values()))

    def time_range(self) -> tuple[Any, Any]:
        """First and last timestamp over all streams (the span of the recording)."""
        firsts, lasts = [], []
        for stream, ds in self.streams.items():
            if "time" not in ds.coords or ds.sizes.get("time", 0) == 0:
                raise ValueError(
                    f"stream {stream!r} of recording {self.name!r} has no "
                    f"'time' coordinate with samples"
                )
            time = ds.indexes["time"]
            firsts.append(time[0])
            lasts.append(time[-1])
        return min(firsts), max(lasts)

    def select(self, start, stop) -> Recording:
        """The same recording restricted to ``start <= time <= stop``."""
        return Recording(
            self.name,
            {k: ds.sel(time=slice(start, stop)) for k, ds in self.streams.items()},
        )


# netCDF4's HDF5 library is not thread-safe, and xarray locks only its reads,
# not the opening of files: every file access of a study -- opening, reading,
# writing results -- goes through this lock (tasks on the threaded scheduler
# share one process).
_NETCDF_LOCK = threading.RLock()


@dataclass(frozen=True)
class RecordingSource:
    """What is needed to open one recording: paths of its streams, or datasets."""

    name: str
    paths: Mapping[str, Path] = field(default_factory=dict)
    datasets: Mapping[str, xr.Dataset] = field(default_factory=dict)

    def open(
        self,
        chunks: Any = None,
        start: Any = None,
        stop: Any = None,
        rows: Mapping[str, tuple[int, int]] | None = None,
    ) -> Recording:
        """Load the streams, restricted to ``start <= time <= stop`` if given.

        Files are read into memory (only the selected span) and closed; with
        ``chunks`` the loaded streams are then made dask-backed, so that an
        analysis written with rbm_nb's lazy functions computes chunk by chunk.

        ``rows`` gives, per stream, the ``(first, stop)`` rows of that span
        (from :meth:`window_rows`): a netCDF file or dataset is then cut by
        position before anything else is read or decoded, so that neither the
        data nor the time coordinate outside the span is ever in memory.
        Streams not in ``rows`` (bags) are cut by time.
        """
        span = slice(start, stop)
        rows = rows or {}
        streams: dict[str, xr.Dataset] = {}
        for stream, path in self.paths.items():
            if stream in rows:
                streams[stream] = _read_rows(path, rows[stream])
            else:
                streams.update(_load_path(stream, path, span))
        for stream, ds in self.datasets.items():
            if stream in rows:
                streams[stream] = ds.isel(time=slice(*rows[stream]))
            else:
                streams[stream] = ds.sel(time=span) if span != slice(None) else ds
        if chunks is not None:
            streams = {k: ds.chunk(chunks) for k, ds in streams.items()}
        return Recording(self.name, streams)

    def time_range(self) -> tuple[Any, Any]:
        """First and last timestamp over all streams.

        Reads two values of each netCDF file's time coordinate (the first and
        the last); a bag is read whole.
        """
        firsts, lasts = [], []
        for stream, path in self.paths.items():
            if _is_bag(path):
                first, last = Recording(
                    self.name, _load_path(stream, path, slice(None))
                ).time_range()
            else:
                with _NETCDF_LOCK, _open_unindexed(path) as ds:
                    _check_time(ds, stream, self.name, path)
                    first, last = ds["time"].isel(time=[0, -1]).values
            firsts.append(first)
            lasts.append(last)
        if self.datasets:
            first, last = Recording(self.name, dict(self.datasets)).time_range()
            firsts.append(first)
            lasts.append(last)
        return min(firsts), max(lasts)

    def window_rows(
        self, spans: Sequence[tuple[Any, Any]]
    ) -> list[dict[str, tuple[int, int]]]:
        """The rows of each stream inside each span ``start <= time <= stop``.

        Each netCDF file's time coordinate is read once, in blocks of
        :data:`TIME_BLOCK` samples, so memory does not grow with the length
        of the recording. Bags are left out (they are cut by time).

        Returns
        -------
        list of dict
            One per span: ``{stream: (first_row, stop_row)}``.
        """
        starts = np.array([s for s, _ in spans])
        stops = np.array([s for _, s in spans])
        per_stream: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        for stream, path in self.paths.items():
            if not _is_bag(path):
                per_stream[stream] = _rows_in_file(
                    path, stream, self.name, starts, stops
                )
        for stream, ds in self.datasets.items():
            time = ds.indexes["time"]
            if not time.is_monotonic_increasing:
                raise ValueError(_unsorted(stream, self.name, "the dataset"))
            per_stream[stream] = (
                time.searchsorted(starts, side="left"),
                time.searchsorted(stops, side="right"),
            )
        return [
            {k: (int(lo[j]), int(hi[j])) for k, (lo, hi) in per_stream.items()}
            for j in range(len(spans))
        ]


# samples of a time coordinate decoded at once when finding window rows
TIME_BLOCK = 1 << 16


def _is_bag(path: Path) -> bool:
    return path.suffix == ".bag" or path.is_dir()


def _open_unindexed(path: Path) -> xr.Dataset:
    """A netCDF file opened lazily without building indexes.

    Building the index of the ``time`` coordinate would read and decode all
    of it; without indexes, ``isel`` reads only the rows selected.
    """
    return xr.open_dataset(path, create_default_indexes=False)


def _check_time(ds: xr.Dataset, stream: str, recording: str, path: Path) -> None:
    if "time" not in ds.variables or ds.sizes.get("time", 0) == 0:
        raise ValueError(
            f"stream {stream!r} of recording {recording!r} ({path}) "
            f"has no 'time' coordinate with samples"
        )


def _unsorted(stream: str, recording: str, where: Any) -> str:
    return (
        f"the times of stream {stream!r} of recording {recording!r} ({where}) "
        f"are not sorted; windows need increasing times"
    )


def _rows_in_file(
    path: Path, stream: str, recording: str, starts: np.ndarray, stops: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Per span, the number of samples before it and up to its end."""
    lo = np.zeros(len(starts), dtype=np.int64)
    hi = np.zeros(len(stops), dtype=np.int64)
    with _NETCDF_LOCK, _open_unindexed(path) as ds:
        _check_time(ds, stream, recording, path)
        time = ds["time"]
        previous = None
        for first in range(0, time.size, TIME_BLOCK):
            block = time.isel(time=slice(first, first + TIME_BLOCK)).values
            if (previous is not None and block[0] < previous) or np.any(
                block[1:] < block[:-1]
            ):
                raise ValueError(_unsorted(stream, recording, path))
            previous = block[-1]
            # sorted blocks: the rows before a time are the sum over blocks
            lo += np.searchsorted(block, starts, side="left")
            hi += np.searchsorted(block, stops, side="right")
    return lo, hi


def _read_rows(path: Path, rows: tuple[int, int]) -> xr.Dataset:
    """Rows ``first:stop`` of a netCDF file, decoded, with their indexes."""
    with _NETCDF_LOCK, _open_unindexed(path) as ds:
        part = ds.isel(time=slice(*rows)).load()
    for name in part.dims:
        if name in part.coords and name not in part.indexes:
            part = part.set_xindex(name)
    return part


def _load_path(stream: str, path: Path, span: slice) -> dict[str, xr.Dataset]:
    if _is_bag(path):
        reader = RosbagReader(path)
        with _NETCDF_LOCK:
            datasets = {
                topic.strip("/").replace("/", "_"): reader.load_dataset(topic)
                for topic, msgtype in reader.get_topics_and_types().items()
                if msgtype in POSE_MESSAGE_TYPES
            }
        return {k: ds.sel(time=span) for k, ds in datasets.items()}
    with _NETCDF_LOCK, xr.open_dataset(path) as ds:
        return {stream: ds.sel(time=span).load()}


def find_sources(
    source: Any, streams: Iterable[str] | None = None
) -> list[RecordingSource]:
    """The recordings a user pointed at, sorted by name.

    ``source`` is one of

    - a folder whose sub-folders are recordings, each holding one ``.nc``
      file (or bag) per stream, named after the stream (``head.nc``);
    - a folder of ``.nc`` files, each a recording of one stream;
    - a sequence of Datasets (each a one-stream recording, named ``rec000``,
      ...) or a mapping of names to Datasets or to mappings of streams.

    ``streams`` keeps only the named streams (every one must be present).
    """
    wanted = None if streams is None else tuple(streams)
    if isinstance(source, (str, os.PathLike)):
        found = _from_folder(Path(source))
    elif isinstance(source, Mapping):
        found = [_in_memory(str(name), value) for name, value in source.items()]
    elif isinstance(source, Iterable):
        found = [_in_memory(f"rec{k:03d}", ds) for k, ds in enumerate(source)]
    else:
        raise TypeError(
            "source must be a folder, a sequence of Datasets or a mapping of "
            f"names to Datasets, got {type(source).__name__}"
        )
    if not found:
        raise ValueError(f"source {source!r} holds no recordings")
    names = [s.name for s in found]
    duplicates = sorted({n for n in names if names.count(n) > 1})
    if duplicates:
        raise ValueError(f"recording names must be unique; repeated: {duplicates}")
    if wanted is not None:
        found = [_keep_streams(s, wanted) for s in found]
    return sorted(found, key=lambda s: s.name)


def _from_folder(folder: Path) -> list[RecordingSource]:
    if not folder.is_dir():
        raise FileNotFoundError(f"source folder {folder} does not exist")
    files = sorted(p for p in folder.iterdir() if p.suffix in STREAM_SUFFIXES)
    subfolders = sorted(
        p for p in folder.iterdir() if p.is_dir() and not p.name.startswith(".")
    )
    if files and subfolders:
        raise ValueError(
            f"{folder} mixes recording files ({files[0].name}, ...) and "
            f"sub-folders ({subfolders[0].name}, ...): use one layout"
        )
    if files:
        return [RecordingSource(p.stem, paths={p.stem: p}) for p in files]
    sources = []
    for sub in subfolders:
        paths = {
            p.stem: p for p in sorted(sub.iterdir()) if p.suffix in STREAM_SUFFIXES
        }
        if paths:
            sources.append(RecordingSource(sub.name, paths=paths))
    return sources


def _in_memory(name: str, value: Any) -> RecordingSource:
    if isinstance(value, xr.Dataset):
        return RecordingSource(name, datasets={"data": value})
    if isinstance(value, Mapping) and all(
        isinstance(v, xr.Dataset) for v in value.values()
    ):
        return RecordingSource(name, datasets=dict(value))
    raise TypeError(
        f"recording {name!r} must be a Dataset or a mapping of stream names to "
        f"Datasets, got {type(value).__name__}"
    )


def _keep_streams(source: RecordingSource, wanted: tuple[str, ...]) -> RecordingSource:
    have = set(source.paths) | set(source.datasets)
    missing = [s for s in wanted if s not in have]
    if missing:
        raise ValueError(
            f"recording {source.name!r} lacks stream(s) {missing}; it has {sorted(have)}"
        )
    return RecordingSource(
        source.name,
        paths={k: v for k, v in source.paths.items() if k in wanted},
        datasets={k: v for k, v in source.datasets.items() if k in wanted},
    )
