"""Example recordings by name: the real files when they can be had, else synthetic ones."""

from __future__ import annotations

import functools
import os
import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..io._files import load_netcdf
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
        it can be had, else the synthetic one with a ``UserWarning`` saying so.
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
        The dataset, loaded into memory; for "rosbag" the path of the bag.

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
        return _synthetic(name, store, seed)
    try:
        path = store[name]
    except (ExampleDataUnavailable, ImportError) as err:
        if source == "remote":
            raise
        warnings.warn(
            f"The real {name} recording is unavailable, using the synthetic one instead. {err}",
            UserWarning,
            stacklevel=2,
        )
        return _synthetic(name, store, seed)
    return path if name == "rosbag" else load_netcdf(path)


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
    return getattr(_synthetic_recording(seed), name).copy(deep=True)


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
    from ..ros.writer import RosbagWriter

    recording = synthetic_head_eye(duration, seed, **kwargs)
    with RosbagWriter(path) as writer:
        for topic, (part, frame, child) in ROSBAG_TOPICS.items():
            writer.write_transform_stamped_dataset(
                getattr(recording, part), topic, frame, child
            )
    return Path(path)
