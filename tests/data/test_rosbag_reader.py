"""RosbagReader on the real ROS1 recording, its ROS2 conversions and written bags.

``rosbags``' own deserializer is the oracle for every decoded value.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from rbm_nb.io import load_netcdf
from rbm_nb.ros import RosbagReader, RosbagWriter
from rbm_nb.ros import _messages as messages

ODOM = "/camera/odom/sample"
VICON = "/vicon/t265_tracker/t265_tracker"
COUNTS = {"/camera/accel/sample": 74, "/camera/gyro/sample": 231, ODOM: 228, VICON: 57}


@pytest.fixture(scope="module")
def ros1_bag(shared_data) -> Path:
    return shared_data / "test.bag"


def _convert(src: Path, dst: Path, storage: str) -> Path:
    from rosbags.convert import convert

    convert([src], dst, storage, 9, None, "none", None, None, [], [], [], [])
    return dst


@pytest.fixture(scope="module")
def ros2_bags(ros1_bag, tmp_path_factory) -> dict:
    """The real bag converted by rosbags' own converter, in both storages."""
    folder = tmp_path_factory.mktemp("ros2")
    return {
        storage: _convert(ros1_bag, folder / f"test_{storage}", storage)
        for storage in ("sqlite3", "mcap")
    }


def _oracle(bag: Path, topic: str) -> dict:
    """Every message of ``topic`` deserialized by rosbags, as arrays."""
    from rosbags.highlevel import AnyReader

    with AnyReader([bag]) as reader:
        conns = [c for c in reader.connections if c.topic == topic]
        msgs = [
            reader.deserialize(raw, c.msgtype)
            for c, _, raw in reader.messages(connections=conns)
        ]
    pose = [m.pose.pose if hasattr(m, "twist") else m.transform for m in msgs]
    out = {
        "timestamps": np.array(
            [m.header.stamp.sec + m.header.stamp.nanosec / 1e9 for m in msgs]
        ),
        "orientation": np.array(
            [(p.orientation if hasattr(p, "orientation") else p.rotation) for p in pose]
        ),
    }
    out["orientation"] = np.array([[q.w, q.x, q.y, q.z] for q in out["orientation"]])
    out["position"] = np.array(
        [
            [v.x, v.y, v.z]
            for v in (
                (p.position if hasattr(p, "position") else p.translation) for p in pose
            )
        ]
    )
    if msgs and hasattr(msgs[0], "twist"):
        out["linear_velocity"] = np.array(
            [
                [m.twist.twist.linear.x, m.twist.twist.linear.y, m.twist.twist.linear.z]
                for m in msgs
            ]
        )
        out["angular_velocity"] = np.array(
            [
                [
                    m.twist.twist.angular.x,
                    m.twist.twist.angular.y,
                    m.twist.twist.angular.z,
                ]
                for m in msgs
            ]
        )
    return out


def test_topics_and_types(ros1_bag):
    with RosbagReader(ros1_bag) as reader:
        assert reader.get_topics_and_types() == {
            "/camera/accel/sample": "sensor_msgs/Imu",
            "/camera/gyro/sample": "sensor_msgs/Imu",
            ODOM: "nav_msgs/Odometry",
            VICON: "geometry_msgs/TransformStamped",
        }


@pytest.mark.parametrize("topic", [ODOM, VICON])
def test_values_match_rosbags(ros1_bag, topic):
    with RosbagReader(ros1_bag) as reader:
        loaded = reader.load_messages(topic)
    expected = _oracle(ros1_bag, topic)
    assert sorted(loaded) == sorted(expected)
    assert len(loaded["timestamps"]) == COUNTS[topic]
    for key in expected:
        np.testing.assert_array_equal(loaded[key], expected[key], err_msg=key)


def test_real_values(ros1_bag):
    """A few numbers of the recording, as rosbags prints them."""
    with RosbagReader(ros1_bag) as reader:
        vicon = reader.load_messages(VICON)
        odom = reader.load_messages(ODOM)
    np.testing.assert_allclose(
        vicon["position"][0],
        [-1.0275484874791208, 1.356312360541053, 0.8057809045368314],
    )
    np.testing.assert_allclose(
        vicon["orientation"][0],
        [
            -0.39341607551869495,
            0.04762464788887069,
            -0.13051192100447118,
            0.9088026864576558,
        ],
    )
    assert vicon["timestamps"][0] == 1594684035 + 573823800 / 1e9
    np.testing.assert_allclose(
        odom["linear_velocity"][0],
        [0.005878002396214002, -0.010559991042574324, 0.008101067377562554],
    )
    # unit quaternions, 1.15 s of recording
    np.testing.assert_allclose(
        np.linalg.norm(odom["orientation"], axis=1), 1.0, atol=1e-6
    )
    assert 1.0 < odom["timestamps"][-1] - odom["timestamps"][0] < 1.3


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
@pytest.mark.parametrize("topic", [ODOM, VICON])
def test_ros2_conversions_load_the_same_arrays(ros1_bag, ros2_bags, storage, topic):
    expected = RosbagReader(ros1_bag).load_messages(topic)
    for path in (
        ros2_bags[storage],
        next(ros2_bags[storage].glob("*.db3" if storage == "sqlite3" else "*.mcap")),
    ):
        with RosbagReader(path) as reader:
            assert (
                reader.get_topics_and_types()[topic]
                == RosbagReader(ros1_bag).get_topics_and_types()[topic]
            )
            loaded = reader.load_messages(topic)
        assert sorted(loaded) == sorted(expected)
        for key in expected:
            np.testing.assert_array_equal(
                loaded[key], expected[key], err_msg=f"{path.name} {key}"
            )


@pytest.mark.parametrize("topic", [ODOM, VICON])
@pytest.mark.parametrize("storage", [None, "sqlite3", "mcap"])
def test_fast_path_equals_rosbags_deserializer(ros1_bag, ros2_bags, topic, storage):
    from rosbags.highlevel import AnyReader

    bag = ros1_bag if storage is None else ros2_bags[storage]
    with AnyReader([bag]) as reader:
        conns = [c for c in reader.connections if c.topic == topic]
        raws = [raw for _, _, raw in reader.messages(connections=conns)]
        name = messages.ros1_type_name(conns[0].msgtype)
        fast = messages.decode_raw(raws, messages.KINDS[name], reader.is2)
        slow = messages.decode_objects(
            [reader.deserialize(r, conns[0].msgtype) for r in raws], name
        )
    assert fast is not None, "the real bag's topics all share one layout"
    for field in (
        "sec",
        "nsec",
        "position",
        "orientation",
        "linear_velocity",
        "angular_velocity",
    ):
        np.testing.assert_array_equal(
            getattr(fast, field), getattr(slow, field), err_msg=field
        )
    assert (fast.frame_id, fast.child_frame_id) == (slow.frame_id, slow.child_frame_id)


def test_changing_frame_ids_take_the_general_path(tmp_path):
    t = np.arange(1.0, 7.0)
    rotation = np.tile([1.0, 0, 0, 0], (6, 1))
    with RosbagWriter(tmp_path / "frames.bag") as writer:
        writer.write_transform_stamped(
            t[:3], np.zeros((3, 3)), rotation[:3], "/x", "map", "a"
        )
        writer.write_transform_stamped(
            t[3:], np.ones((3, 3)), rotation[3:], "/x", "odom", "a"
        )
    ds = RosbagReader(tmp_path / "frames.bag").load_dataset("/x")
    assert ds.attrs["frame_id"] == "map, odom"
    np.testing.assert_array_equal(ds.position.values[:, 0], [0, 0, 0, 1, 1, 1])


def test_load_dataset(ros1_bag):
    with RosbagReader(ros1_bag) as reader:
        ds = reader.load_dataset(ODOM)
        raw = reader.load_messages(ODOM)
    assert dict(ds.sizes) == {"time": 228, "cartesian_axis": 3, "quaternion_axis": 4}
    assert ds.time.dtype == np.dtype("datetime64[ns]")
    assert list(ds.cartesian_axis.values) == ["x", "y", "z"]
    assert list(ds.quaternion_axis.values) == ["w", "x", "y", "z"]
    assert set(ds.data_vars) == {
        "position",
        "orientation",
        "linear_velocity",
        "angular_velocity",
    }
    assert ds.attrs["message_type"] == "nav_msgs/Odometry"
    assert (ds.attrs["frame_id"], ds.attrs["child_frame_id"]) == (
        "camera_odom_frame",
        "camera_pose_frame",
    )
    # time is exact to the ns of the header stamps, not rounded through floats
    first = np.datetime64(1594684035859086752, "ns")
    assert ds.time.values[0] == first
    np.testing.assert_allclose(
        (ds.time.values - first) / np.timedelta64(1, "s"),
        raw["timestamps"] - raw["timestamps"][0],
        atol=1e-6,
    )
    np.testing.assert_array_equal(ds.angular_velocity.values, raw["angular_velocity"])


def test_reader_works_without_with_block(ros1_bag):
    reader = RosbagReader(ros1_bag)
    assert len(reader.load_messages(VICON)["timestamps"]) == 57
    assert reader._reader is None  # closed again
    with reader:
        with pytest.raises(RuntimeError, match="already open"):
            reader.__enter__()


def test_cache_is_written_once_and_reused(ros1_bag, tmp_path):
    bag = Path(shutil.copy(ros1_bag, tmp_path / "copy.bag"))
    reader = RosbagReader(bag)
    ds = reader.load_dataset(VICON, cache=True)
    cache = tmp_path / "cache" / "_vicon_t265_tracker_t265_tracker.nc"
    assert reader.cache_file(VICON) == cache and cache.is_file()
    stamp = cache.stat().st_mtime_ns
    again = reader.load_dataset(VICON, cache=True)
    assert cache.stat().st_mtime_ns == stamp
    for name in ds.data_vars:
        np.testing.assert_array_equal(again[name].values, ds[name].values)
    np.testing.assert_array_equal(again.time.values, ds.time.values)
    assert sorted(p.name for p in (tmp_path / "cache").iterdir()) == [cache.name]


def test_cache_of_another_bag_is_rebuilt(ros1_bag, tmp_path):
    bag = tmp_path / "same_name.bag"
    with RosbagWriter(bag) as writer:
        writer.write_transform_stamped(
            [1.0, 2.0], np.zeros((2, 3)), [[1, 0, 0, 0]] * 2, VICON, "a", "b"
        )
    assert RosbagReader(bag).load_dataset(VICON, cache=True).sizes["time"] == 2
    shutil.copy(ros1_bag, bag)  # another recording under the same name
    assert RosbagReader(bag).load_dataset(VICON, cache=True).sizes["time"] == 57


def test_export(ros1_bag, tmp_path):
    bag = Path(shutil.copy(ros1_bag, tmp_path / "rec.bag"))
    reader = RosbagReader(bag)
    default = reader.export(ODOM)
    assert default == tmp_path / "rec.nc"
    chosen = reader.export(VICON, tmp_path / "out" / "vicon.nc")
    assert chosen.is_file()

    back = load_netcdf(default)
    ds = reader.load_dataset(ODOM)
    for name in ds.data_vars:  # lossless, unlike the reference's int32 encoding
        np.testing.assert_array_equal(back[name].values, ds[name].values)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out", "rec.bag", "rec.nc"]


def test_progress_bar_when_asked(ros1_bag, capsys):
    RosbagReader(ros1_bag).load_messages(ODOM, progress=True)
    assert ODOM in capsys.readouterr().err
    RosbagReader(ros1_bag).load_messages(ODOM)  # small topic: no bar by default
    assert ODOM not in capsys.readouterr().err


def test_large_topics_get_a_bar_by_default(tmp_path, capsys, monkeypatch):
    from rbm_nb.ros import reader as reader_module

    monkeypatch.setattr(reader_module, "LARGE_TOPIC", 10)
    with RosbagWriter(tmp_path / "x.bag") as writer:
        writer.write_transform_stamped(
            np.arange(1.0, 21.0),
            np.zeros((20, 3)),
            [[1, 0, 0, 0]] * 20,
            "/big",
            "a",
            "b",
        )
    RosbagReader(tmp_path / "x.bag").load_messages("/big")
    assert "/big" in capsys.readouterr().err
    RosbagReader(tmp_path / "x.bag").load_messages("/big", progress=False)
    assert "/big" not in capsys.readouterr().err


def test_pose_stamped_topics(tmp_path):
    """PoseStamped, written with rosbags itself (RosbagWriter writes transforms only)."""
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    T = store.types
    path = tmp_path / "pose.bag"
    with Writer(path) as writer:
        conn = writer.add_connection(
            "/pose", "geometry_msgs/msg/PoseStamped", typestore=store
        )
        for i in range(5):
            msg = T["geometry_msgs/msg/PoseStamped"](
                header=T["std_msgs/msg/Header"](
                    seq=i,
                    stamp=T["builtin_interfaces/msg/Time"](sec=10 + i, nanosec=5),
                    frame_id="map",
                ),
                pose=T["geometry_msgs/msg/Pose"](
                    position=T["geometry_msgs/msg/Point"](x=i, y=2.0, z=3.0),
                    orientation=T["geometry_msgs/msg/Quaternion"](
                        x=0.0, y=0.0, z=np.sin(i / 10), w=np.cos(i / 10)
                    ),
                ),
            )
            writer.write(
                conn,
                (10 + i) * 10**9,
                store.serialize_ros1(msg, "geometry_msgs/msg/PoseStamped"),
            )
    with RosbagReader(path) as reader:
        assert reader.get_topics_and_types() == {"/pose": "geometry_msgs/PoseStamped"}
        loaded = reader.load_messages("/pose")
    np.testing.assert_array_equal(loaded["position"][:, 0], np.arange(5.0))
    np.testing.assert_array_equal(
        loaded["orientation"][:, 0], np.cos(np.arange(5) / 10)
    )
    np.testing.assert_array_equal(loaded["timestamps"], 10 + np.arange(5) + 5e-9)
