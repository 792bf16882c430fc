"""Places where rbm_nb must give what rigid-body-motion 0.9.3 gives (issue 11, item 1).

Quaternion signs follow these rules:

* Where the reference's sign follows from algebra (products, SQUAD, tf2's
  composition of a chain of transforms) rbm_nb returns the same numbers.
* ``ros.Transformer.transform_quaternion``/``transform_pose``: the reference
  calls ``tf2_geometry_msgs.do_transform_pose``, which multiplies two PyKDL
  frames and reads the orientation back with ``KDL::Rotation::GetQuaternion``
  (ros/geometry2, ``tf2_geometry_msgs.py``). So the sign a reference user gets
  is KDL's rule for a rotation matrix: ``w > 0`` when the trace is above 1e-12,
  otherwise the component of the largest diagonal entry is positive. That rule
  is tested here, against a plain-numpy twin of it.
* Where the reference's sign is an artefact of an eigen-solver
  (``best_fit_rotation``/``best_fit_transform`` and
  ``ReferenceFrame.from_rotation_matrix`` use numpy-quaternion's Bar-Itzhack
  eigenvector method), the documented convention is tested: **w > 0; for a
  half-turn (w == 0) the first non-zero of x, y, z is positive**, the rotation
  equals the reference's, and README's "What differs" says so.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
import xarray as xr
from conftest import REPO

import rbm_nb as rbm

ref = pytest.importorskip("rigid_body_motion")


@pytest.fixture(autouse=True)
def _clear_reference_registry():
    ref.clear_registry()
    yield
    ref.clear_registry()


# ---------------------------------------------------------------------------
# plain-numpy helpers (test-side twins; independent of rbm_nb's kernels)
# ---------------------------------------------------------------------------


def qmul(a, b):
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return np.array(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ]
    )


def qconj(q):
    return np.array([q[0], -q[1], -q[2], -q[3]])


def matrix(q):
    w, x, y, z = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def kdl_quaternion(m):
    """w, x, y, z as KDL's Rotation::GetQuaternion reads them off a matrix."""
    trace = m[0, 0] + m[1, 1] + m[2, 2]
    if trace > 1e-12:
        s = 0.5 / np.sqrt(trace + 1.0)
        return np.array(
            [0.25 / s, (m[2, 1] - m[1, 2]) * s, (m[0, 2] - m[2, 0]) * s,
             (m[1, 0] - m[0, 1]) * s]
        )  # fmt: skip
    if m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = 2.0 * np.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2])
        return np.array(
            [(m[2, 1] - m[1, 2]) / s, 0.25 * s, (m[0, 1] + m[1, 0]) / s,
             (m[0, 2] + m[2, 0]) / s]
        )  # fmt: skip
    if m[1, 1] > m[2, 2]:
        s = 2.0 * np.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2])
        return np.array(
            [(m[0, 2] - m[2, 0]) / s, (m[0, 1] + m[1, 0]) / s, 0.25 * s,
             (m[1, 2] + m[2, 1]) / s]
        )  # fmt: skip
    s = 2.0 * np.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1])
    return np.array(
        [(m[1, 0] - m[0, 1]) / s, (m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s,
         0.25 * s]
    )  # fmt: skip


def random_unit_quaternions(rng, n):
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def assert_convention(q):
    """w > 0, or w == 0 and the first non-zero of x, y, z positive."""
    q = np.atleast_2d(q)
    for row in q:
        if abs(row[0]) > 1e-9:
            assert row[0] > 0, f"{row}: w must be positive"
        else:
            first = row[1:][np.abs(row[1:]) > 1e-9][0]
            assert first > 0, f"{row}: half-turn, first non-zero of x, y, z must be > 0"


def assert_same_rotation(a, b, atol=1e-9):
    a, b = np.asarray(a), np.asarray(b)
    sign = 1.0 if np.dot(a, b) >= 0 else -1.0
    np.testing.assert_allclose(a * sign, b, atol=atol)


# ---------------------------------------------------------------------------
# eigen-solver signs: documented convention
# ---------------------------------------------------------------------------


def _point_sets(seed):
    rng = np.random.default_rng(seed)
    v1 = rng.normal(size=(20, 3))
    q = random_unit_quaternions(rng, 1)[0]
    v2 = v1 @ matrix(q).T + rng.normal(size=3)
    return v1, v2


@pytest.mark.parametrize("seed", range(12))
def test_best_fit_signs_follow_the_convention(seed):
    v1, v2 = _point_sets(seed)
    r = rbm.best_fit_rotation(v1, v2)
    t, rt = rbm.best_fit_transform(v1, v2)
    assert_convention(r)
    assert_convention(rt)
    assert_same_rotation(r, ref.best_fit_rotation(v1, v2), atol=1e-7)
    ref_t, ref_r = ref.best_fit_transform(v1, v2)
    assert_same_rotation(rt, ref_r, atol=1e-7)
    np.testing.assert_allclose(t, ref_t, atol=1e-7)


HALF_TURNS = [
    np.diag([1.0, -1.0, -1.0]),  # about x
    np.diag([-1.0, 1.0, -1.0]),  # about y
    np.diag([-1.0, -1.0, 1.0]),  # about z
    np.array([[0.0, 1, 0], [1, 0, 0], [0, 0, -1]]),  # about (x + y)/sqrt 2
    np.array([[0.0, -1, 0], [-1, 0, 0], [0, 0, -1]]),  # about (x - y)/sqrt 2
]


@pytest.mark.parametrize(
    "mat",
    [np.array([[0.0, 0, -1], [-1, 0, 0], [0, 1, 0]])] + HALF_TURNS,
    ids=["issue-example", "half-x", "half-y", "half-z", "half-x+y", "half-x-y"],
)
def test_from_rotation_matrix_sign_follows_the_convention(mat):
    rbm.register_frame("world")
    ref.register_frame("world")
    got = rbm.ReferenceFrame.from_rotation_matrix(mat, "world").rotation
    expected = ref.ReferenceFrame.from_rotation_matrix(mat, "world").rotation
    assert_convention(got)
    assert_same_rotation(got, expected)
    np.testing.assert_allclose(matrix(got), mat, atol=1e-12)


def test_readme_documents_the_sign_convention():
    text = (REPO / "README.md").read_text()
    start = text.index("What differs")
    section = text[start : text.index("\n## ", start)]
    assert re.search(r"best_fit", section), "What differs must name best_fit_*"
    assert re.search(r"from_rotation_matrix", section)
    assert re.search(r"w\s*(>=|≥|>)\s*0", section), "What differs must state w >= 0"


# ---------------------------------------------------------------------------
# ros.Transformer: tf2's composition and KDL's read-back
# ---------------------------------------------------------------------------

TREE = {  # child: parent
    "a": "world",
    "b": "a",
    "c": "b",
    "d": "world",
    "e": "d",
}


def _static_grid(seed):
    rng = np.random.default_rng(seed)
    qs = random_unit_quaternions(rng, len(TREE))
    ts = rng.normal(size=(len(TREE), 3))
    rbm.register_frame("world")
    edges = {}
    for (child, parent), q, t in zip(TREE.items(), qs, ts, strict=True):
        rbm.register_frame(child, parent=parent, translation=t, rotation=q)
        edges[child] = (parent, q, t)
    return edges


def _to_root(name, edges):
    """tf2's accumulation of a frame's rotation up to the root (no sign fix)."""
    q = np.array([1.0, 0, 0, 0])
    while name in edges:
        parent, edge_q, _ = edges[name]
        q = qmul(edge_q, q)
        name = parent
    return q


def _chain(name, edges):
    out = [name]
    while name in edges:
        name = edges[name][0]
        out.append(name)
    return out


def tf2_rotation(target, source, edges):
    """tf2 BufferCore::lookupTransform's rotation: walk both to their common
    ancestor multiplying edge rotations, then inverse(target side) * source side."""
    up_source = _chain(source, edges)
    up_target = _chain(target, edges)
    top = next(n for n in up_source if n in up_target)

    def accumulate(name):
        q = np.array([1.0, 0, 0, 0])
        while name != top:
            parent, edge_q, _ = edges[name]
            q = qmul(edge_q, q)
            name = parent
        return q

    return qmul(qconj(accumulate(target)), accumulate(source))


PAIRS = [(t, s) for t in ["world", *TREE] for s in ["world", *TREE] if t != s]


@pytest.mark.parametrize("seed", range(4))
def test_transformer_lookup_sign_is_tf2_composition(seed):
    edges = _static_grid(seed)
    tf = rbm.ros.Transformer.from_reference_frame("world")
    for target, source in PAIRS:
        _, r = tf.lookup_transform(target, source)
        np.testing.assert_allclose(
            r, tf2_rotation(target, source, edges), atol=1e-12,
            err_msg=f"lookup_transform({target!r}, {source!r})",
        )  # fmt: skip


@pytest.mark.parametrize("seed", range(4))
def test_transformer_transform_quaternion_and_pose_sign(seed):
    edges = _static_grid(seed)
    tf = rbm.ros.Transformer.from_reference_frame("world")
    rng = np.random.default_rng(100 + seed)
    wrong = []
    for target, source in PAIRS:
        q = random_unit_quaternions(rng, 1)[0]
        r = tf2_rotation(target, source, edges)
        expected = kdl_quaternion(matrix(r) @ matrix(q))
        got = np.array(tf.transform_quaternion(q, target, source))
        _, got_pose = tf.transform_pose((0.0, 1.0, 2.0), q, target, source)
        assert_same_rotation(got, expected)  # the rotation is right either way
        if not (
            np.allclose(got, expected, atol=1e-9)
            and np.allclose(got_pose, expected, atol=1e-9)
        ):
            wrong.append((target, source, got.round(4), expected.round(4)))
    assert not wrong, (
        f"{len(wrong)} of {len(PAIRS)} pairs have the other sign: {wrong[:3]}"
    )


# ---------------------------------------------------------------------------
# stored values round-trip (the real head recording)
# ---------------------------------------------------------------------------


@pytest.fixture(scope="module")
def head(shared_data):
    return xr.load_dataset(shared_data / "rbm-data" / "head.nc")


def test_real_head_values_round_trip(head):
    # the file stores quaternions to 1e-4, so |q| - 1 reaches ~8e-5
    norms = np.linalg.norm(head.orientation.values, axis=1)
    assert np.abs(norms - 1).max() > 1e-5
    for pkg in (rbm, ref):
        pkg.register_frame("world")
        pkg.ReferenceFrame.from_dataset(
            head, "position", "orientation", "time", parent="world", name="head"
        ).register()
    np.testing.assert_array_equal(
        rbm.registry["head"].rotation, head.orientation.values
    )
    got = rbm.lookup_transform("head", "world", as_dataset=True)
    expected = ref.lookup_transform("head", "world", as_dataset=True)
    np.testing.assert_array_equal(got.rotation.values, expected.rotation.values)
    np.testing.assert_array_equal(got.rotation.values, head.orientation.values)
    np.testing.assert_array_equal(got.translation.values, head.position.values)
    pose = rbm.lookup_pose("head", "world", as_dataset=True)
    np.testing.assert_array_equal(pose.orientation.values, head.orientation.values)


# ---------------------------------------------------------------------------
# qinterp with qaxis=0
# ---------------------------------------------------------------------------


def _smooth_quaternions(n=8):
    a = np.linspace(0, 1.5, n)
    q = np.column_stack(
        [np.cos(a), np.sin(a) * 0.6, np.sin(a) * 0.8 * np.cos(a), 0 * a]
    )
    q[:, 3] = 0.3 * np.sin(2 * a)
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def test_qinterp_quaternion_axis_first():
    q = _smooth_quaternions()
    t_in = np.arange(8.0)
    t_out = np.linspace(0.0, 7.0, 23)
    expected = ref.qinterp(q.T, t_in, t_out, qaxis=0)
    got = rbm.qinterp(q.T, t_in, t_out, qaxis=0)
    assert got.shape == expected.shape == (4, 23)
    np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(got, rbm.qinterp(q, t_in, t_out).T, atol=1e-12)


# ---------------------------------------------------------------------------
# the registry as a mutable mapping, and double registration
# ---------------------------------------------------------------------------


def test_registry_del_and_setitem_like_the_reference():
    for pkg in (rbm, ref):
        pkg.register_frame("world")
        pkg.register_frame("a", parent="world", translation=[1.0, 0, 0])
        frame = pkg.ReferenceFrame("b", parent="world", translation=[0.0, 2.0, 0])
        pkg.registry["b"] = frame
        assert pkg.registry["b"] is frame
        np.testing.assert_allclose(pkg.lookup_transform("b", "world")[0], [0, 2, 0])
        del pkg.registry["a"]
        assert "a" not in pkg.registry
        with pytest.raises(ValueError):
            pkg.lookup_transform("a", "world")
    assert sorted(rbm.registry) == sorted(ref.registry)


def test_registering_the_same_object_twice_raises_like_the_reference():
    for pkg in (ref, rbm):
        pkg.register_frame("world")
        frame = pkg.ReferenceFrame("x", parent="world")
        frame.register()
        with pytest.raises(ValueError, match="already registered"):
            frame.register()
        frame.register(update=True)  # explicit update stays allowed


# ---------------------------------------------------------------------------
# outlier rejection that leaves nothing to interpolate from
# ---------------------------------------------------------------------------


def _zigzag(n=86):
    """n samples; all but the last three jump back and forth (outliers)."""
    t = np.arange(n) * 0.01
    x = np.zeros((n, 3))
    x[:, 0] = np.where(np.arange(n) % 2, 1.0, -1.0)
    x[-3:, 0] = x[-4, 0]
    return t, x


def test_outlier_rejection_never_returns_nan_rows():
    t, x = _zigzag()
    rbm.register_frame("world")
    rbm.register_frame("b", parent="world", translation=x, timestamps=t)
    with pytest.raises(ValueError, match="outlier_thresh"):
        rbm.estimate_linear_velocity(x, timestamps=t, outlier_thresh=0.5)
    with pytest.raises(ValueError, match="outlier_thresh"):
        rbm.lookup_twist("b", "world", outlier_thresh=0.5)
    with pytest.raises(ValueError, match="outlier_thresh"):
        rbm.lookup_linear_velocity("b", "world", outlier_thresh=0.5)


def test_rejected_first_sample_is_not_a_silent_nan():
    t = np.arange(86) * 0.01
    x = np.zeros((86, 3))
    x[0, 0] = 5.0  # one outlier, at the start
    rbm.register_frame("world")
    rbm.register_frame("b", parent="world", translation=x, timestamps=t)
    calls = [
        lambda: rbm.estimate_linear_velocity(x, timestamps=t, outlier_thresh=0.5),
        lambda: rbm.lookup_twist("b", "world", outlier_thresh=0.5)[0],
    ]
    for call in calls:
        try:
            v = call()
        except ValueError as err:  # a clear refusal is fine
            assert "outlier_thresh" in str(err)
        else:
            assert np.isfinite(v).all(), "rows without a kept neighbour came back NaN"


@pytest.mark.parametrize(
    "coords",
    [{"time": [0.5], "quaternion_axis": ["w"]}, {"time": np.zeros((2, 2))}],
    ids=["two-dims", "2d-time"],
)
def test_accessor_qinterp_error_type_matches_the_reference(coords):
    from rigid_body_motion.accessors import DataArrayAccessor as RefAccessor

    da = xr.DataArray(
        np.tile([1.0, 0, 0, 0], (4, 1)),
        dims=("time", "quaternion_axis"),
        coords={"time": np.arange(4.0), "quaternion_axis": list("wxyz")},
    )
    with pytest.raises(Exception) as expected:
        RefAccessor(da).qinterp(**coords)
    with pytest.raises(Exception) as got:
        da.rbm.qinterp(**coords)
    assert isinstance(got.value, type(expected.value)), (
        f"reference raises {type(expected.value).__name__}, rbm_nb "
        f"{type(got.value).__name__}: {got.value}"
    )


# ---------------------------------------------------------------------------
# signs of interpolated quaternions when the stored series flips sign
# ---------------------------------------------------------------------------


def _alternating(n=8):
    """A smooth rotation stored with every other sample negated (q and -q are
    the same rotation; trackers and bags produce such series)."""
    a = np.linspace(0, 2.5, n)
    q = np.column_stack(
        [np.cos(a / 2), 0 * a, np.sin(a / 2) * 0.6, np.sin(a / 2) * 0.8]
    )
    q[1::2] *= -1
    return np.arange(float(n)), q


def _assert_exact_sign(got, expected, what):
    got, expected = np.asarray(got), np.asarray(expected)
    assert got.shape == expected.shape, what
    np.testing.assert_allclose(
        np.abs(np.sum(got * expected, axis=-1)), 1.0, atol=1e-9, err_msg=what
    )  # same rotations
    flipped = np.sum(got * expected, axis=-1) < 0
    assert not flipped.any(), (
        f"{what}: {flipped.sum()} of {flipped.size} rows have the other sign"
    )


def test_qinterp_sign_on_a_series_that_flips_sign():
    t, q = _alternating()
    t_out = np.arange(0.0, 7.0, 0.3)
    _assert_exact_sign(rbm.qinterp(q, t, t_out), ref.qinterp(q, t, t_out), "qinterp")


def test_lookup_signs_on_a_series_that_flips_sign():
    t, q = _alternating()
    t_out = np.arange(0.0, 7.0, 0.3)
    for pkg in (rbm, ref):
        pkg.register_frame("world")
        pkg.register_frame(
            "m", parent="world", rotation=q, translation=np.zeros((8, 3)), timestamps=t
        )
        pkg.register_frame(
            "clock",
            parent="world",
            translation=np.zeros((len(t_out), 3)),
            timestamps=t_out,
        )
    # at the samples themselves the stored values come back
    _assert_exact_sign(rbm.lookup_transform("m", "world")[1], q, "stored samples")
    for outof, into in [("m", "world"), ("m", "clock"), ("clock", "m")]:
        _assert_exact_sign(
            rbm.lookup_transform(outof, into)[1],
            ref.lookup_transform(outof, into)[1],
            f"lookup_transform({outof!r}, {into!r})",
        )
    ones = np.tile([1.0, 0, 0, 0], (len(t_out), 1))
    _assert_exact_sign(
        rbm.transform_quaternions(ones, "world", "m", timestamps=t_out),
        ref.transform_quaternions(ones, "world", "m", timestamps=t_out),
        "transform_quaternions",
    )


def tf2_slerp(q1, q2, f):
    """tf2::Quaternion::slerp: the shorter arc, the result on q1's side."""
    d = float(np.dot(q1, q2))
    if d < 0:
        q2, d = -q2, -d
    theta = np.arccos(min(d, 1.0))
    if theta == 0:
        return q1
    return (np.sin((1 - f) * theta) * q1 + np.sin(f * theta) * q2) / np.sin(theta)


def test_transformer_interpolation_sign_is_tf2_slerp():
    t, q = _alternating(6)
    rbm.register_frame("world")
    rbm.register_frame(
        "m", parent="world", rotation=q, translation=np.zeros((6, 3)), timestamps=t
    )
    tf = rbm.ros.Transformer.from_reference_frame("world")
    times = np.arange(0.1, 5.0, 0.25)
    got = np.array([tf.lookup_transform("world", "m", time=x)[1] for x in times])
    expected = np.array(
        [tf2_slerp(q[int(x)], q[int(x) + 1], x - int(x)) for x in times]
    )
    _assert_exact_sign(got, expected, "Transformer.lookup_transform")
