"""tf in bags: /tf and /tf_static read, written and loaded as whole trees.

The bags are written here with rosbags' own writers and serializers (ROS1 and
ROS2), independently of rbm_nb's writer, then read with rbm_nb.
"""

from __future__ import annotations

import numpy as np
import pytest
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

import rbm_nb as rbm
from rbm_nb.io import FileFormatError
from rbm_nb.ros import (
    RosbagReader,
    RosbagWriter,
    Transformer,
    load_tf_tree,
    register_frames_from_bag,
)

T0 = 1_600_000_000 * 10**9  # ns


def _unit(rng, n):
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def hamilton(p, q):
    pw, px, py, pz = p
    qw, qx, qy, qz = q
    return np.array(
        [
            pw * qw - px * qx - py * qy - pz * qz,
            pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx,
            pw * qz + px * qy - py * qx + pz * qw,
        ]
    )


def rotate(q, v):
    return hamilton(hamilton(q, np.r_[0.0, v]), q * [1, -1, -1, -1])[1:]


@pytest.fixture(scope="module")
def content():
    """map -> odom (moving), odom -> base_link (moving), base_link -> camera,
    base_link -> imu (static), all with random signs of w."""
    rng = np.random.default_rng(3)
    n = 12
    stamps = T0 + np.arange(n) * 100_000_000  # 10 Hz
    return {
        "stamps": stamps,
        ("map", "odom"): (rng.normal(size=(n, 3)), _unit(rng, n)),
        ("odom", "base_link"): (rng.normal(size=(n, 3)), _unit(rng, n)),
        ("base_link", "camera"): (rng.normal(size=3), _unit(rng, 1)[0]),
        ("base_link", "imu"): (rng.normal(size=3), _unit(rng, 1)[0]),
    }


def _msg(store, stamp, parent, child, t, q, ros1):
    types = store.types
    time = types["builtin_interfaces/msg/Time"](
        sec=int(stamp // 10**9), nanosec=int(stamp % 10**9)
    )
    header_type = types["std_msgs/msg/Header"]
    header = (
        header_type(seq=0, stamp=time, frame_id=parent)
        if ros1
        else header_type(stamp=time, frame_id=parent)
    )
    return types["geometry_msgs/msg/TransformStamped"](
        header=header,
        child_frame_id=child,
        transform=types["geometry_msgs/msg/Transform"](
            translation=types["geometry_msgs/msg/Vector3"](x=t[0], y=t[1], z=t[2]),
            rotation=types["geometry_msgs/msg/Quaternion"](
                x=q[1], y=q[2], z=q[3], w=q[0]
            ),
        ),
    )


def _write_with_rosbags(path, content, ros1: bool):
    """/tf_static twice (latched re-send), /tf with two transforms per message
    (and the last stamp's odom -> base_link alone in a message of its own)."""
    if ros1:
        from rosbags.rosbag1 import Writer

        store = get_typestore(Stores.ROS1_NOETIC)
        store.register(
            get_types_from_msg(
                "geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage"
            )
        )
        writer = Writer(path)
        serialize = store.serialize_ros1
    else:
        from rosbags.rosbag2 import Writer

        store = get_typestore(Stores.ROS2_HUMBLE)
        writer = Writer(path, version=Writer.VERSION_LATEST)
        serialize = store.serialize_cdr
    tf_type = "tf2_msgs/msg/TFMessage"
    TF = store.types[tf_type]
    stamps = content["stamps"]
    with writer:
        static = writer.add_connection("/tf_static", tf_type, typestore=store)
        dynamic = writer.add_connection("/tf", tf_type, typestore=store)
        statics = [
            _msg(store, stamps[0], p, c, *content[(p, c)], ros1)
            for p, c in (("base_link", "camera"), ("base_link", "imu"))
        ]
        for stamp in (stamps[0], stamps[5]):
            writer.write(
                static, int(stamp), bytes(serialize(TF(transforms=statics), tf_type))
            )
        for i, stamp in enumerate(stamps):
            msgs = [
                _msg(
                    store,
                    stamp,
                    p,
                    c,
                    content[(p, c)][0][i],
                    content[(p, c)][1][i],
                    ros1,
                )
                for p, c in (("map", "odom"), ("odom", "base_link"))
            ]
            if i == len(stamps) - 1:
                for m in msgs:
                    writer.write(
                        dynamic,
                        int(stamp),
                        bytes(serialize(TF(transforms=[m]), tf_type)),
                    )
            else:
                writer.write(
                    dynamic, int(stamp), bytes(serialize(TF(transforms=msgs), tf_type))
                )


@pytest.fixture(params=["ros1", "ros2"])
def tf_bag(request, tmp_path, content):
    path = tmp_path / ("tf.bag" if request.param == "ros1" else "tf_ros2")
    _write_with_rosbags(path, content, request.param == "ros1")
    return path


def test_reader_splits_every_transform_per_pair(tf_bag, content):
    with RosbagReader(tf_bag) as reader:
        assert reader.get_topics_and_types() == {
            "/tf": "tf2_msgs/TFMessage",
            "/tf_static": "tf2_msgs/TFMessage",
        }
        pairs = reader.load_tf()
        with pytest.raises(ValueError, match="load_tf"):
            reader.load_messages("/tf")
    assert set(pairs) == {k for k in content if k != "stamps"}
    for key in (("map", "odom"), ("odom", "base_link")):
        pair = pairs[key]
        assert not pair.static
        np.testing.assert_array_equal(pair.stamps_ns, content["stamps"])
        np.testing.assert_array_equal(pair.position, content[key][0])
        np.testing.assert_array_equal(pair.orientation, content[key][1])
    assert pairs[("odom", "base_link")].message_index[-1] == 12  # in a message alone
    for key in (("base_link", "camera"), ("base_link", "imu")):
        pair = pairs[key]
        assert pair.static and len(pair.stamps_ns) == 1  # sent twice, kept once
        np.testing.assert_array_equal(pair.position[0], content[key][0])
        np.testing.assert_array_equal(pair.orientation[0], content[key][1])


def _expected_camera_in_map(content, i):
    """camera -> map by explicit composition of the stored transforms."""
    t_mo, q_mo = content[("map", "odom")][0][i], content[("map", "odom")][1][i]
    t_ob, q_ob = (
        content[("odom", "base_link")][0][i],
        content[("odom", "base_link")][1][i],
    )
    t_bc, q_bc = content[("base_link", "camera")]
    q = hamilton(q_mo, hamilton(q_ob, q_bc))
    t = t_mo + rotate(q_mo, t_ob + rotate(q_ob, t_bc))
    return t, q


def test_transformer_from_bag(tf_bag, content):
    tf = Transformer.from_bag(tf_bag)
    assert set(tf.frames) == {"map", "odom", "base_link", "camera", "imu"}
    for i in (0, 4, 11):
        when = content["stamps"][i] / 1e9
        t, q = _expected_camera_in_map(content, i)
        got_t, got_q = tf.lookup_transform("map", "camera", when)
        np.testing.assert_allclose(got_t, t, atol=1e-9)
        np.testing.assert_allclose(got_q, q, atol=1e-12)  # tf2's sign too
    # the latest common time is the last stamp
    np.testing.assert_allclose(
        tf.lookup_transform("map", "camera")[0],
        _expected_camera_in_map(content, 11)[0],
        atol=1e-9,
    )


def test_register_frames_from_bag(tf_bag, content):
    names = register_frames_from_bag(tf_bag)
    assert names[0] == "map" and set(names) == {
        "map",
        "odom",
        "base_link",
        "camera",
        "imu",
    }
    assert names.index("odom") < names.index("base_link") < names.index("camera")
    assert rbm.registry["camera"].timestamps is None
    assert rbm.registry["odom"].timestamps.dtype == np.dtype("datetime64[ns]")
    t, q = rbm.lookup_transform("camera", "map", as_dataset=False)
    for i in (0, 7):
        et, eq = _expected_camera_in_map(content, i)
        np.testing.assert_allclose(t[i], et, atol=1e-9)
        assert min(np.abs(q[i] - eq).max(), np.abs(q[i] + eq).max()) < 1e-12
    # all or nothing: a second call refuses and changes nothing
    before = dict(rbm.registry)
    with pytest.raises(ValueError, match="registered already"):
        register_frames_from_bag(tf_bag)
    assert dict(rbm.registry) == before
    assert register_frames_from_bag(tf_bag, update=True) == names[1:]  # map exists


@pytest.mark.parametrize("suffix", [".bag", "_ros2"])
def test_writer_writes_tf_that_rosbags_and_the_reader_read(tmp_path, content, suffix):
    path = tmp_path / f"out{suffix}"
    stamps = content["stamps"]
    with RosbagWriter(path) as writer:
        for key in (("map", "odom"), ("odom", "base_link")):
            writer.write_tf(stamps.astype("datetime64[ns]"), *content[key], *key)
        writer.write_tf_message(
            [
                (stamps[0] / 1e9, "base_link", child, *content[("base_link", child)])
                for child in ("camera", "imu")
            ],
            static=True,
        )
    pairs = RosbagReader(path).load_tf()
    for key, value in content.items():
        if key == "stamps":
            continue
        np.testing.assert_array_equal(
            pairs[key].position.reshape(-1, 3), np.reshape(value[0], (-1, 3))
        )
        np.testing.assert_array_equal(
            pairs[key].orientation.reshape(-1, 4), np.reshape(value[1], (-1, 4))
        )
    np.testing.assert_array_equal(pairs[("map", "odom")].stamps_ns, stamps)
    # rosbags' own reader and deserializer agree
    from rosbags.highlevel import AnyReader

    with AnyReader([path]) as reader:
        conn = [c for c in reader.connections if c.topic == "/tf_static"]
        (msg,) = [
            reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages(conn)
        ]
        assert [t.child_frame_id for t in msg.transforms] == ["camera", "imu"]
        assert (
            msg.transforms[1].transform.rotation.w
            == content[("base_link", "imu")][1][0]
        )
    # and the whole tree loads
    tf = Transformer.from_bag(path)
    np.testing.assert_allclose(
        tf.lookup_transform("map", "camera", stamps[3] / 1e9)[1],
        _expected_camera_in_map(content, 3)[1],
        atol=1e-12,
    )


def test_tf_errors(tmp_path, content):
    path = tmp_path / "bad.bag"
    stamps = content["stamps"] / 1e9
    with RosbagWriter(path) as writer:
        writer.write_tf(stamps, *content[("map", "odom")], "map", "odom")
        writer.write_tf(stamps, *content[("odom", "base_link")], "world", "odom")
        writer.write_transform_stamped(
            stamps, *content[("map", "odom")], "/pose", "map", "x"
        )
    with pytest.raises(ValueError, match="'odom' has two parents"):
        Transformer.from_bag(path)
    with pytest.raises(ValueError, match="not a tf message type"):
        RosbagReader(path).load_tf(["/pose"])
    with pytest.raises(ValueError, match="'/nope' is not in"):
        RosbagReader(path).load_tf(["/nope"])
    with RosbagWriter(tmp_path / "none.bag") as writer:
        writer.write_transform_stamped(
            stamps, *content[("map", "odom")], "/pose", "map", "x"
        )
    with pytest.raises(ValueError, match="no /tf or /tf_static"):
        register_frames_from_bag(tmp_path / "none.bag")
    with pytest.raises(ValueError, match="strictly increasing"):
        with RosbagWriter(tmp_path / "x.bag") as writer:
            writer.write_tf(stamps[::-1], *content[("map", "odom")], "map", "odom")
    with pytest.raises(ValueError, match="at least one transform"):
        with RosbagWriter(tmp_path / "y.bag") as writer:
            writer.write_tf_message([])


def test_damaged_tf_quaternion_names_topic_and_message(tmp_path, content):
    """A non-unit quaternion in a tf message (written raw with rosbags)."""
    bad = {**content}
    q = content[("map", "odom")][1].copy()
    q[4] *= 1.5
    bad[("map", "odom")] = (content[("map", "odom")][0], q)
    path = tmp_path / "damaged.bag"
    _write_with_rosbags(path, bad, ros1=True)
    with pytest.raises(
        FileFormatError, match=r"topic '/tf' \(map -> odom\): message 4 has orientation"
    ):
        load_tf_tree(path)
