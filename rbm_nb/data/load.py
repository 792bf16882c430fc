"""Example recordings by name: the real files when they can be had, else synthetic ones."""

from __future__ import annotations

import functools
import os
import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

from .._infra.frozen import freeze_dataset
from ..io._files import load_netcdf
from ..ros.writer import RosbagWriter
from .fetch import ExampleDataStore, ExampleDataUnavailable, cache_dir, example_data
from .synthetic import synthetic_head_eye

if TYPE_CHECKING:
    import xarray as xr

    from .synthetic import HeadEyeRecording

SOURCES = ("auto", "remote", "synthetic")
DATASETS = ("head", "left_eye", "right_eye")
# bump when the generator's output changes, so that cached bags are rebuilt
SYNTHETIC_VERSION = 4

# topic -> (recording part, frame, child frame), as in the real example bag
ROSBAG_TOPICS = {
    "/t265/transform": ("head", "t265/world", "t265/tracker"),
    "/pupil/left_eye/transform": ("left_eye", "pupil/scene_camera", "pupil/left_eye"),
    "/pupil/right_eye/transform": (
        "right_eye",
        "pupil/scene_camera",
        "pupil/right_eye",
    ),
}


class DataChoice(NamedTuple):
    """Which data :func:`load_example` gave for a name, and why.

    Attributes
    ----------
    name : str
        The dataset asked for ("head", "left_eye", ...).
    kind : {"real", "own", "synthetic"}
        The registered example file; a file of the same name in
        ``RBM_NB_DATA_DIR`` that is not the example (your own recording, same
        schema); or the synthetic stand-in.
    path : pathlib.Path or None
        The file read (None for synthetic data).
    reason : str
        One sentence: why this data and, for synthetic data, how to get the
        real one.
    """

    name: str
    kind: str
    path: Path | None
    reason: str


_CHOICES: dict[str, DataChoice] = {}
# what a recording of each name must have to be opened as your own
_SCHEMA = {
    "head": ("position", "orientation"),
    "left_eye": ("orientation",),
    "right_eye": ("orientation",),
}


def last_choice(name: str) -> DataChoice | None:
    """What the latest :func:`load_example` call for ``name`` gave, and why.

    None before the first call. The CLI and the explorer use it to say which
    data they show.
    """
    return _CHOICES.get(name)


def load_example(
    name: str,
    source: str = "auto",
    *,
    store: ExampleDataStore | None = None,
    seed: int = 0,
) -> xr.Dataset | Path:
    """Load an example recording.

    Parameters
    ----------
    name : {"head", "left_eye", "right_eye", "rosbag"}
        Which recording.
    source : {"auto", "remote", "synthetic"}, default "auto"
        "remote": the real file (downloaded if needed, see
        :data:`rbm_nb.example_data`); "synthetic": the synthetic stand-in
        (:func:`synthetic_head_eye`, 5.5 minutes); "auto": the real file if
        it can be had; else a file of the same name in ``RBM_NB_DATA_DIR``
        whose sha256 differs from the example's but that has the example's
        schema (your own recording: it is opened, and a ``UserWarning`` says
        so); else the synthetic one with a ``UserWarning`` naming the file
        that did not do and why. :func:`last_choice` tells which it was.
    store : ExampleDataStore, optional
        Where real files come from (default :data:`rbm_nb.example_data`).
        Nothing is written into its folder but the registry's files: the
        synthetic bag is built once into :func:`rbm_nb.data.fetch.cache_dir`
        (``RBM_NB_CACHE_DIR``).
    seed : int, default 0
        Seed of the synthetic recording.

    Returns
    -------
    xarray.Dataset or pathlib.Path
        The dataset, loaded into memory and read-only (frames then keep its
        arrays instead of copies; ``ds.copy(deep=True)`` is a writeable
        copy); for "rosbag" the path of the bag.

    Raises
    ------
    ExampleDataUnavailable
        With ``source="remote"``, if the real file cannot be had.
    rbm_nb.io.FileFormatError
        If a real file cannot be read as netCDF.
    """
    if name not in (*DATASETS, "rosbag"):
        raise ValueError(f"name must be one of {(*DATASETS, 'rosbag')}, got {name!r}")
    if source not in SOURCES:
        raise ValueError(f"source must be one of {SOURCES}, got {source!r}")
    store = example_data if store is None else store
    if source == "synthetic":
        _CHOICES[name] = DataChoice(
            name, "synthetic", None, "the synthetic recording was asked for"
        )
        return _synthetic(name, store, seed)
    try:
        path = store[name]
    except (ExampleDataUnavailable, ImportError) as err:
        if source == "remote":
            raise
        own = _own_recording(name, store)
        if isinstance(own, tuple):
            path, dataset = own
            reason = (
                f"{path} is not the example file (its sha256 differs) but has its "
                "schema, so it is opened as your own recording"
            )
            _CHOICES[name] = DataChoice(name, "own", path, reason)
            warnings.warn(f"{name}: {reason}.", UserWarning, stacklevel=2)
            return freeze_dataset(dataset)
        reason = f"The real {name} recording is unavailable, using the synthetic one instead. "
        reason += f"{own} " if own else ""
        reason += str(err)
        _CHOICES[name] = DataChoice(name, "synthetic", None, reason)
        warnings.warn(reason, UserWarning, stacklevel=2)
        return _synthetic(name, store, seed)
    _CHOICES[name] = DataChoice(name, "real", Path(path), "the registered example file")
    return path if name == "rosbag" else freeze_dataset(load_netcdf(path))


def _own_recording(name: str, store: ExampleDataStore):
    """(path, dataset) of a user's file standing in for ``name``, or why there is none.

    Only a file in the folder the store reads (``RBM_NB_DATA_DIR``) counts:
    the store has refused it as the example file, so it is the user's own.
    Returns "" when there is no such file, else a sentence naming it and
    saying why it cannot be opened.
    """
    if name not in _SCHEMA:
        return ""
    try:
        path = store.path(name)
    except (KeyError, ImportError):
        return ""
    if not path.is_file():
        return ""
    try:
        dataset = load_netcdf(path)
    except Exception as err:  # any reader error: say it, use synthetic data
        return f"{path} could not be read as netCDF ({err})."
    wanted = _SCHEMA[name]
    lacking = [v for v in wanted if v not in dataset or "time" not in dataset[v].dims]
    if lacking:
        return (
            f"{path} is not the example file and lacks the example's schema: "
            f"no {', '.join(repr(v) for v in lacking)} along 'time'."
        )
    return path, dataset


def _synthetic(name: str, store: ExampleDataStore, seed: int):
    if name == "rosbag":
        path = (
            cache_dir()
            / "synthetic"
            / f"example-synthetic-v{SYNTHETIC_VERSION}-seed{seed}.bag"
        )
        if not path.is_file():
            write_synthetic_rosbag(path, seed=seed)
        return path
    return freeze_dataset(getattr(_synthetic_recording(seed), name).copy(deep=True))


@functools.lru_cache(maxsize=2)
def _synthetic_recording(seed: int) -> HeadEyeRecording:
    return synthetic_head_eye(seed=seed)


def write_synthetic_rosbag(
    path: str | os.PathLike, duration: float = 330.0, seed: int = 0, **kwargs: Any
) -> Path:
    """Write the synthetic recording as a bag with the real example bag's topics.

    Topics ``/t265/transform`` (head in world), ``/pupil/left_eye/transform``
    and ``/pupil/right_eye/transform`` (eyes in the scene camera), all
    ``geometry_msgs/TransformStamped``; written atomically.

    Parameters
    ----------
    path : str or path-like
        Target; ``.bag`` makes a ROS1 bag, anything else a ROS2 bag folder.
    duration, seed, **kwargs
        Passed to :func:`synthetic_head_eye`.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    recording = synthetic_head_eye(duration, seed, **kwargs)
    with RosbagWriter(path) as writer:
        for topic, (part, frame, child) in ROSBAG_TOPICS.items():
            writer.write_transform_stamped_dataset(
                getattr(recording, part), topic, frame, child
            )
    return Path(path)
