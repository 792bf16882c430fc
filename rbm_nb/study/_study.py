"""The :class:`Study`: one analysis mapped over many recordings with dask."""

from __future__ import annotations

import gc
import threading
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any

import xarray as xr

from .._infra.atomic import atomic_path, check_replaceable
from . import _windows
from ._sources import _NETCDF_LOCK, Recording, RecordingSource, find_sources

Analysis = Callable[..., Any]
FrameBuilder = Callable[[Recording], Mapping[str, Any]]


def open_study(
    source: Any,
    *,
    streams: Iterable[str] | None = None,
    chunks: Any = None,
) -> Study:
    """Open a collection of recordings for analysis; nothing is read yet.

    Parameters
    ----------
    source : path, sequence or mapping
        A folder of recording folders (each with one ``.nc`` file or bag per
        stream, e.g. ``head.nc``, ``left_eye.nc``), a folder of ``.nc`` files
        (one recording each), a sequence of Datasets, or a mapping of
        recording names to Datasets or to mappings of stream names to
        Datasets.
    streams : iterable of str, optional
        Keep only these streams; every recording must have them.
    chunks : int, dict or "auto", optional
        Make the streams dask-backed with these chunks once a task has read
        them, so that an analysis written with rbm_nb's lazy functions
        computes one chunk at a time. To bound what a task reads, use
        ``window=`` in :meth:`Study.map`. Default: NumPy arrays.

    Returns
    -------
    Study

    Examples
    --------
    >>> from rbm_nb.data import synthetic_head_eye
    >>> recs = {f"s{k}": dict(synthetic_head_eye(duration=20.0, seed=k)._asdict())
    ...         for k in range(2)}
    >>> study = open_study(recs, streams=["head"])
    >>> study.names
    ['s0', 's1']
    """
    return Study(find_sources(source, streams), chunks=chunks)


class Study:
    """Recordings analysed alike, in parallel, on the active dask scheduler.

    Each recording (or each time window of one, see :meth:`map`) is a task:
    it opens its files on the worker that runs it, builds its own frame tree
    with the ``frames`` function, runs the ``analysis`` and returns xarray
    results. The scheduler is whatever dask would use for ``dask.compute``:
    threads by default, a ``dask.distributed`` cluster when a ``Client``
    exists.

    Frame trees are per task: ``frames`` should return the frames as
    :class:`~rbm_nb.ReferenceFrame` objects linked by ``parent=`` objects,
    not register them by name, since tasks on threads share the registry.

    To run on an existing cluster, connect a ``distributed.Client(address)``
    first; its workers need rbm_nb (``rbm_nb[dask]``, the client's version),
    what the analysis imports, and the study's files at the same paths (see
    :mod:`rbm_nb.study`).
    """

    def __init__(self, sources: list[RecordingSource], *, chunks: Any = None):
        self._sources = {s.name: s for s in sources}
        self.chunks = chunks

    def __repr__(self) -> str:
        return f"<Study of {len(self)} recordings: {', '.join(self.names[:5])}{', ...' if len(self) > 5 else ''}>"

    def __len__(self) -> int:
        return len(self._sources)

    @property
    def names(self) -> list[str]:
        """Names of the recordings, sorted."""
        return list(self._sources)

    def open(self, name: str) -> Recording:
        """Open one recording here (to try an analysis before mapping it)."""
        try:
            source = self._sources[name]
        except KeyError:
            raise KeyError(
                f"no recording named {name!r}; the study has {self.names}"
            ) from None
        return source.open(self.chunks)

    def delayed(
        self,
        analysis: Analysis,
        *,
        frames: FrameBuilder | None = None,
        window: float | None = None,
        margin: float = 1.0,
    ) -> dict[str, Any]:
        """One :class:`dask.delayed.Delayed` result per recording, not computed.

        Arguments as for :meth:`map`; use this to combine the study's tasks
        with other dask work, or to compute them with your own options.
        """
        import dask

        _check_callable(analysis, "analysis")
        if frames is not None:
            _check_callable(frames, "frames")
        run = dask.delayed(_run_piece, pure=True)
        join = dask.delayed(_join_windows, pure=True)
        find_rows = dask.delayed(_window_rows, pure=True)
        # functions and in-memory sources go into the graph once, as keys
        analysis_key = dask.delayed(analysis, pure=True)
        frames_key = dask.delayed(frames, pure=True)
        results = {}
        for name, source in self._sources.items():
            source_key = dask.delayed(source, pure=True)
            if window is None:
                results[name] = run(
                    source_key, self.chunks, analysis_key, frames_key, None
                )
                continue
            # the span costs two values per file; the rows of every window
            # are found by one small task per recording (it reads each time
            # coordinate once, in blocks), so a window task reads its rows
            # and nothing else
            windows = _windows.split(*source.time_range(), window, margin)
            rows = find_rows(source_key, [(w.read_start, w.read_stop) for w in windows])
            pieces = [
                run(source_key, self.chunks, analysis_key, frames_key, w, rows, k)
                for k, w in enumerate(windows)
            ]
            results[name] = join(name, pieces)
        return results

    def map(
        self,
        analysis: Analysis,
        *,
        frames: FrameBuilder | None = None,
        window: float | None = None,
        margin: float = 1.0,
        combine: bool = True,
        progress: bool | None = None,
    ):
        """Run ``analysis`` on every recording and gather the results.

        Parameters
        ----------
        analysis : callable
            ``analysis(recording)`` or, with ``frames``,
            ``analysis(recording, frames)``, returning an xarray Dataset or
            DataArray (a dict of DataArrays or a number is made a Dataset).
        frames : callable, optional
            ``frames(recording) -> {name: ReferenceFrame}``: the recording's
            frame tree, built in the task that uses it.
        window : float, optional
            Cut each recording into windows of this many seconds, analysed
            as separate tasks; the analysis must return values over ``time``.
            Memory per task then depends on the window, not the recording.
        margin : float, default 1.0
            Seconds read beyond each window edge and trimmed afterwards; it
            must cover what the analysis looks at around a sample
            (interpolation neighbours, difference stencils, filter response).
        combine : bool, default True
            Concatenate the results along a new ``recording`` dimension
            (outer join on other coordinates); False returns a dict.
        progress : bool, optional
            Show a progress bar (default: when there are 4 tasks or more).

        Returns
        -------
        xarray.Dataset or xarray.DataArray or dict
        """
        results = self.delayed(analysis, frames=frames, window=window, margin=margin)
        computed = _compute(list(results.values()), progress)
        by_name = dict(zip(results, computed, strict=True))
        if not combine:
            return by_name
        return _concat_recordings(by_name)

    def to_netcdf(
        self,
        analysis: Analysis,
        folder: str | Path,
        *,
        frames: FrameBuilder | None = None,
        window: float | None = None,
        margin: float = 1.0,
        progress: bool | None = None,
    ) -> list[Path]:
        """Run ``analysis`` and write each recording's result to ``folder/<name>.nc``.

        The results are written by the tasks themselves (on the workers, into a
        folder they all reach), never gathered in this process. Each file is
        written atomically: an existing file is replaced only once the new
        one is complete.

        Returns
        -------
        list of pathlib.Path
            The files written, in the order of :attr:`names`.
        """
        import dask

        folder = Path(folder)
        for name in self.names:  # a folder at a target is refused before the work
            check_replaceable(folder / f"{name}.nc")
        folder.mkdir(parents=True, exist_ok=True)
        results = self.delayed(analysis, frames=frames, window=window, margin=margin)
        write = dask.delayed(_write_netcdf)
        tasks = [
            write(result, folder / f"{name}.nc") for name, result in results.items()
        ]
        return list(_compute(tasks, progress))


def _check_callable(value: Any, name: str) -> None:
    if not callable(value):
        raise TypeError(f"{name} must be callable, got {type(value).__name__}")


def _window_rows(source: RecordingSource, spans) -> list[dict[str, tuple[int, int]]]:
    return source.window_rows(spans)


def _run_piece(
    source: RecordingSource, chunks, analysis, frames, window, rows=None, k=0
):
    """Open, build frames, analyse and (for a window) trim: one task's work."""
    with _task_garbage:
        return _analyse_piece(source, chunks, analysis, frames, window, rows, k)


def _analyse_piece(source, chunks, analysis, frames, window, rows, k):
    if window is None:
        recording = source.open(chunks)
    else:
        recording = source.open(
            chunks, window.read_start, window.read_stop, rows=rows[k]
        )
    if frames is None:
        result = analysis(recording)
    else:
        result = analysis(recording, frames(recording))
    result = _as_xarray(result, recording.name)
    if window is not None:
        result = window.trim(result, recording.name)
    # compute chunk by chunk inside this task: parallelism is across tasks
    return result.compute(scheduler="synchronous")


class _TaskGarbage:
    """Frees the reference cycles a task leaves behind, scanning only the task's objects.

    A task's frame tree is a reference cycle (a parent lists its children),
    so its arrays -- the window's data -- are freed only by Python's cycle collector, whose full
    passes are rare in a process holding many long-lived objects (compiled
    kernels, dask, xarray): without help a worker's memory grows with the
    number of windows it has run. A full pass over everything takes about
    0.1 s in a worker, longer than a short window's task. So the objects
    that exist when the task starts are frozen (:func:`gc.freeze`), the
    pass after the task scans only what was created since, and they are
    unfrozen again. (The engine's cache of chains holds frame values, which
    form no cycle and go with the next frame built, not frames.) One task
    per process does this at a time, and only if nothing else has frozen
    objects (a freeze of others is never undone).
    """

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.owner: int | None = None

    def __enter__(self) -> _TaskGarbage:
        if gc.get_freeze_count() == 0 and self.lock.acquire(blocking=False):
            self.owner = threading.get_ident()
            gc.freeze()
        return self

    def __exit__(self, *exc: object) -> None:
        if self.owner != threading.get_ident():
            return
        try:
            gc.collect()
        finally:
            gc.unfreeze()
            self.owner = None
            self.lock.release()


_task_garbage = _TaskGarbage()


def _as_xarray(result: Any, name: str):
    if isinstance(result, (xr.Dataset, xr.DataArray)):
        return result
    if isinstance(result, Mapping):
        return xr.Dataset(dict(result))
    if isinstance(result, (int, float)):
        return xr.DataArray(result)
    raise TypeError(
        f"the analysis of recording {name!r} returned {type(result).__name__}; "
        f"it must return an xarray Dataset or DataArray, a dict or a number"
    )


def _join_windows(name: str, pieces: list):
    kept = [p for p in pieces if p.sizes.get("time", 0)]
    if not kept:
        raise ValueError(f"the analysis of recording {name!r} returned no samples")
    return xr.concat(kept, dim="time", data_vars="minimal", coords="minimal")


def _concat_recordings(results: Mapping[str, Any]):
    import numpy as np

    combined = xr.concat(
        list(results.values()),
        dim="recording",
        join="outer",
        combine_attrs="drop_conflicts",
    )
    # a plain unicode coordinate, whatever string dtype pandas would pick
    return combined.assign_coords(recording=np.array(list(results), dtype=str))


def _write_netcdf(result, path: Path) -> Path:
    # writing goes through HDF5 too: under the lock that keeps the tasks on
    # threads from reaching it at once (see _sources)
    with _NETCDF_LOCK, atomic_path(path) as tmp:
        result.to_netcdf(tmp)
    return path


def _active_client():
    """The dask.distributed Client dask would use, or None."""
    try:
        from distributed import default_client
    except ImportError:
        return None
    try:
        return default_client()
    except ValueError:
        return None


def _compute(tasks: list, progress: bool | None) -> list:
    import dask

    show = len(tasks) >= 4 if progress is None else progress
    client = _active_client()
    if client is not None:
        futures = client.compute(tasks)
        if show:
            from distributed import progress as distributed_progress

            distributed_progress(futures)
        return client.gather(futures)
    if show:
        from dask.diagnostics import ProgressBar

        with ProgressBar():
            return list(dask.compute(*tasks))
    return list(dask.compute(*tasks))
