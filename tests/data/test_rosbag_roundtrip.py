"""Round trips of real data through rosbags, and where derived files go.

The eye recordings (real when ``../shared/data/rbm-data`` is there, else
synthetic) have NaN rows: the writer must write them and the reader read them
back bit for bit. Nothing but the registry's files is ever written into the
example-data folder.
"""

from __future__ import annotations

import shutil

import numpy as np
import pytest
from recordings import REAL_DIR, recording

from rbm_nb.ros import RosbagReader, RosbagWriter


def _bits(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float64).view(np.uint64)


@pytest.mark.parametrize("suffix", [".bag", "_ros2"])
def test_eye_recording_with_nan_rows_round_trips_bit_exact(tmp_path, suffix):
    head, left, right, source = recording()
    path = tmp_path / f"eyes{suffix}"
    topics = {"/pupil/left_eye/transform": left, "/pupil/right_eye/transform": right}
    with RosbagWriter(path) as writer:
        for topic, eye in topics.items():
            writer.write_transform_stamped_dataset(
                eye, topic, "pupil/scene_camera", topic.split("/")[2]
            )
    with RosbagReader(path) as reader:
        for topic, eye in topics.items():
            back = reader.load_dataset(topic)
            assert np.isnan(eye.orientation.values).any(), source
            np.testing.assert_array_equal(back.time.values, eye.time.values)
            for name in ("position", "orientation"):
                np.testing.assert_array_equal(
                    _bits(back[name].values),
                    _bits(eye[name].values),
                    err_msg=f"{topic} {name}",
                )


def test_real_example_bag_agrees_with_the_nc_files():
    """Where the real example.bag and the .nc files overlap, they agree."""
    bag = REAL_DIR / "example.bag"
    if not bag.is_file():
        pytest.skip(f"{bag} is not there (only the .nc files are shared)")
    import xarray as xr

    with RosbagReader(bag) as reader:
        for topic, name in (
            ("/t265/transform", "head"),
            ("/pupil/left_eye/transform", "left_eye"),
            ("/pupil/right_eye/transform", "right_eye"),
        ):
            from_bag = reader.load_dataset(topic)
            nc = xr.load_dataset(REAL_DIR / f"{name}.nc")
            common, i, j = np.intersect1d(
                from_bag.time.values, nc.time.values, return_indices=True
            )
            assert common.size > 0.5 * nc.sizes["time"]
            for var in ("position", "orientation"):
                # the .nc files store 4 decimals
                np.testing.assert_allclose(
                    from_bag[var].values[i], nc[var].values[j], atol=5.1e-5
                )


def test_reader_cache_of_a_bag_in_the_data_folder_goes_to_the_cache_folder(
    tmp_path, monkeypatch, shared_data
):
    data, cache = tmp_path / "data", tmp_path / "cache"
    data.mkdir()
    bag = shutil.copy(shared_data / "test.bag", data / "example.bag")
    monkeypatch.setenv("RBM_NB_DATA_DIR", str(data))
    monkeypatch.setenv("RBM_NB_CACHE_DIR", str(cache))
    reader = RosbagReader(bag)
    ds = reader.load_dataset("/camera/odom/sample", cache=True)
    assert sorted(p.name for p in data.iterdir()) == ["example.bag"]
    cached = reader.cache_file("/camera/odom/sample")
    assert cached.is_file() and cache in cached.parents
    # read from the cache the second time, same values
    again = reader.load_dataset("/camera/odom/sample", cache=True)
    np.testing.assert_array_equal(again.position.values, ds.position.values)


def test_reader_cache_of_another_bag_stays_beside_it(
    tmp_path, monkeypatch, shared_data
):
    """As in rigid-body-motion: cache/<topic>.nc next to a user's own bag."""
    monkeypatch.setenv("RBM_NB_DATA_DIR", str(tmp_path / "data"))
    monkeypatch.setenv("RBM_NB_CACHE_DIR", str(tmp_path / "derived"))
    bag = shutil.copy(shared_data / "test.bag", tmp_path / "mine.bag")
    RosbagReader(bag).load_dataset("/camera/odom/sample", cache=True)
    assert (tmp_path / "cache" / "_camera_odom_sample.nc").is_file()
    assert not (tmp_path / "data").exists() and not (tmp_path / "derived").exists()
