"""rbm.plot: the guides' plotting cells run unchanged; artists hold the expected
geometry (checked against scipy); rendered pixels show what was drawn;
trajectory; bad input."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from scipy.spatial.transform import Rotation  # noqa: E402

import rbm_nb as rbm  # noqa: E402
from rbm_nb.core.plot import Arrow3D  # noqa: E402


@pytest.fixture(autouse=True)
def close_figures():
    yield
    plt.close("all")


def rendered(fig) -> np.ndarray:
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba())[..., :3].astype(int)


def count_color(img, rgb, tol=60) -> int:
    return int((np.abs(img - np.asarray(rgb)).sum(axis=-1) < tol).sum())


def arrow_points(arrows):
    return [np.column_stack(a._verts3d) for a in arrows]


def shafts(collection, n):
    """(tails, tips) of the n arrows of a 3-D quiver (its first n segments, tip first)."""
    segments = np.asarray(collection._segments3d, dtype=float)[:n]
    return segments[:, 1], segments[:, 0]


# -- guide 1.2: static frames, points, quaternions, vectors ----------------------------
def test_guide_1_2_cells():
    rf_world = rbm.ReferenceFrame("world")
    rf_observer = rbm.ReferenceFrame(
        "observer",
        parent=rf_world,
        translation=(5, 0, 0),
        rotation=(np.sqrt(2) / 2, 0, 0, np.sqrt(2) / 2),
    )
    p_body_world = np.array((2, 0, 0))
    o_body_world = np.array((1, 0, 0, 0))
    v_body_world = np.array((1, 0, 0))

    # cells [5], [11], [15], [18] as in the guide
    fig = plt.figure()
    ax = fig.add_subplot(111, projection="3d")
    world_arrows = rbm.plot.reference_frame(rf_world, ax=ax)
    observer_arrows = rbm.plot.reference_frame(rf_observer, rf_world, ax=ax)
    points = rbm.plot.points(p_body_world, ax=ax, fmt="yo")
    triads = rbm.plot.quaternions(o_body_world, base=p_body_world, ax=ax)
    velocity = rbm.plot.vectors(v_body_world, base=p_body_world, ax=ax, color="y")
    fig.tight_layout()

    assert all(isinstance(a, Arrow3D) for a in world_arrows + observer_arrows)
    for arrows, origin, axes in (
        (world_arrows, np.zeros(3), np.eye(3)),
        # the observer's x axis points along the world's y axis
        (
            observer_arrows,
            np.array([5.0, 0, 0]),
            np.array([[0, 1.0, 0], [-1.0, 0, 0], [0, 0, 1.0]]),
        ),
    ):
        for arrow, axis in zip(arrows, axes, strict=True):
            np.testing.assert_allclose(arrow.tail, origin, atol=1e-12)
            np.testing.assert_allclose(arrow.head, origin + axis, atol=1e-12)
    assert [matplotlib.colors.to_hex(a.get_edgecolor()) for a in world_arrows] == [
        "#ff0000",
        "#008000",
        "#0000ff",
    ]
    np.testing.assert_allclose(np.array(points[0].get_data_3d()).T, [p_body_world])
    for collection, axis in zip(triads, np.eye(3), strict=True):
        tails, tips = shafts(collection, 1)
        np.testing.assert_allclose(tails, [p_body_world])
        np.testing.assert_allclose(tips, [p_body_world + 0.5 * axis])
    tails, tips = shafts(velocity, 1)
    np.testing.assert_allclose(tips - tails, [v_body_world])
    # equal scaling on all three axes, every artist inside
    limits = np.array([ax.get_xlim3d(), ax.get_ylim3d(), ax.get_zlim3d()])
    spans = np.diff(limits, axis=1)[:, 0]
    np.testing.assert_allclose(spans, spans[0])
    assert (
        limits[0, 0] <= 0
        and limits[0, 1] >= 5
        and limits[1, 1] >= 1
        and limits[2, 1] >= 1
    )

    img = rendered(fig)
    assert count_color(img, (255, 0, 0)) > 20  # x arrows
    assert count_color(img, (0, 128, 0)) > 20  # y arrows
    assert count_color(img, (0, 0, 255)) > 20  # z arrows
    assert count_color(img, (191, 191, 0)) > 20  # the yellow point and velocity


def test_guide_1_2_moving_points():
    rf_world = rbm.ReferenceFrame("world")
    p_body_world = np.zeros((5, 3))
    p_body_world[:, 0] = np.linspace(0, 5, 5)
    p_body2_world = np.zeros((5, 3))
    p_body2_world[:, 1] = np.linspace(0, 2, 5)
    fig = plt.figure()
    ax = fig.add_subplot(111, projection="3d")
    rbm.plot.reference_frame(rf_world, ax=ax)
    a = rbm.plot.points(p_body_world, ax=ax, fmt="yo-")
    b = rbm.plot.points(p_body2_world, ax=ax, fmt="co-")
    fig.tight_layout()
    np.testing.assert_allclose(np.array(a[0].get_data_3d()).T, p_body_world)
    np.testing.assert_allclose(np.array(b[0].get_data_3d()).T, p_body2_world)
    assert a[0].get_linestyle() == "-" and a[0].get_marker() == "o"


# -- guide 1.3: poses on two subplots ----------------------------------------------------
def test_guide_1_3_cell():
    from quaternion import as_float_array, from_euler_angles

    rbm.register_frame("world")
    ts = np.linspace(0, 5, 5)
    p_body_world = np.zeros((5, 3))
    p_body_world[:, 0] = np.linspace(0, 5, 5)
    o_body_world = as_float_array(from_euler_angles(np.linspace(0, np.pi / 4, 5), 0, 0))
    rbm.register_frame(
        "body",
        translation=p_body_world,
        rotation=o_body_world,
        timestamps=ts,
        parent="world",
    )
    p_body2_body = np.zeros((5, 3))
    p_body2_body[:, 0] = -np.linspace(0, 1, 5)
    p_body2_body[:, 1] = 1
    o_body2_body = as_float_array(from_euler_angles(0, np.linspace(0, np.pi / 4, 5), 0))
    rbm.register_frame(
        "body2",
        translation=p_body2_body,
        rotation=o_body2_body,
        timestamps=ts,
        parent="body",
    )

    p_body2_world, o_body2_world = rbm.lookup_pose("body2", "world")
    fig = plt.figure(figsize=(10, 5))
    ax = fig.add_subplot(121, projection="3d")
    rbm.plot.points(p_body_world, ax=ax, fmt="yo-")
    triads = rbm.plot.quaternions(o_body_world, base=p_body_world, ax=ax)
    ax = fig.add_subplot(122, projection="3d", sharex=ax, sharey=ax, sharez=ax)
    rbm.plot.points(p_body2_world, ax=ax, fmt="co-")
    rbm.plot.quaternions(o_body2_world, base=p_body2_world, ax=ax)
    fig.tight_layout()
    # each x arrow is the body's x axis rotated by its orientation, 0.5 long
    q = o_body_world
    expected = Rotation.from_quat(
        q[:, [1, 2, 3, 0]]
    ).as_matrix()  # columns: rotated axes
    for i, collection in enumerate(triads):
        tails, tips = shafts(collection, 5)
        np.testing.assert_allclose(tails, p_body_world, atol=1e-12)
        np.testing.assert_allclose(tips - tails, 0.5 * expected[:, :, i], atol=1e-12)


# -- guide 1.4: frames by name, arrays of vectors and points -------------------------------
def test_guide_1_4_cells():
    rbm.register_frame("world")
    v1 = (1, 0, 0)
    v2 = (np.sqrt(2) / 2, np.sqrt(2) / 2, 0)
    fig = plt.figure()
    ax = fig.add_subplot(111, projection="3d")
    arrows = rbm.plot.reference_frame("world", ax=ax)
    rbm.plot.vectors(v1, ax=ax, color="y")
    rbm.plot.vectors(v2, ax=ax, color="c")
    fig.tight_layout()
    assert len(arrows) == 3

    r = rbm.from_euler_angles(yaw=np.linspace(0, np.pi / 8, 10))
    v2_arr = rbm.rotate_vectors(r, v2, one_to_one=False)
    fig = plt.figure()
    ax = fig.add_subplot(111, projection="3d")
    rbm.plot.reference_frame("world", ax=ax)
    rbm.plot.vectors(v1, ax=ax, color="y")
    cloud = rbm.plot.vectors(v2_arr, ax=ax, color="c", alpha=0.3)
    fig.tight_layout()
    tails, tips = shafts(cloud, 10)
    np.testing.assert_allclose(tips, v2_arr, atol=1e-12)
    np.testing.assert_allclose(tails, 0)

    p1_arr = 0.1 * np.random.default_rng(0).normal(size=(100, 3))
    t = np.array((1, 1, 0))
    p2_arr = (
        rbm.rotate_vectors(
            rbm.from_euler_angles(yaw=np.pi / 4), p1_arr, one_to_one=False
        )
        + t
    )
    fig = plt.figure()
    ax = fig.add_subplot(111, projection="3d")
    rbm.plot.reference_frame("world", ax=ax)
    rbm.plot.points(p1_arr, ax=ax, fmt="yo")
    lines = rbm.plot.points(p2_arr, ax=ax, fmt="co")
    fig.tight_layout()
    np.testing.assert_allclose(np.array(lines[0].get_data_3d()).T, p2_arr)
    img = rendered(fig)
    assert count_color(img, (0, 191, 191)) > 50  # the cyan point cloud is drawn


def test_reference_frame_wrt_world_matches_transform_points():
    rbm.register_frame("world")
    rbm.register_frame(
        "a", parent="world", translation=(1, 2, 3), rotation=(0.5, 0.5, 0.5, 0.5)
    )
    rbm.register_frame("b", parent="a", translation=(0, 0, 1))
    arrows = rbm.plot.reference_frame("b", "world", arrow_len=2.0)
    corners = np.array([[0, 0, 0], [2, 0, 0], [0, 2, 0], [0, 0, 2]], dtype=float)
    expected = rbm.transform_points(corners, outof="b", into="world")
    for arrow, tip in zip(arrows, expected[1:], strict=True):
        np.testing.assert_allclose(arrow.tail, expected[0], atol=1e-12)
        np.testing.assert_allclose(arrow.head, tip, atol=1e-12)


# -- trajectory ------------------------------------------------------------------------
def test_trajectory_plots_position_and_orientation_over_time():
    rbm.register_frame("world")
    ts = np.datetime64("2020-01-01") + np.arange(50) * np.timedelta64(20, "ms")
    yaw = np.linspace(0, 3 * np.pi, 50)  # more than a turn: angles are unwrapped
    position = np.c_[np.arange(50.0), np.zeros(50), np.ones(50)]
    rbm.register_frame(
        "body",
        parent="world",
        timestamps=ts,
        translation=position,
        rotation=np.c_[np.cos(yaw / 2), np.zeros(50), np.zeros(50), np.sin(yaw / 2)],
    )
    ax_p, ax_o = rbm.plot.trajectory("body")
    assert [line.get_label() for line in ax_p.lines] == ["x", "y", "z"]
    assert [line.get_label() for line in ax_o.lines] == ["roll", "pitch", "yaw"]
    np.testing.assert_allclose(ax_p.lines[0].get_ydata(), position[:, 0])
    np.testing.assert_allclose(ax_o.lines[2].get_ydata(), np.degrees(yaw), atol=1e-9)
    assert np.issubdtype(np.asarray(ax_p.lines[0].get_xdata()).dtype, np.datetime64)
    assert ax_o.get_xlabel() == "Time"


# -- bad input -------------------------------------------------------------------------
@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: rbm.plot.points([1, 2]), r"shape \(3,\) or \(N, 3\)"),
        (
            lambda: rbm.plot.vectors(np.zeros((2, 3)), base=np.zeros((3, 3))),
            "base must have shape",
        ),
        (lambda: rbm.plot.quaternions([0, 0, 0, 0]), "non-zero"),
        (lambda: rbm.plot.quaternions([1, 0, 0]), r"shape \(4,\) or \(N, 4\)"),
        (
            lambda: rbm.plot.points([0, 0, 0], ax=plt.figure().add_subplot(111)),
            "3-D axes",
        ),
    ],
)
def test_bad_arrays(call, message):
    with pytest.raises(ValueError, match=message):
        call()


def test_bad_frames():
    rbm.register_frame("world")
    rbm.register_frame(
        "body", parent="world", timestamps=np.arange(3.0), translation=np.zeros((3, 3))
    )
    rbm.register_frame("on_body", parent="body", translation=(1, 0, 0))
    with pytest.raises(ValueError, match="'body' is moving"):
        rbm.plot.reference_frame("body")
    with pytest.raises(ValueError, match="moves"):
        rbm.plot.reference_frame("on_body", "world")
    with pytest.raises(ValueError, match="not found"):
        rbm.plot.reference_frame("nobody")
    with pytest.raises(ValueError, match="arrow_len"):
        rbm.plot.reference_frame("world", arrow_len=0)
    with pytest.raises(ValueError, match="has no parent; pass the reference frame"):
        rbm.plot.trajectory("world")
    with pytest.raises(ValueError, match="does not move"):
        rbm.plot.trajectory("on_body", "body")
