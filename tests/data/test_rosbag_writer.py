"""RosbagWriter: exact round trips, rosbags-identical bytes, atomic writes, bad input."""

from __future__ import annotations

import hashlib

import numpy as np
import pytest
import xarray as xr

from rbm_nb.ros import RosbagReader, RosbagWriter
from rbm_nb.ros import _messages as messages

TARGETS = {
    "ros1": ("walk.bag", {}),
    "sqlite3": ("walk_sqlite3", {}),
    "mcap": ("walk_mcap", {"storage": "mcap"}),
}


def _motion(n: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    t = 1_580_603_231.0 + np.cumsum(rng.uniform(0.001, 0.01, n))
    translation = rng.normal(0.0, 10.0, (n, 3))
    rotation = rng.normal(size=(n, 4))
    rotation /= np.linalg.norm(rotation, axis=1, keepdims=True)
    return t, translation, rotation


def _digest(path) -> str:
    files = sorted(path.rglob("*")) if path.is_dir() else [path]
    h = hashlib.sha256()
    for f in files:
        if f.is_file():
            h.update(f.name.encode() + f.read_bytes())
    return h.hexdigest()


@pytest.mark.parametrize("kind", sorted(TARGETS))
def test_round_trip_is_exact(tmp_path, kind):
    name, options = TARGETS[kind]
    t, translation, rotation = _motion(500)
    with RosbagWriter(tmp_path / name, **options) as writer:
        writer.write_transform_stamped(
            t, translation, rotation, "/head", "world", "head"
        )
    with RosbagReader(tmp_path / name) as reader:
        assert reader.get_topics_and_types() == {
            "/head": "geometry_msgs/TransformStamped"
        }
        loaded = reader.load_messages("/head")
        ds = reader.load_dataset("/head")
    # float seconds -> (sec, nsec) -> float seconds gives back the same doubles
    np.testing.assert_array_equal(loaded["timestamps"], t)
    np.testing.assert_array_equal(loaded["position"], translation)
    np.testing.assert_array_equal(loaded["orientation"], rotation)
    assert ds.attrs["frame_id"] == "world" and ds.attrs["child_frame_id"] == "head"


@pytest.mark.parametrize("kind", sorted(TARGETS))
def test_dataset_round_trip_keeps_nanoseconds(tmp_path, kind):
    name, options = TARGETS[kind]
    t, translation, rotation = _motion(300, seed=1)
    time = np.datetime64("2020-02-02T00:27:14.300365210", "ns") + np.arange(
        300
    ) * np.timedelta64(4_999_999, "ns")
    ds = xr.Dataset(
        {
            "position": (("time", "cartesian_axis"), translation),
            "orientation": (("time", "quaternion_axis"), rotation),
        },
        coords={"time": time},
    )
    with RosbagWriter(tmp_path / name, **options) as writer:
        writer.write_transform_stamped_dataset(
            ds, "/t265/transform", "t265/world", "t265/tracker"
        )
    back = RosbagReader(tmp_path / name).load_dataset("/t265/transform")
    np.testing.assert_array_equal(back.time.values, time)
    np.testing.assert_array_equal(back.position.values, translation)
    np.testing.assert_array_equal(back.orientation.values, rotation)


def test_dataset_with_other_names_and_axis_order(tmp_path):
    t, translation, rotation = _motion(20, seed=2)
    ds = xr.Dataset(
        {
            "t": (("axis", "stamp"), translation.T),
            "r": (("stamp", "q"), rotation),
        },
        coords={"stamp": t},
    )
    with RosbagWriter(tmp_path / "x.bag") as writer:
        writer.write_transform_stamped_dataset(
            ds, "/x", "a", "b", timestamps="stamp", translation="t", rotation="r"
        )
    back = RosbagReader(tmp_path / "x.bag").load_messages("/x")
    np.testing.assert_array_equal(back["timestamps"], t)
    np.testing.assert_array_equal(back["position"], translation)


@pytest.mark.parametrize("cdr", [False, True], ids=["ros1", "cdr"])
@pytest.mark.parametrize(
    "frames", [("world", "head"), ("", "x"), ("/map", "a/much/longer/child")]
)
def test_encoding_matches_rosbags_serializer(cdr, frames):
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE if cdr else Stores.ROS1_NOETIC)
    types = store.types
    t, translation, rotation = _motion(7, seed=3)
    ns = np.round(t * 1e9).astype(np.int64)
    rows = messages.encode_transform_stamped(
        ns, translation, rotation, *frames, cdr=cdr
    )
    typename = "geometry_msgs/msg/TransformStamped"
    for i in range(len(t)):
        header = {
            "stamp": types["builtin_interfaces/msg/Time"](
                sec=int(ns[i] // 10**9), nanosec=int(ns[i] % 10**9)
            )
        }
        if not cdr:
            header["seq"] = i
        msg = types[typename](
            header=types["std_msgs/msg/Header"](frame_id=frames[0], **header),
            child_frame_id=frames[1],
            transform=types["geometry_msgs/msg/Transform"](
                translation=types["geometry_msgs/msg/Vector3"](*translation[i]),
                rotation=types["geometry_msgs/msg/Quaternion"](
                    x=rotation[i, 1],
                    y=rotation[i, 2],
                    z=rotation[i, 3],
                    w=rotation[i, 0],
                ),
            ),
        )
        expected = (
            store.serialize_cdr(msg, typename)
            if cdr
            else store.serialize_ros1(msg, typename)
        )
        assert rows[i].tobytes() == bytes(expected)
        # and rosbags reads our bytes back to the same numbers
        back = (
            store.deserialize_cdr(rows[i].tobytes(), typename)
            if cdr
            else store.deserialize_ros1(rows[i].tobytes(), typename)
        )
        assert back.transform.rotation.w == rotation[i, 0]
        assert back.child_frame_id == frames[1]


@pytest.mark.parametrize("kind", sorted(TARGETS))
def test_failure_leaves_existing_bag_untouched(tmp_path, kind):
    name, options = TARGETS[kind]
    target = tmp_path / name
    t, translation, rotation = _motion(50)
    with RosbagWriter(target, **options) as writer:
        writer.write_transform_stamped(t, translation, rotation, "/old", "a", "b")
    before = _digest(target)
    with pytest.raises(RuntimeError, match="crash"):
        with RosbagWriter(target, **options) as writer:
            writer.write_transform_stamped(
                t, translation + 1, rotation, "/new", "a", "b"
            )
            raise RuntimeError("crash in the middle")
    assert _digest(target) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]  # no temporary left
    assert RosbagReader(target).get_topics_and_types() == {
        "/old": "geometry_msgs/TransformStamped"
    }


@pytest.mark.parametrize("kind", sorted(TARGETS))
def test_success_replaces_existing_bag(tmp_path, kind):
    name, options = TARGETS[kind]
    target = tmp_path / name
    t, translation, rotation = _motion(50)
    for topic in ("/old", "/new"):
        with RosbagWriter(target, **options) as writer:
            writer.write_transform_stamped(t, translation, rotation, topic, "a", "b")
    assert RosbagReader(target).get_topics_and_types() == {
        "/new": "geometry_msgs/TransformStamped"
    }
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]


def test_failed_validation_writes_nothing(tmp_path):
    target = tmp_path / "never.bag"
    with pytest.raises(ValueError, match="translation"):
        with RosbagWriter(target) as writer:
            writer.write_transform_stamped(
                [1.0, 2.0],
                np.zeros((3, 3)),
                np.tile([1.0, 0, 0, 0], (2, 1)),
                "/x",
                "a",
                "b",
            )
    assert list(tmp_path.iterdir()) == []


def test_several_topics_and_calls_append(tmp_path):
    t, translation, rotation = _motion(40)
    with RosbagWriter(tmp_path / "multi.bag") as writer:
        writer.write_transform_stamped(
            t[:20], translation[:20], rotation[:20], "/a", "w", "a"
        )
        writer.write_transform_stamped(
            t[20:], translation[20:], rotation[20:], "/a", "w", "a"
        )
        writer.write_transform_stamped(t, translation, rotation, "/b", "w", "b")
    with RosbagReader(tmp_path / "multi.bag") as reader:
        np.testing.assert_array_equal(
            reader.load_messages("/a")["position"], translation
        )
        np.testing.assert_array_equal(reader.load_messages("/b")["timestamps"], t)


BAD_CALLS = [
    ({"timestamps": np.ones((2, 2))}, "one-dimensional"),
    ({"translation": np.zeros((3, 2))}, r"translation must have shape \(3, 3\)"),
    ({"rotation": np.zeros((3, 3))}, r"rotation must have shape \(3, 4\)"),
    (
        {"translation": [[0, 0, 0], [np.nan, 0, 0], [0, 0, 0]]},
        "topic '/x': translation row 1 .* all finite, or all NaN",
    ),
    (
        {"rotation": [[1, 0, 0, 0], [np.inf, 0, 0, 0], [1, 0, 0, 0]]},
        "topic '/x': rotation row 1 .* all finite, or all NaN",
    ),
    ({"timestamps": [2.0, 1.0, 3.0]}, "topic '/x'.*strictly increasing; stamp 1"),
    ({"timestamps": [1.0, 2.0, 2.0]}, "topic '/x'.*strictly increasing; stamp 2"),
    (
        {"rotation": [[1, 0, 0, 0], [2, 0, 0, 0], [1, 0, 0, 0]]},
        "unit quaternions.*row 1",
    ),
    ({"rotation": np.zeros((3, 4))}, "unit quaternions.*row 0"),
    ({"timestamps": [-1.0, 0.0, 1.0]}, "1970"),
    ({"timestamps": [0.0, np.inf, 1.0]}, "finite; index 1"),
    (
        {
            "timestamps": np.array(
                ["2020-01-01", "NaT", "2020-01-02"], dtype="datetime64[ns]"
            )
        },
        "NaT at index 1",
    ),
    ({"timestamps": ["a", "b", "c"]}, "float seconds or datetime64"),
    ({"topic": ""}, "topic must not be empty"),
    ({"frame": None}, "frame must be a str"),
]


@pytest.mark.parametrize("override, message", BAD_CALLS)
def test_bad_input(tmp_path, override, message):
    args = {
        "timestamps": [1.0, 2.0, 3.0],
        "translation": np.zeros((3, 3)),
        "rotation": np.tile([1.0, 0.0, 0.0, 0.0], (3, 1)),
        "topic": "/x",
        "frame": "a",
        "child_frame": "b",
    }
    args.update(override)
    with pytest.raises(ValueError, match=message):
        with RosbagWriter(tmp_path / "bad.bag") as writer:
            writer.write_transform_stamped(**args)
    assert list(tmp_path.iterdir()) == []


def test_timestamps_beyond_ros1_range(tmp_path):
    with pytest.raises(ValueError, match="bag format can hold"):
        with RosbagWriter(tmp_path / "late.bag") as writer:
            writer.write_transform_stamped(
                [2.0**32], np.zeros((1, 3)), [[1, 0, 0, 0]], "/x", "a", "b"
            )


def test_writing_outside_with_block_is_an_error(tmp_path):
    writer = RosbagWriter(tmp_path / "x.bag")
    with pytest.raises(RuntimeError, match="with block"):
        writer.write_transform_stamped(
            [1.0], np.zeros((1, 3)), [[1, 0, 0, 0]], "/x", "a", "b"
        )


def test_storage_options_are_checked(tmp_path):
    with pytest.raises(ValueError, match="ROS1"):
        RosbagWriter(tmp_path / "x.bag", storage="mcap")
    with pytest.raises(ValueError, match="storage must be one of"):
        RosbagWriter(tmp_path / "x", storage="zip")


def test_dataset_missing_variable_is_named(tmp_path):
    ds = xr.Dataset(
        {"position": (("time", "cartesian_axis"), np.zeros((2, 3)))},
        coords={"time": [1.0, 2.0]},
    )
    with pytest.raises(
        ValueError, match="rotation=.orientation. is not a variable or coordinate"
    ):
        with RosbagWriter(tmp_path / "x.bag") as writer:
            writer.write_transform_stamped_dataset(ds, "/x", "a", "b")
