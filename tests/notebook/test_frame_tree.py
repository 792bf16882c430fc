"""FrameTree: rows, details, selection, registry hook, player time, scene highlight."""

from __future__ import annotations

import numpy as np
import pytest
import traitlets
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

import rbm_nb as rbm
from rbm_nb.core import frames
from rbm_nb.widgets import FrameTree, Player
from rbm_nb.widgets.frame_details import (
    EULER_ORDER,
    Attitude,
    FrameDetails,
    PairDetails,
    details_html,
    details_text,
)
from rbm_nb.widgets.frame_tree import frame_info

pytestmark = pytest.mark.usefixtures("recording_comm")


@pytest.fixture
def tree_frames():
    """world -> observer (static), body (moving) -> body2 (static), events (discrete)."""
    rbm.register_frame("world")
    rbm.register_frame(
        "observer",
        parent="world",
        translation=(5, 0, 0),
        rotation=(np.sqrt(2) / 2, 0, 0, np.sqrt(2) / 2),
    )
    ts = np.arange(5) * 0.5
    angle = np.linspace(0, np.pi / 2, 5)
    rbm.register_frame(
        "body",
        parent="world",
        translation=np.c_[np.arange(5.0), np.zeros(5), np.zeros(5)],
        rotation=np.c_[np.cos(angle / 2), np.zeros(5), np.zeros(5), np.sin(angle / 2)],
        timestamps=ts,
    )
    rbm.register_frame("body2", parent="body", translation=(0, 1, 0))
    rbm.register_frame(
        "events",
        parent="world",
        translation=np.eye(3),
        timestamps=np.array([1.0, 2.0, 4.0]),
        discrete=True,
    )
    return ts


def test_rows_list_frames_depth_first_with_their_kind(tree_frames):
    tree = FrameTree("world")
    assert tree.nodes == ["world", "observer", "body", "body2", "events"]
    assert tree.row_text("world") == "root"
    assert tree.row_text("observer") == "static"
    assert tree.row_text("body") == "moving \u00b7 5 samples \u00b7 2 s \u00b7 2 Hz"
    assert (
        tree.row_text("events")
        == "discrete \u00b7 3 events \u00b7 3 s \u00b7 0.6667 Hz"
    )
    depths = [tree._rows[n]["depth"] for n in tree.nodes]
    assert depths == [0, 1, 1, 2, 1]


def test_frame_info_of_datetime_frame():
    rbm.register_frame("world")
    ts = np.datetime64("2020-02-02T00:00:00") + np.arange(201) * np.timedelta64(5, "ms")
    rbm.register_frame(
        "head", parent="world", translation=np.zeros((201, 3)), timestamps=ts
    )
    info = frame_info(rbm.registry["head"])
    assert info["kind"] == "moving"
    assert info["samples"] == 201
    assert info["span"] == pytest.approx(1.0)
    assert info["rate"] == pytest.approx(200.0)
    assert info["time_kind"] == "datetime64"


def test_single_selection_shows_pose_wrt_parent_at_the_current_time(tree_frames):
    tree = FrameTree("world")
    tree.select("body")
    text = tree.details_text()
    assert "parent: world" in text
    assert "children: body2" in text
    assert "path to root: body \u2192 world" in text
    assert "(at 0.000 s)" in text and "translation (0, 0, 0) m" in text
    tree.set_time(1.2)  # latest sample at or before: index 2 (t=1.0)
    details = tree.details
    assert isinstance(details, FrameDetails)
    assert details.parent == "world" and details.children == ("body2",)
    assert details.pose.when == "at 1.000 s"
    assert details.pose.translation == (2.0, 0.0, 0.0)
    np.testing.assert_allclose(details.pose.attitude.euler, (45.0, 0.0, 0.0), atol=1e-9)
    text = tree.details_text()
    assert "translation (2, 0, 0) m" in text
    assert "rotation yaw 45.00\u00b0, pitch 0.00\u00b0, roll 0.00\u00b0" in text
    assert "quaternion (w, x, y, z) = (0.9239, 0, 0, 0.3827)" in text
    assert tree._details.value == details_html(details)


def test_static_frame_details(tree_frames):
    tree = FrameTree("world")
    tree.select("observer")
    text = tree.details_text()
    assert "pose wrt world (static)" in text
    assert "translation (5, 0, 0) m" in text
    assert "yaw 90.00\u00b0, pitch 0.00\u00b0, roll 0.00\u00b0" in text
    tree.select("world")
    assert "parent: none (root)" in tree.details_text()


def test_two_frames_show_the_chain_and_the_transform(tree_frames):
    tree = FrameTree("world")
    tree.select("body2", "observer")
    tree.set_time(2.0)
    text = tree.details_text()
    assert "chain: body2 \u2192 body \u2192 world \u2192 observer" in text
    t, r, ts = rbm.lookup_transform(
        outof="body2", into="observer", return_timestamps=True
    )
    i = int(np.searchsorted(ts, 2.0, side="right")) - 1
    details = tree.details
    assert isinstance(details, PairDetails)
    assert details.chain == ("body2", "body", "world", "observer")
    np.testing.assert_allclose(details.pose.translation, t[i])
    assert details.pose.attitude == Attitude.of(r[i])
    assert details.pose.attitude.euler_text() in text
    assert details_text(details) == text


def test_time_before_the_start_says_so(tree_frames):
    tree = FrameTree("world")
    tree.select("events")
    tree.set_time(0.5)
    assert "not defined before 1.000 s" in tree.details_text()


def test_clicking_rows_selects_at_most_two(tree_frames):
    tree = FrameTree("world")
    buttons = {name: tree._rows[name]["button"] for name in tree.nodes}
    buttons["body"].value = True
    buttons["observer"].value = True
    assert tree.selected == ("body", "observer")
    buttons["events"].value = True  # the oldest selection goes
    assert tree.selected == ("observer", "events")
    assert not buttons["body"].value
    buttons["observer"].value = False
    assert tree.selected == ("events",)


def test_registry_changes_refresh_the_tree(tree_frames):
    tree = FrameTree("world")
    tree.select("body2")
    rbm.register_frame("new", parent="body2", translation=(1, 2, 3))
    assert tree.nodes == ["world", "observer", "body", "body2", "new", "events"]
    assert tree._rows["new"]["depth"] == 3
    rbm.deregister_frame("body2")
    assert "body2" not in tree.nodes and "new" not in tree.nodes
    assert tree.selected == ()
    rbm.clear_registry()
    assert tree.nodes == []
    assert "no frame named 'world'" in tree._message.value


def test_close_removes_the_registry_listener(tree_frames):
    before = len(frames.registry._callbacks)
    tree = FrameTree("world")
    assert len(frames.registry._callbacks) == before + 1
    tree.close()
    tree.close()
    assert len(frames.registry._callbacks) == before
    rbm.register_frame("late", parent="world")
    assert "late" not in tree.nodes  # a closed tree no longer follows the registry


def test_collapse_and_expand(tree_frames):
    tree = FrameTree("world")
    tree.collapse("body")
    assert tree.visible_nodes == ["world", "observer", "body", "events"]
    tree._rows["world"]["toggle"].click()
    assert tree.visible_nodes == ["world"]
    tree.expand("world")
    assert tree.visible_nodes == ["world", "observer", "body", "events"]
    tree.expand("body")
    assert tree.visible_nodes == tree.nodes


def test_player_time_drives_the_details(tree_frames):
    player = Player(tree_frames)
    tree = FrameTree("world", player=player)
    tree.select("body")
    player.seek(3)
    assert tree.time == pytest.approx(1.5)
    assert tree.details.pose.translation == (3.0, 0.0, 0.0)
    player.time = 0.7  # what the browser tells the kernel, throttled
    assert tree.details.pose.when == "at 0.500 s"
    player.unlink(tree)
    player.time = 2.0
    assert tree.details.pose.when == "at 0.500 s"  # no longer follows


def test_datetime_frames_print_the_shared_readout():
    rbm.register_frame("world")
    start = np.datetime64("2020-02-02T00:27:14", "ns")
    stamps = start + (np.arange(5) * 250).astype("timedelta64[ms]")
    rbm.register_frame(
        "head", parent="world", translation=np.zeros((5, 3)), timestamps=stamps
    )
    player = Player(stamps)
    tree = FrameTree("world", player=player)
    tree.select("head")
    player.time = 0.6
    assert tree.details.pose.when == "at 0.500 s \u00b7 2020-02-02 00:27:14.500"
    standalone = FrameTree("world")  # no player: counts from the first sample
    standalone.select("head")
    assert standalone.details.pose.when == "at 0.000 s \u00b7 2020-02-02 00:27:14.000"


def test_selection_goes_both_ways_with_a_scene(tree_frames):
    from rbm_nb.scene import Scene

    scene = Scene("world")
    body = scene.add_frame("body")
    scene.add_frame("observer")
    tree = FrameTree("world", scene=scene)
    tree.select("body")  # tree -> scene: selected and highlighted
    assert scene.selected == "body"
    assert scene._highlight == ("scaled", body)
    scene.widget.set_state({"selected": "observer"})  # a click in the 3D view
    assert tree.selected == ("observer",)
    assert tree.details.name == "observer"
    tree.select("body2", "observer")  # a pair: the scene gets the last one
    assert scene.selected == "observer" and tree.selected == ("body2", "observer")
    scene.widget.set_state({"selected": None})  # click on empty space
    assert tree.selected == ()
    tree.select("events")  # not drawn in the scene: selected there, no highlight
    assert scene.selected == "events" and scene._highlight is None
    tree.close()
    scene.widget.set_state({"selected": "body"})
    assert tree.selected == ("events",)  # a closed tree no longer follows
    scene.close()


def test_bad_selection_and_root(tree_frames):
    tree = FrameTree("world")
    with pytest.raises(traitlets.TraitError, match="'nope' is not in the tree"):
        tree.select("nope")
    with pytest.raises(traitlets.TraitError, match="at most two"):
        tree.select("world", "body", "observer")
    with pytest.raises(ValueError, match="not in the tree"):
        tree.collapse("nope")
    other = FrameTree("nope")
    assert other.nodes == [] and "no frame named 'nope'" in other._message.value


def _scipy_zyx(q):
    """scipy's intrinsic Z-Y'-X'' angles (yaw, pitch, roll) in degrees."""
    return Rotation.from_quat([q[1], q[2], q[3], q[0]]).as_euler("ZYX", degrees=True)


def _rebuilt(euler):
    """The quaternion (w, x, y, z) the shown angles stand for, by scipy."""
    x, y, z, w = Rotation.from_euler("ZYX", euler, degrees=True).as_quat()
    return np.array([w, x, y, z])


def _same_rotation(q1, q2):
    return abs(float(np.dot(q1, q2))) == pytest.approx(1.0, abs=1e-9)


def test_head_frame_of_the_explorer_shows_yaw_90_pitch_90():
    from rbm_nb.app.explorer import R_T265_ROS

    rbm.register_frame("world")
    rbm.ReferenceFrame.from_rotation_matrix(
        R_T265_ROS, parent="world", name="head", inverse=True
    ).register()
    tree = FrameTree("world")
    tree.select("head")
    attitude = tree.details.pose.attitude
    np.testing.assert_allclose(attitude.euler, (90.0, 90.0, 0.0), atol=1e-6)
    np.testing.assert_allclose(attitude.quaternion, (0.5, -0.5, 0.5, 0.5), atol=1e-12)
    assert "yaw 90.00\u00b0, pitch 90.00\u00b0, roll 0.00\u00b0" in tree.details_text()


# a grid of attitudes with every pitch from -90 to 90, gimbal lock included
GRID = [
    (yaw, pitch, roll)
    for yaw in (-180.0, -135.0, -30.0, 0.0, 45.0, 90.0, 179.0)
    for pitch in (-90.0, -89.999, -60.0, -1.0, 0.0, 30.0, 89.0, 90.0)
    for roll in (-170.0, -45.0, 0.0, 10.0, 120.0)
]


@pytest.mark.parametrize("yaw, pitch, roll", GRID)
def test_attitude_angles_stand_for_the_rotation_at_every_attitude(yaw, pitch, roll):
    q = _rebuilt((yaw, pitch, roll))
    attitude = Attitude.of(-q if q[0] > 0 else q)  # either sign of q
    assert attitude.quaternion[0] >= 0
    assert _same_rotation(attitude.quaternion, q)
    shown = attitude.euler
    assert _same_rotation(_rebuilt(shown), q)  # the angles give back the rotation
    assert (
        -90.0 <= shown[1] <= 90.0 and abs(shown[0]) <= 180.0 and abs(shown[2]) <= 180.0
    )
    if abs(pitch) < 89.0:  # away from gimbal lock the angles are unique
        wrapped = (np.asarray(shown) - _scipy_zyx(q) + 180.0) % 360.0 - 180.0
        np.testing.assert_allclose(wrapped, 0.0, atol=1e-7)  # -180 is 180
    elif abs(pitch) == 90.0:  # at gimbal lock roll is 0 and yaw carries the rest
        assert shown[1] == pytest.approx(pitch, abs=1e-6)
        assert shown[2] == pytest.approx(0.0, abs=1e-6)


unit = st.floats(-1, 1, allow_nan=False)


@settings(max_examples=200, deadline=None)
@given(st.tuples(unit, unit, unit, unit))
def test_attitude_round_trip(q):
    q = np.asarray(q)
    if np.linalg.norm(q) < 1e-3:
        return
    q = q / np.linalg.norm(q)
    attitude = Attitude.of(q)
    assert _same_rotation(_rebuilt(attitude.euler), q)
    assert _same_rotation(attitude.quaternion, q)


def test_attitude_rejects_bad_quaternions():
    for bad in ([0, 0, 0, 0], [1, 0, 0], [np.nan, 0, 0, 1]):
        with pytest.raises(ValueError, match="Attitude.of"):
            Attitude.of(bad)
    assert EULER_ORDER == "zyx"


def test_show_lookup_highlights_the_chain(tree_frames):
    tree = FrameTree("world")
    chain = tree.show_lookup("body2", "observer")
    assert chain == ("body2", "body", "world", "observer")
    assert tree.selected == ("body2", "observer")
    styles = {name: row["button"].button_style for name, row in tree._rows.items()}
    assert styles["body2"] == styles["observer"] == "info"  # the two ends
    assert styles["body"] == styles["world"] == "warning"  # passed through
    assert all(s == "" for n, s in styles.items() if n not in chain)
    assert (
        "chain: body2 \u2192 body \u2192 world \u2192 observer" in tree.details_text()
    )
    tree.select("body")  # one frame: no chain
    assert tree.chain == ()
    assert tree._rows["world"]["button"].button_style == ""
