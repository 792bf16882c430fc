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
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import xarray as xr

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
        self, chunks: Any = None, start: Any = None, stop: Any = None
    ) -> Recording:
        """Load the streams, restricted to ``start <= time <= stop`` if given.

        Files are read into memory (only the selected span) and closed; with
        ``chunks`` the loaded streams are then made dask-backed, so that an
        analysis written with rbm_nb's lazy functions computes chunk by chunk.
        """
        span = slice(start, stop)
        streams: dict[str, xr.Dataset] = {}
        for stream, path in self.paths.items():
            streams.update(_load_path(stream, path, span))
        for stream, ds in self.datasets.items():
            streams[stream] = ds.sel(time=span) if span != slice(None) else ds
        if chunks is not None:
            streams = {k: ds.chunk(chunks) for k, ds in streams.items()}
        return Recording(self.name, streams)

    def time_range(self) -> tuple[Any, Any]:
        """First and last timestamp over all streams, reading only time coordinates."""
        if not self.paths:
            return Recording(self.name, dict(self.datasets)).time_range()
        firsts, lasts = [], []
        for stream, path in self.paths.items():
            if path.suffix == ".bag" or path.is_dir():
                first, last = Recording(
                    self.name, _load_path(stream, path, slice(None))
                ).time_range()
            else:
                with _NETCDF_LOCK, xr.open_dataset(path) as ds:
                    if "time" not in ds.coords or ds.sizes.get("time", 0) == 0:
                        raise ValueError(
                            f"stream {stream!r} of recording {self.name!r} ({path}) "
                            f"has no 'time' coordinate with samples"
                        )
                    first, last = ds.indexes["time"][0], ds.indexes["time"][-1]
            firsts.append(first)
            lasts.append(last)
        if self.datasets:
            first, last = Recording(self.name, dict(self.datasets)).time_range()
            firsts.append(first)
            lasts.append(last)
        return min(firsts), max(lasts)


def _load_path(stream: str, path: Path, span: slice) -> dict[str, xr.Dataset]:
    if path.suffix == ".bag" or path.is_dir():
        from ..ros import RosbagReader

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
