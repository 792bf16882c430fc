"""Scene logic without a browser: tracks, lowered commands, handles, publishers.

The commands are checked as the lowered msgpack the viewer would receive
(``scene.state``) and the messages the widget sends over the comm; the
browser side is covered in ``test_browser.py``.
"""

from __future__ import annotations

import threading

import ipywidgets
import numpy as np
import pytest
import umsgpack
from scipy.spatial.transform import Rotation

import rbm_nb as rbm
from rbm_nb.scene import FramePublisher, PathPublisher, Scene
from rbm_nb.scene.commands import (
    TransformPacker,
    color_int,
    meshcat_geometry,
    pose_matrix,
)
from rbm_nb.scene.tracks import PoseTrack

pytestmark = pytest.mark.usefixtures("recording_comm")


@pytest.fixture
def moving():
    """world -> body (moving, 11 samples at 0.1 s) -> eye (static); late (starts at 0.55)."""
    rbm.register_frame("world")
    ts = np.arange(11) * 0.1
    angle = np.linspace(0, np.pi, 11)
    rbm.register_frame(
        "body",
        parent="world",
        timestamps=ts,
        translation=np.c_[np.arange(11.0), np.zeros(11), np.ones(11)],
        rotation=np.c_[
            np.cos(angle / 2), np.zeros(11), np.zeros(11), np.sin(angle / 2)
        ],
    )
    rbm.register_frame("eye", parent="body", translation=(0.1, 0.0, 0.2))
    late_ts = 0.55 + np.arange(5) * 0.1
    rbm.register_frame(
        "late",
        parent="world",
        timestamps=late_ts,
        translation=np.c_[late_ts, late_ts, late_ts],
    )
    scene = Scene("world")
    yield scene
    scene.close()


def decode(messages):
    out = []
    for m in messages:
        if isinstance(m.data, bytes):
            out.append(umsgpack.unpackb(m.data))
        else:
            out.append({"type": "json", "path": m.path})
    return out


def transforms(scene):
    """Path -> 4x4 pose of every placed node, as a viewer shows it at the scene's time.

    Nodes hidden because their data has not started yet are left out.
    """
    t = scene._link.time_key()  # the time shown, as the scene's exact key
    if t is None:
        t = scene.state.span()[0] if scene.state.tracks else 0.0
    out = {}
    for path in [*scene.state.statics, *scene.state.tracks]:
        matrix = scene.state.pose_at(path, t)
        if matrix is not None:
            out[path] = matrix
    return out


def naive_matrix(t, q):
    m = np.eye(4)
    m[:3, :3] = Rotation.from_quat([q[1], q[2], q[3], q[0]]).as_matrix()
    m[:3, 3] = t
    return m


# -- commands and tracks ---------------------------------------------------------------
rng = np.random.default_rng(3)
RANDOM_POSES = [(rng.normal(size=3) * 10, rng.normal(size=4)) for _ in range(8)]


@pytest.mark.parametrize("t, q", RANDOM_POSES)
def test_pose_matrix_matches_naive_twin(t, q):
    np.testing.assert_allclose(
        pose_matrix(t, q), naive_matrix(t, q / np.linalg.norm(q)), atol=1e-12
    )


@pytest.mark.parametrize("t, q", RANDOM_POSES)
def test_transform_packer_is_byte_identical_to_meshcat(t, q):
    meshcat_geometry()  # imports meshcat quietly
    from meshcat.commands import SetTransform
    from meshcat.path import Path

    matrix = pose_matrix(t, q)
    expected = umsgpack.packb(
        SetTransform(matrix, Path(("rbm", "root", "x", "pose"))).lower()
    )
    assert TransformPacker("/rbm/root/x/pose").pack(matrix) == expected


def test_transform_packer_long_paths():
    path = "/rbm/root/" + "a" * 300
    decoded = umsgpack.unpackb(TransformPacker(path).pack(np.eye(4)))
    assert decoded["path"] == path and decoded["matrix"][0] == 1.0


@pytest.mark.parametrize(
    "t, expected",
    [(-1.0, -1), (0.0, 0), (0.05, 0), (0.1, 1), (0.95, 9), (1.0, 10), (5.0, 10)],
)
def test_track_picks_latest_sample_at_or_before(t, expected):
    ts = np.arange(11) * 0.1
    track = PoseTrack(np.zeros((11, 3)), np.tile([1.0, 0, 0, 0], (11, 1)), ts)
    assert track.index_at(t) == expected


def test_track_validates_shapes():
    with pytest.raises(ValueError, match=r"3 timestamps need translation \(3, 3\)"):
        PoseTrack(np.zeros((2, 3)), np.zeros((2, 4)), np.arange(3.0))
    with pytest.raises(ValueError, match="static pose"):
        PoseTrack(np.zeros((2, 3)), np.zeros(4))
    with pytest.raises(ValueError, match="static pose must not be NaN"):
        PoseTrack(np.array([np.nan, 0, 0]), np.array([1.0, 0, 0, 0]))
    with pytest.raises(ValueError, match="infinite"):
        PoseTrack(np.array([[np.inf, 0, 0]]), np.array([[1.0, 0, 0, 0]]), [0.0])


def test_missing_samples_hide_the_object():
    """A NaN row (no data at that sample, e.g. a blink) hides the node there."""
    t = np.array([[0.0, 0, 0], [1.0, 0, 0], [np.nan, 0, 0], [3.0, 0, 0]])
    r = np.tile([1.0, 0, 0, 0], (4, 1))
    r[1] = np.nan
    track = PoseTrack(t, r, np.arange(4.0))
    assert [track.missing(i) for i in range(4)] == [False, True, True, False]
    assert np.isnan(track.translation[1]).all() and np.isnan(track.rotation[2]).all()
    np.testing.assert_array_equal(track.positions(), [[0.0, 0, 0], [3.0, 0, 0]])


@pytest.mark.parametrize(
    "color, expected",
    [
        ("#ff00ff", 0xFF00FF),
        ("#f0f", 0xFF00FF),
        ("#ffffffff", 0xFFFFFF),
        (0x123456, 0x123456),
        ((1.0, 0.5, 0.0), 0xFF8000),
    ],
)
def test_color_parsing(color, expected):
    assert color_int(color) == expected


@pytest.mark.parametrize("color", ["red", "#12345", (2.0, 0, 0), -1, 0x1000000])
def test_bad_colors(color):
    with pytest.raises(ValueError, match="color"):
        color_int(color)


# -- scene objects --------------------------------------------------------------------
def test_objects_are_laid_out_under_rbm(moving):
    frame = moving.add_frame("body")
    path = moving.add_path("body", color="#ff00ff")
    vectors = moving.add_vectors("eye", (1, 0, 0), length=2)
    assert frame.name == "frame_body" and moving["frame_body"] is frame
    assert frame.geom_path == "/rbm/root/frame_body/pose/geom"
    objects = {
        c["path"]: c
        for c in decode(moving.state.snapshot())
        if c["type"] == "set_object"
    }
    grid = objects.pop("/rbm/grid")  # sized to the content, see test_grid_legend_labels
    assert grid["object"]["object"]["type"] == "LineSegments"
    assert set(objects) == {frame.geom_path, path.geom_path, vectors.geom_path}
    # segments: a path is broken where samples are missing (test_scene_path.py)
    assert objects[path.geom_path]["object"]["object"]["type"] == "LineSegments"
    assert objects[path.geom_path]["object"]["materials"][0]["color"] == 0xFF00FF
    assert objects[frame.geom_path]["object"]["object"]["type"] == "LineSegments"
    again = moving.add_frame("body")
    assert again.name == "frame_body_2"


def test_set_time_moves_everything_to_its_latest_sample(moving):
    frame = moving.add_frame("body")
    eye = moving.add_vectors("eye", (1, 0, 0))
    moving.set_time(0.57)
    poses = transforms(moving)
    t, r, ts = rbm.lookup_transform(outof="body", into="world", return_timestamps=True)
    np.testing.assert_allclose(
        poses[frame.pose_path], pose_matrix(t[5], r[5]), atol=1e-12
    )
    t, r, ts = rbm.lookup_transform(outof="eye", into="world", return_timestamps=True)
    np.testing.assert_allclose(
        poses[eye.pose_path], pose_matrix(t[5], r[5]), atol=1e-12
    )
    assert moving.time == pytest.approx(0.57)


def test_objects_are_hidden_before_their_data_starts(moving):
    late = moving.add_frame("late")
    moving.set_time(0.3)
    assert late.pose_path not in transforms(moving)  # hidden: nothing recorded yet
    assert moving.state.pose_at(late.pose_path, 0.6)[0, 3] == pytest.approx(0.55)
    assert moving.state.world_pose(late.geom_path, 0.3) is None


def test_timestamps_shared_or_a_grid(moving):
    moving.add_frame("body")
    moving.add_frame("eye")
    np.testing.assert_array_equal(moving.timestamps, np.arange(11) * 0.1)
    moving.add_frame("late")
    grid = moving.timestamps
    assert grid[0] == 0.0 and grid[-1] == pytest.approx(1.0)  # spans every object
    assert np.diff(grid).max() <= 0.1 + 1e-12


def test_datetime_scene():
    rbm.register_frame("world")
    ts = np.datetime64("2020-02-02T00:27:14.3") + np.arange(5) * np.timedelta64(
        100, "ms"
    )
    rbm.register_frame(
        "head",
        parent="world",
        timestamps=ts,
        translation=np.c_[np.arange(5.0), np.zeros(5), np.zeros(5)],
    )
    with Scene("world") as scene:
        handle = scene.add_frame("head")
        np.testing.assert_array_equal(scene.timestamps, ts)
        scene.set_time(ts[3] + np.timedelta64(50, "ms"))
        assert transforms(scene)[handle.pose_path][0, 3] == 3.0
        scene.publish(1)
        assert transforms(scene)[handle.pose_path][0, 3] == 1.0
        with pytest.raises(ValueError, match="plain seconds|datetime"):
            rbm.register_frame(
                "other",
                parent="world",
                timestamps=np.arange(3.0),
                translation=np.zeros((3, 3)),
            )
            scene.add_frame("other")


def test_handles_update_hide_and_remove(moving):
    frame = moving.add_frame("body", scale=0.5)
    frame.update(scale=2.0)
    obj = next(c for c in decode(moving.state.snapshot()) if c["type"] == "set_object")
    positions = np.frombuffer(
        obj["object"]["geometries"][0]["data"]["attributes"]["position"]["array"].data,
        np.float32,
    )
    assert positions.max() == 2.0
    frame.visible = False
    props = [
        c
        for c in decode(moving.state.snapshot())
        if c["type"] == "set_property" and c["path"] == frame.root_path
    ]
    assert props == [
        {
            "type": "set_property",
            "path": frame.root_path,
            "property": "visible",
            "value": False,
        }
    ]
    with pytest.raises(ValueError, match="unknown style"):
        frame.update(colour="red")
    with pytest.raises(ValueError, match="scale"):
        frame.update(scale=-1)
    frame.remove()
    frame.remove()
    assert (
        len(moving) == 0
        and [m for m in moving.state.snapshot()[1:] if m.path.startswith("/rbm/root")]
        == []
    )
    with pytest.raises(RuntimeError, match="removed"):
        frame.update(scale=1.0)


def test_objects_in_a_moving_base_hang_below_an_anchor(moving):
    eye_in_body = moving.add_vectors("eye", (1, 0, 0), base="body")
    assert eye_in_body.root_path.startswith("/rbm/anchor_body/")
    assert "/rbm/anchor_body" in moving.state.tracks
    moving.set_time(0.3)
    poses = transforms(moving)
    t, r, _ = rbm.lookup_transform(outof="body", into="world", return_timestamps=True)
    np.testing.assert_allclose(
        poses["/rbm/anchor_body"], pose_matrix(t[3], r[3]), atol=1e-12
    )
    np.testing.assert_allclose(poses[eye_in_body.pose_path][:3, 3], [0.1, 0.0, 0.2])
    eye_in_body.remove()
    assert "/rbm/anchor_body" not in moving.state.tracks  # unused anchors go too


def test_time_varying_vector_is_turned_and_scaled(moving):
    ts = np.array([0.0, 0.5])
    vecs = np.array([[0.0, 2.0, 0.0], [0.0, 0.0, -3.0]])
    handle = moving.add_vectors("world", vecs, timestamps=ts, origins=(1, 1, 1))
    track = moving.state.tracks[f"{handle.pose_path}/data"]
    for i in range(2):
        m = track.matrix(i)
        np.testing.assert_allclose(m[:3, :3] @ [1, 0, 0], vecs[i], atol=1e-12)
        np.testing.assert_allclose(m[:3, 3], [1, 1, 1])


def test_points_static_cloud_and_moving_marker(moving):
    cloud = moving.add_points(
        np.random.default_rng(0).normal(size=(7, 3)), frame="body", size=0.02
    )
    obj = next(
        c for c in decode(moving.state.snapshot()) if c["path"] == cloud.geom_path
    )
    assert obj["object"]["object"]["type"] == "Points"
    ts = np.array([0.0, 1.0])
    marker = moving.add_points([[0, 0, 0], [1, 2, 3]], timestamps=ts, color="#00ff00")
    moving.set_time(1.0)
    np.testing.assert_allclose(
        transforms(moving)[f"{marker.pose_path}/data"][:3, 3], [1, 2, 3]
    )


def test_meshes_primitives_and_files(moving, tmp_path):
    for mesh, size in (
        ("box", (0.1, 0.2, 0.3)),
        ("sphere", 0.1),
        ("cylinder", (0.2, 0.05)),
        ("ellipsoid", (1, 2, 3)),
    ):
        moving.add_mesh("body", mesh, size=size)
    obj = tmp_path / "tri.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    handle = moving.add_mesh(
        "body", obj, offset=(0, 0, 1), color="#ff0000", opacity=0.5
    )
    geometry = next(
        c for c in decode(moving.state.snapshot()) if c["path"] == handle.geom_path
    )["object"]
    assert geometry["geometries"][0]["format"] == "obj"
    np.testing.assert_allclose(transforms(moving)[handle.geom_path][:3, 3], [0, 0, 1])
    geometry_object = meshcat_geometry().Box([1, 1, 1])
    assert moving.add_mesh("body", geometry_object).mesh is geometry_object
    moving.fit_camera()  # every kind of mesh has an extent the camera can frame


@pytest.mark.parametrize(
    "mesh, size, message",
    [
        ("teapot", 0.1, "mesh must be one of"),
        ("sphere", (1, 2), "sphere needs size=radius"),
        ("box", (1, 2), "box needs"),
        ("cylinder", 1.0, "cylinder needs"),
        ("box", -1.0, "size must be positive"),
        ("missing.stl", 0.1, "does not exist"),
        (42, 0.1, "mesh must be one of"),
    ],
)
def test_bad_meshes(moving, mesh, size, message):
    with pytest.raises(ValueError, match=message):
        moving.add_mesh("body", mesh, size=size)


def test_highlight(moving):
    frame = moving.add_frame("body")
    moving.highlight("body")
    scale = [c for c in decode(moving.state.snapshot()) if c.get("property") == "scale"]
    assert scale == [
        {
            "type": "set_property",
            "path": frame.geom_path,
            "property": "scale",
            "value": [2.0, 2.0, 2.0],
        }
    ]
    moving.highlight("eye")
    assert "highlight_eye" in moving.handles
    moving.highlight(None)
    assert "highlight_eye" not in moving.handles


def test_camera_fits_the_objects(moving):
    moving.add_path("body")
    moving.fit_camera()
    data = moving.widget._camera
    np.testing.assert_allclose(data["target"], [5.0, 0.0, 1.0])
    assert np.linalg.norm(np.subtract(data["position"], data["target"])) > 5.0


# -- playback -------------------------------------------------------------------------
def test_player_drives_the_scene(moving):
    frame = moving.add_frame("body")
    player = moving.player()
    assert moving.widget.player is player  # the view follows it in the browser
    player.seek(7)
    assert moving.time == pytest.approx(0.7)
    np.testing.assert_allclose(transforms(moving)[frame.pose_path][0, 3], 7.0)
    moving.set_time(0.3)  # setting the scene's time moves its player
    assert player.index == 3
    player.close()


def test_frame_publisher_moves_only_its_frame(moving):
    pub = FramePublisher("body", scene=moving)
    assert pub.translation.shape == (11, 3)
    np.testing.assert_array_equal(pub.timestamps, np.arange(11) * 0.1)
    other = moving.add_frame("late")
    pub.publish(4)
    poses = transforms(moving)
    assert poses[pub.handle.pose_path][0, 3] == 4.0
    assert other.pose_path not in moving.state.pins  # untouched
    assert moving.widget._pins == {pub.handle.pose_path: pytest.approx(0.4)}
    pub.publish(0)  # index 0 is honoured (the reference treats it as "default")
    assert transforms(moving)[pub.handle.pose_path][0, 3] == 0.0
    with pytest.raises(IndexError, match="idx"):
        pub.publish(11)


def test_subscribed_publisher_follows_the_nearest_sample(moving):
    eye_ts = np.arange(0, 1.0, 0.03)
    rbm.register_frame(
        "pupil",
        parent="body",
        timestamps=eye_ts,
        translation=np.c_[eye_ts, 0 * eye_ts, 0 * eye_ts],
    )
    head = FramePublisher("body", scene=moving)
    eye = FramePublisher(
        "pupil", base="body", scene=moving, subscribe="body", pose_arrow=True
    )
    head.publish(5)  # t = 0.5: nearest eye sample 0.51 (index 17)
    pins = moving.state.pins
    assert pins[eye.handle.pose_path] == pytest.approx(0.51)
    assert pins[eye.pose_handle.pose_path] == pytest.approx(0.51)
    # the eye is drawn in the body frame, whose anchor moved with the head
    assert pins["/rbm/anchor_body"] == pytest.approx(0.5)


def test_publisher_spin_and_stop(moving):
    pub = FramePublisher("body", scene=moving)
    thread = pub.spin()
    assert isinstance(thread, threading.Thread)
    deadline = threading.Event()
    while pub.idx < 3 and not deadline.wait(0.01):
        pass
    pub.stop()
    assert not thread.is_alive() and pub.stopped
    path = PathPublisher("body", scene=moving, publish_interval=0.01)
    assert not path.handle.visible
    path.spin()
    path.stop()
    assert path.handle.visible
    # the body moves along a straight line: its two ends draw it exactly
    np.testing.assert_array_equal(path.points, path.translation[[0, -1]])


def test_ros_names_and_play_publisher(moving):
    broadcaster = rbm.ros.ReferenceFrameTransformBroadcaster(
        "body", base="world", scene=moving
    )
    broadcaster.publish()
    assert broadcaster.translation.shape == (11, 3)
    marker = rbm.ros.ReferenceFrameMarkerPublisher(
        "body", base="world", scene=moving, max_points=5
    )
    marker.publish()
    assert marker.topic == "/body/path" and len(marker.points) <= 6
    player = rbm.ros.play_publisher(broadcaster, step=2, speed=0.5)
    assert player.step == 2 and player.speed == 0.5
    player.seek(6)
    assert transforms(moving)[broadcaster.handle.pose_path][0, 3] == 6.0
    static = rbm.ros.ReferenceFrameTransformBroadcaster("eye", scene=moving)
    assert static.timestamps is None
    with pytest.raises(ValueError, match="no timestamps"):
        rbm.ros.play_publisher(static)
    player.close()


def test_default_scene_is_shared_and_recreated():
    from rbm_nb.scene import default_scene

    rbm.register_frame("world")
    ts = np.arange(3.0)
    rbm.register_frame(
        "body", parent="world", timestamps=ts, translation=np.zeros((3, 3))
    )
    pub = FramePublisher("body")
    assert pub.scene is default_scene()
    assert pub.scene.base is rbm.registry["world"]
    pub.scene.close()
    again = default_scene()
    assert again is not pub.scene
    rbm.clear_registry()
    rbm.register_frame("world")  # a new tree: the default scene follows it
    fresh = default_scene()
    assert again.closed and fresh.base is rbm.registry["world"]
    fresh.close()


# -- bad input -----------------------------------------------------------------------
def test_unknown_frame_names_list_close_ones(moving):
    with pytest.raises(
        ValueError, match="add_frame: frame: frame 'bdy' not found.*'body'"
    ):
        moving.add_frame("bdy")
    with pytest.raises(ValueError, match="base"):
        moving.add_frame("body", base="wrld")
    with pytest.raises(ValueError, match="Scene: base"):
        Scene("nowhere")


def test_path_of_a_static_frame(moving):
    with pytest.raises(ValueError, match="does not move"):
        moving.add_path("eye", base="body")


def test_empty_scene():
    rbm.register_frame("world")
    with Scene("world") as scene:
        assert scene.timestamps is None
        scene.publish()  # nothing moves: nothing to do
        scene.set_time(1.0)
        with pytest.raises(ValueError, match="no moving objects"):
            scene.player()
        with pytest.raises(ValueError, match="empty"):
            scene.to_html("unused.html")


def test_closed_scene_cannot_be_used(moving):
    handle = moving.add_frame("body")
    moving.close()
    moving.close()
    assert moving.closed and handle.removed
    for call in (
        lambda: moving.add_frame("body"),
        lambda: moving.set_time(0.0),
        lambda: moving.publish(0),
        lambda: moving.to_html("x.html"),
        lambda: moving.widget,
        lambda: moving.player(),
    ):
        with pytest.raises(RuntimeError, match="closed"):
            call()


def test_bad_vectors_and_points(moving):
    with pytest.raises(ValueError, match=r"vectors must have shape \(3,\) or \(n, 3\)"):
        moving.add_vectors("eye", [[1, 2]])
    with pytest.raises(ValueError, match="origins"):
        moving.add_vectors("eye", np.eye(3), origins=np.zeros((2, 3)))
    with pytest.raises(ValueError, match="length"):
        moving.add_vectors("eye", length=0)
    with pytest.raises(ValueError, match="points"):
        moving.add_points(np.zeros((0, 3)))
    with pytest.raises(ValueError, match="timestamps"):
        moving.add_points(np.zeros((3, 3)), timestamps=np.arange(2.0))


def test_guide_1_6_visualisation_cells_run_without_ros():
    """Cells [10]-[15] and [22]-[25] of the ROS guide, on a short synthetic recording."""
    from rbm_nb.data import synthetic_head_eye
    from rbm_nb.scene import default_scene

    recording = synthetic_head_eye(duration=20)
    # the frame tree of cells [5]-[8] and [18]-[20]
    r_t265_ros = np.array([[0.0, 0.0, -1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    r_pupil_ros = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]])
    rbm.register_frame("world")
    rbm.ReferenceFrame.from_rotation_matrix(
        r_t265_ros, parent="world", name="t265/world"
    ).register()
    rbm.ReferenceFrame.from_dataset(
        recording.head,
        "position",
        "orientation",
        "time",
        parent="t265/world",
        name="t265/tracker",
    ).register()
    rbm.ReferenceFrame.from_rotation_matrix(
        r_t265_ros, parent="t265/tracker", name="head", inverse=True
    ).register()
    rbm.register_frame(
        "pupil/scene_cam",
        parent="t265/tracker",
        translation=(24.5e-3, -29e-3, 0.0),
        rotation=(-0.00125, -1.0, 6.3463e-05, 3.977e-06),
    )
    rbm.ReferenceFrame.from_dataset(
        recording.left_eye,
        "position",
        "orientation",
        "time",
        parent="pupil/scene_cam",
        name="pupil/left_eye",
    ).register()
    rbm.ReferenceFrame.from_rotation_matrix(
        r_pupil_ros, parent="pupil/left_eye", name="left_eye"
    ).register(update=True)

    # the cells, as written in the guide
    master = rbm.ros.init_node("rbm_vis", start_master=True)
    tf_world_head = rbm.ros.ReferenceFrameTransformBroadcaster("head", base="world")
    tf_world_head.publish()
    assert tf_world_head.translation.shape == (4000, 3)
    tf_world_head.publish(1000)
    marker_publisher = rbm.ros.ReferenceFrameMarkerPublisher("head", base="world")
    marker_publisher.publish()
    tf_head_left_eye = rbm.ros.ReferenceFrameTransformBroadcaster(
        "left_eye", base="head", publish_pose=True, subscribe="head"
    )
    tf_head_left_eye.spin()
    player = rbm.ros.play_publisher(tf_world_head, step=2, speed=0.5)

    scene = default_scene()
    assert tf_world_head.scene is scene and tf_head_left_eye.scene is scene
    assert set(scene.handles) == {
        "frame_head",
        "path_head",
        "frame_left_eye",
        "pose_left_eye",
    }
    assert player.step == 2 and player.speed == 0.5
    player.seek(3000)  # the eye follows the head to the nearest of its own samples
    eye_keys = tf_head_left_eye._keys  # exact int64 ns of the eye's samples
    pinned = scene.state.pins[tf_head_left_eye.handle.pose_path]
    shown = int(np.datetime64(player.time_value, "ns").astype(np.int64))
    nearest = np.argmin(np.abs(eye_keys - shown))
    assert pinned == eye_keys[nearest]
    tf_head_left_eye.stop()
    player.close()
    master.shutdown()
    assert scene.closed


# -- the widget and its transport ---------------------------------------------------


def custom_messages(widget):
    return [
        (data["content"], buffers)
        for data, buffers in widget.comm.sent
        if data and data.get("method") == "custom"
    ]


def test_scene_is_a_dom_widget_for_layouts(moving):
    moving.add_frame("body")
    box = ipywidgets.HBox([moving.widget, ipywidgets.Label("x")])
    assert isinstance(moving.widget, ipywidgets.DOMWidget)
    assert box.children[0] is moving.widget
    assert "application/vnd.jupyter.widget-view+json" in moving._repr_mimebundle_()[0]
    # meshcat's own viewer is the 3D engine, inlined in the widget's module
    from rbm_nb.scene.commands import meshcat_js_path

    assert meshcat_js_path().read_text()[:2000] in moving.widget._esm


def test_content_goes_over_the_comm_after_ready(moving):
    frame = moving.add_frame("body")
    widget = moving.widget
    assert custom_messages(widget) == []  # nothing before the browser listens
    widget.comm.receive({"type": "ready"})
    [(content, buffers)] = custom_messages(widget)
    assert content["type"] == "snapshot"
    commands = [umsgpack.unpackb(b) for b in buffers[: content["commands"]]]
    assert commands[0] == {"type": "delete", "path": "/rbm"}
    assert {"set_object", "set_property"} <= {c["type"] for c in commands}
    [track] = content["tracks"]
    assert track["path"] == frame.pose_path and track["n"] == 11
    times = np.frombuffer(buffers[track["times"]], "<f8")
    xyz = np.frombuffer(buffers[track["translation"]], "<f4").reshape(-1, 3)
    xyzw = np.frombuffer(buffers[track["rotation"]], "<f4").reshape(-1, 4)
    np.testing.assert_allclose(times, np.arange(11) * 0.1)
    np.testing.assert_allclose(xyz[:, 0], np.arange(11.0))
    _, r = rbm.lookup_transform(outof="body", into="world")
    np.testing.assert_allclose(xyzw, r[:, [1, 2, 3, 0]], atol=1e-7)
    # later changes go as deltas: a restyle is one command, a new mover one track
    frame.update(scale=1.0)
    content, buffers = custom_messages(widget)[-1]
    assert content == {"type": "commands"} and len(buffers) == 1
    sent = len(custom_messages(widget))
    moving.add_frame("late")
    [content] = [c for c, _ in custom_messages(widget)[sent:] if c["type"] == "tracks"]
    assert content["type"] == "tracks" and [t["path"] for t in content["tracks"]] == [
        "/rbm/root/frame_late/pose"
    ]
    # decimation only on request
    coarse = Scene("world", max_samples=4)
    coarse.add_frame("body")
    coarse.widget.comm.receive({"type": "ready"})
    [(content, _)] = custom_messages(coarse.widget)
    assert content["tracks"][0]["n"] == 4
    coarse.close()
    with pytest.raises(ValueError, match="max_samples"):
        Scene("world", max_samples=1)
    # tracks with the same timestamps share one time buffer
    state = moving.state
    meta, buffers = state.track_payload(max_samples=4)
    assert [m["n"] for m in meta] == [4, 4]
    assert len(buffers) == 2 + 2 * 2


def test_playback_moves_no_kernel_data(moving):
    """Setting the time from Python is one small trait update, not pose data."""
    moving.add_frame("body")
    widget = moving.widget
    widget.comm.receive({"type": "ready"})
    player = moving.player()
    before = len(widget.comm.sent)
    player.seek(5)
    assert len(widget.comm.sent) == before  # the scene's comm is silent
    updates = [d for d, _ in player.comm.sent if d and d.get("method") == "update"]
    assert updates[-1]["state"] == {"time": pytest.approx(0.5)}


def test_grid_legend_and_labels(moving):
    frame = moving.add_frame("body", scale=0.5)
    moving.add_path("body", color="#ff00ff")
    legend = moving.legend()
    assert legend[0]["text"] == "frame axes x, y, z"
    assert {"text": "path body", "color": "#ff00ff"} in legend
    assert legend[-1] == {"text": "grid 1 m", "color": "#5a5a5a"}  # the path spans 10 m
    grid = umsgpack.unpackb(moving.state.objects["/rbm/grid"].data)
    xyz = np.frombuffer(
        grid["object"]["geometries"][0]["data"]["attributes"]["position"]["array"].data,
        np.float32,
    ).reshape(-1, 3)
    assert xyz[:, 0].min() <= 0 and xyz[:, 0].max() >= 10 and (xyz[:, 2] == 0).all()
    assert moving.widget._labels == {frame.pose_path: "body"}
    assert moving.widget._frames == {"body": frame.pose_path}
    from rbm_nb.scene.scene import format_length, nice_step

    assert [nice_step(s) for s in (0.7, 10, 33, 120)] == [0.1, 1.0, 5.0, 20.0]
    assert [format_length(v) for v in (0.005, 0.5, 20, 2000)] == [
        "5 mm",
        "50 cm",
        "20 m",
        "2 km",
    ]


def test_selection_follow_and_focus(moving):
    frame = moving.add_frame("body", scale=0.5)
    widget = moving.widget
    widget.selected = "body"  # what a click in 3D does (from the browser)
    assert moving.selected == "body"
    assert moving.state.properties[(frame.geom_path, "scale")] is not None
    scale = umsgpack.unpackb(moving.state.properties[(frame.geom_path, "scale")].data)
    assert scale["value"] == [2.0, 2.0, 2.0]
    moving.selected = None
    scale = umsgpack.unpackb(moving.state.properties[(frame.geom_path, "scale")].data)
    assert scale["value"] == [1.0, 1.0, 1.0]
    moving.follow("body")
    assert widget.follow == "body"
    moving.follow(None)
    assert widget.follow is None
    with pytest.raises(ValueError, match="not drawn in this scene"):
        moving.follow("eye")
    moving.set_time(0.5)
    moving.focus("body")
    np.testing.assert_allclose(widget._camera["target"], [5.0, 0.0, 1.0])
    distance = np.linalg.norm(np.subtract(widget._camera["position"], [5.0, 0.0, 1.0]))
    assert distance == pytest.approx(5.0)  # ten triads


def test_focus_refuses_a_frame_whose_samples_are_missing(moving):
    """Missing at the time shown and at its last sample: a clear error, no TypeError."""
    frame = moving.add_frame("body", scale=0.5)
    t = np.c_[np.arange(11.0), np.zeros(11), np.ones(11)]
    t[5:] = np.nan  # a blink from 0.5 s to the end
    r = np.tile([1.0, 0.0, 0.0, 0.0], (11, 1))
    moving.state.add_track(frame.pose_path, PoseTrack(t, r, np.arange(11) * 0.1))
    moving.set_time(0.2)
    moving.focus("body")  # shown now: aimed at it
    np.testing.assert_allclose(moving._camera["target"], [2.0, 0.0, 1.0])
    moving.set_time(0.7)
    with pytest.raises(ValueError, match="'body' has no pose at the time shown"):
        moving.focus("body")


def test_no_socket_is_opened(moving):
    import psutil

    def listening():
        return {
            c.laddr
            for c in psutil.Process().net_connections(kind="inet")
            if c.status == psutil.CONN_LISTEN
        }

    before = listening()
    moving.add_frame("body")
    moving.show()
    moving.player().play()
    assert listening() == before


def test_explorer_gaze_rays_are_hidden_where_the_eye_was_not_seen():
    """Blinks, lost pupils and samples below confidence 0.6 draw no gaze ray."""
    from rbm_nb.app.explorer import explorer_scene, register_head_eye_frames
    from rbm_nb.data import synthetic_head_eye

    recording = synthetic_head_eye(duration=20.0, seed=2)
    register_head_eye_frames(*recording)
    scene = explorer_scene()
    eye = recording.left_eye
    [ray] = [
        h
        for h in scene.handles.values()
        if getattr(h, "frame", None) is not None and h.frame.name == "pupil/left_eye"
    ]
    track = scene.state.tracks[ray.pose_path]
    times = eye.time.values
    unseen = np.isnan(eye.orientation.values).any(axis=1) | (
        eye.confidence.values < 0.6
    )
    assert unseen.any() and not unseen.all()
    # the ray is sampled on the eye's clock: every unseen sample is hidden
    # there (and its squad neighbours may be too), and some seen ones are not
    hidden = np.array([track.missing(i) for i in range(len(track))])
    position = {t: k for k, t in enumerate(track.original_timestamps)}
    checked = 0
    for t in times[unseen]:
        k = position.get(t)
        if k is not None:
            assert hidden[k], t
            checked += 1
    assert checked > 0.9 * unseen.sum()
    assert not hidden.all()


def test_a_track_is_hidden_across_a_gap_longer_than_max_gap():
    """A scene holds each pose until the next sample; across a gap the frame
    core does not bridge (max_gap), the object is hidden from max_gap after
    the last sample on, and shown again at the next sample."""
    import numpy as np

    import rbm_nb as rbm
    from rbm_nb.core import frames
    from rbm_nb.scene.tracks import PoseTrack

    t = np.array([0.0, 0.1, 0.2, 2.0, 2.1])
    rbm.register_frame("world")
    rbm.register_frame(
        "eye", parent="world", timestamps=t, translation=np.ones((5, 3)), max_gap=0.5
    )
    rbm.register_frame(
        "free", parent="world", timestamps=t, translation=np.ones((5, 3))
    )
    world = frames.registry["world"]
    track = PoseTrack.lookup(frames.registry["eye"], world)
    assert len(track) == 6
    assert not track.missing(track.index_at(0.6))  # within max_gap of 0.2 s
    assert track.missing(track.index_at(0.71))  # beyond it, until the next sample
    assert track.missing(track.index_at(1.99))
    assert not track.missing(track.index_at(2.0))
    free = PoseTrack.lookup(frames.registry["free"], world)
    assert len(free) == 5 and not free.missing(free.index_at(1.5))
