"""rbm_nb.sdf.GridSDF against scikit-robot's GridSDF (test-only oracle), trimesh and geometry."""

from __future__ import annotations

import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

import rbm_nb as rbm
from rbm_nb.sdf import GridSDF

skrobot_sdf = pytest.importorskip("skrobot.sdf")
Coordinates = pytest.importorskip("skrobot.coordinates").Coordinates
trimesh = pytest.importorskip("trimesh")

RADIUS = 0.3


@pytest.fixture(autouse=True)
def clean_registry():
    rbm.clear_registry()
    yield
    rbm.clear_registry()


def ball_grid(n=31, resolution=0.04, lower=-0.6):
    axis = lower + np.arange(n) * resolution
    x, y, z = np.meshgrid(axis, axis, axis, indexing="ij")
    return np.sqrt(x**2 + y**2 + z**2) - RADIUS, np.full(3, lower), resolution


def random_grid(shape=(7, 9, 6), seed=0):
    rng = np.random.default_rng(seed)
    return rng.normal(size=shape), rng.normal(size=3), 0.13


def query_points(data, origin, resolution, n=4000, seed=1):
    """Random points over (and a little beyond) the grid, plus nodes and corners."""
    rng = np.random.default_rng(seed)
    upper = origin + (np.array(data.shape) - 1) * resolution
    span = upper - origin
    pts = rng.uniform(origin - 0.2 * span, upper + 0.2 * span, (n, 3))
    idx = np.stack([rng.integers(0, s, 50) for s in data.shape], axis=1)
    nodes = origin + idx * resolution
    return np.concatenate([pts, nodes, [origin, upper]])


def skrobot_grid(data, origin, resolution, pose=None, **kw):
    oracle = skrobot_sdf.GridSDF(data, origin, resolution, **kw)
    if pose is not None:
        t, q = pose
        rot = Rotation.from_quat(q, scalar_first=True).as_matrix()
        oracle.newcoords(Coordinates(pos=np.asarray(t, float), rot=rot))
    return oracle


# -- distances ------------------------------------------------------------------


@pytest.mark.parametrize("use_abs", [False, True])
@pytest.mark.parametrize("fill_value", [np.inf, -7.5, 0.0])
def test_distances_match_skrobot_on_the_same_grid(use_abs, fill_value):
    data, origin, res = random_grid()
    pts = query_points(data, origin, res)
    ours = GridSDF(data, origin, res, fill_value=fill_value, use_abs=use_abs).sdf(pts)
    theirs = skrobot_grid(data, origin, res, fill_value=fill_value, use_abs=use_abs)(
        pts
    )
    np.testing.assert_array_equal(np.isfinite(ours), np.isfinite(theirs))
    np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-12)
    assert (
        np.isfinite(ours).sum() > 1000
        and (~np.isfinite(ours)).sum() > 100
        or (fill_value != np.inf)
    )


def test_the_grid_keeps_its_own_copy_and_hands_out_read_only_views():
    data, origin, resolution = random_grid()
    grid = GridSDF(data, origin, resolution)
    centre = grid.bounds.mean(axis=0)
    before = grid.sdf(centre)
    assert np.isfinite(before)
    # the caller's arrays stay theirs: writeable, and changing them later
    # does not change the grid
    assert data.flags.writeable and origin.flags.writeable
    data += 1.0
    origin += 1.0
    assert grid.sdf(centre) == before
    for arr in (grid.data, grid.origin):
        with pytest.raises(ValueError, match="read-only"):
            arr[...] = 0.0
    assert grid.sdf(centre) == before


def test_out_of_bounds_is_where_skrobot_fills():
    data, origin, res = random_grid(seed=3)
    pts = query_points(data, origin, res, seed=4)
    ours = GridSDF(data, origin, res).is_out_of_bounds(pts)
    theirs_filled = ~np.isfinite(skrobot_grid(data, origin, res)(pts))
    np.testing.assert_array_equal(ours, theirs_filled)
    assert ours.sum() > 100 and (~ours).sum() > 100


def test_points_keep_their_leading_shape():
    data, origin, res = ball_grid()
    pts = np.zeros((2, 5, 3))
    assert GridSDF(data, origin, res).sdf(pts).shape == (2, 5)
    assert GridSDF(data, origin, res).gradient(pts).shape == (2, 5, 3)
    assert GridSDF(data, origin, res).sdf([0.0, 0.0, 0.0]).shape == ()


def test_static_rotated_frame_matches_skrobot_with_the_same_pose():
    data, origin, res = random_grid(seed=5)
    t = np.array([0.3, -1.2, 0.5])
    q = Rotation.random(rng=np.random.default_rng(6)).as_quat(scalar_first=True)
    rbm.register_frame("world")
    rbm.register_frame("object", parent="world", translation=t, rotation=q)
    pts_grid = query_points(data, origin, res, seed=7)
    pts_world = Rotation.from_quat(q, scalar_first=True).apply(pts_grid) + t
    grid = GridSDF(data, origin, res, frame="object")
    ours = grid.sdf(pts_world, frame="world")
    theirs = skrobot_grid(data, origin, res, pose=(t, q))(pts_world)
    # rounding decides for points on the boundary itself (the nodes there)
    lower, upper = grid.bounds
    edge = np.any(
        np.isclose(pts_grid, lower, atol=1e-9) | np.isclose(pts_grid, upper, atol=1e-9),
        axis=1,
    )
    np.testing.assert_array_equal(np.isfinite(ours)[~edge], np.isfinite(theirs)[~edge])
    finite = np.isfinite(ours) & np.isfinite(theirs)
    np.testing.assert_allclose(ours[finite], theirs[finite], rtol=0, atol=1e-9)
    # the grid's own frame needs no lookup, and the frame may be given as object
    np.testing.assert_allclose(
        grid.sdf(pts_grid[finite], frame=rbm.registry["object"]),
        GridSDF(data, origin, res).sdf(pts_grid[finite]),
        atol=1e-15,
    )


def moving_object():
    """world -> object moving along x and turning about z, 21 samples over 2 s."""
    ts = np.linspace(0.0, 2.0, 21)
    t = np.c_[ts, 0.2 * np.sin(ts), np.zeros_like(ts)]
    q = Rotation.from_euler("z", 0.8 * ts[:, None]).as_quat(scalar_first=True)
    rbm.register_frame("world")
    rbm.register_frame(
        "object", parent="world", translation=t, rotation=q, timestamps=ts
    )
    return ts, t, q


def test_moving_frame_at_its_samples_matches_skrobot_pose_by_pose():
    ts, t, q = moving_object()
    data, origin, res = ball_grid()
    grid = GridSDF(data, origin, res, frame="object")
    rng = np.random.default_rng(8)
    # unsorted, repeated timestamps: one per point
    which = rng.integers(0, len(ts), 3000)
    pts = rng.uniform(-0.8, 2.8, (3000, 3)) * [1, 0.3, 0.3]
    ours = grid.sdf(pts, frame="world", timestamps=ts[which])
    for i in np.unique(which):
        sel = which == i
        theirs = skrobot_grid(data, origin, res, pose=(t[i], q[i]))(pts[sel])
        np.testing.assert_array_equal(np.isfinite(ours[sel]), np.isfinite(theirs))
        finite = np.isfinite(theirs)
        np.testing.assert_allclose(ours[sel][finite], theirs[finite], atol=1e-9)
    assert np.isfinite(ours).sum() > 300


def test_moving_frame_between_samples_uses_the_core_interpolation():
    moving_object()
    data, origin, res = ball_grid()
    grid = GridSDF(data, origin, res, frame="object")
    times = np.array([0.05, 1.37, 0.05, 1.99])
    pts = np.array([[0.1, 0.0, 0.0], [1.2, 0.1, 0.0], [0.0, 0.2, 0.1], [2.1, 0.1, 0.0]])
    # the same points placed in the object frame by the public core API
    in_object = np.array(
        [
            rbm.transform_points(p[None], into="object", outof="world", timestamps=[s])[
                0
            ]
            for p, s in zip(pts, times, strict=True)
        ]
    )
    np.testing.assert_allclose(
        grid.sdf(pts, frame="world", timestamps=times),
        GridSDF(data, origin, res).sdf(in_object),
        atol=1e-12,
    )


def test_timestamps_along_the_first_axis_of_a_cloud():
    moving_object()
    data, origin, res = ball_grid()
    grid = GridSDF(data, origin, res, frame="object")
    clouds = np.random.default_rng(9).uniform(-0.5, 2.5, (4, 10, 3)) * [1, 0.2, 0.2]
    times = np.array([0.3, 0.1, 1.5, 0.3])
    out = grid.sdf(clouds, frame="world", timestamps=times)
    assert out.shape == (4, 10)
    for i in range(4):
        np.testing.assert_allclose(
            out[i], grid.sdf(clouds[i], frame="world", timestamps=np.full(10, times[i]))
        )


unit_quaternions = (
    st.tuples(*[st.floats(-1, 1, allow_nan=False)] * 4)
    .filter(lambda q: np.linalg.norm(q) > 0.1)
    .map(lambda q: np.array(q) / np.linalg.norm(q))
)
offsets = st.tuples(*[st.floats(-5, 5, allow_nan=False)] * 3).map(np.array)


@settings(max_examples=40, deadline=None)
@given(offsets, unit_quaternions, st.integers(0, 2**32 - 1))
def test_distances_do_not_depend_on_the_frame_the_points_are_given_in(t, q, seed):
    rbm.clear_registry()
    rbm.register_frame("world")
    rbm.register_frame("object", parent="world", translation=t, rotation=q)
    data, origin, res = ball_grid()
    grid = GridSDF(data, origin, res, frame="object")
    local = np.random.default_rng(seed).uniform(-0.55, 0.55, (50, 3))
    world = Rotation.from_quat(q, scalar_first=True).apply(local) + t
    np.testing.assert_allclose(
        grid.sdf(world, frame="world"), grid.sdf(local), rtol=0, atol=1e-9
    )
    np.testing.assert_allclose(
        grid.gradient(world, frame="world"),
        Rotation.from_quat(q, scalar_first=True).apply(grid.gradient(local)),
        atol=1e-6,
    )


# -- gradients ---------------------------------------------------------------------


def test_gradients_match_central_differences_of_skrobot():
    data, origin, res = random_grid(seed=10)
    oracle = skrobot_grid(data, origin, res)
    rng = np.random.default_rng(11)
    # points well inside cells: the interpolant is smooth there
    cell = np.stack([rng.integers(0, s - 1, 500) for s in data.shape], axis=1)
    frac = rng.uniform(0.1, 0.9, (500, 3))
    pts = origin + (cell + frac) * res
    h = 1e-6
    expected = np.stack(
        [(oracle(pts + h * e) - oracle(pts - h * e)) / (2 * h) for e in np.eye(3)],
        axis=1,
    )
    ours = GridSDF(data, origin, res).gradient(pts)
    np.testing.assert_allclose(ours, expected, atol=1e-6)


def test_gradients_are_represented_in_the_query_frame():
    ts, t, q = moving_object()
    data, origin, res = ball_grid()
    grid = GridSDF(data, origin, res, frame="object")
    rng = np.random.default_rng(12)
    local = rng.normal(size=(200, 3))
    local *= 0.45 / np.linalg.norm(local, axis=1, keepdims=True)
    idx = rng.integers(0, len(ts), 200)
    rot = Rotation.from_quat(q[idx], scalar_first=True)
    world = rot.apply(local) + t[idx]
    g_world = grid.gradient(world, frame="world", timestamps=ts[idx], normalize=True)
    g_local = GridSDF(data, origin, res).gradient(local, normalize=True)
    np.testing.assert_allclose(g_world, rot.apply(g_local), atol=1e-9)
    # a ball's normals point away from its centre, to within the grid's error
    radial = world - t[idx]
    radial /= np.linalg.norm(radial, axis=1, keepdims=True)
    assert np.min(np.einsum("ij,ij->i", g_world, radial)) > 0.99


def test_gradient_outside_is_nan_and_use_abs_flips_inside():
    data, origin, res = ball_grid()
    signed = GridSDF(data, origin, res)
    unsigned = GridSDF(data, origin, res, use_abs=True)
    assert np.isnan(signed.gradient([[5.0, 0.0, 0.0]])).all()
    p = [[0.11, 0.02, 0.03], [0.5, 0.01, 0.02]]  # inside, outside the ball
    np.testing.assert_allclose(unsigned.gradient(p)[0], -signed.gradient(p)[0])
    np.testing.assert_allclose(unsigned.gradient(p)[1], signed.gradient(p)[1])


# -- rays ------------------------------------------------------------------------------


def test_ray_hits_match_skrobot_ray_marching():
    data, origin, res = ball_grid()
    grid = GridSDF(data, origin, res)
    rng = np.random.default_rng(13)
    # origins inside the grid (skrobot's marcher has no box entry) aimed at the ball
    starts = rng.uniform(-0.55, 0.55, (300, 3))
    starts = starts[np.linalg.norm(starts, axis=1) > 0.4]
    targets = rng.normal(size=starts.shape) * 0.05
    dirs = targets - starts
    hits = grid.ray_hits(starts, dirs, tolerance=1e-10)
    assert hits.hit.all()
    tips, _ = skrobot_sdf.signed_distance_function.ray_marching(
        starts.copy(), dirs.copy(), skrobot_grid(data, origin, res), 1e-9
    )
    np.testing.assert_allclose(hits.points, tips, atol=1e-8)
    np.testing.assert_allclose(grid.sdf(hits.points), 0.0, atol=1e-9)
    # the default tolerance stops within 1e-4 cells of the surface
    default = grid.ray_hits(starts, dirs)
    assert np.all(np.abs(grid.sdf(default.points)) <= 1e-4 * res)


def test_ray_hits_on_a_ball_are_where_geometry_says():
    data, origin, res = ball_grid(n=61, resolution=0.02)
    grid = GridSDF(data, origin, res)
    rng = np.random.default_rng(14)
    n = 500
    starts = rng.normal(size=(n, 3))
    starts *= 2.0 / np.linalg.norm(starts, axis=1, keepdims=True)  # outside the grid
    aim = rng.normal(size=(n, 3)) * 0.2
    dirs = aim - starts
    hits = grid.ray_hits(starts, dirs)
    u = dirs / np.linalg.norm(dirs, axis=1, keepdims=True)
    # analytic ray-sphere intersection
    b = np.einsum("ij,ij->i", starts, u)
    disc = b**2 - (np.einsum("ij,ij->i", starts, starts) - RADIUS**2)
    expected_hit = disc > 0
    clear = np.abs(disc) > 0.02  # not grazing within the grid's error
    np.testing.assert_array_equal(hits.hit[clear], expected_hit[clear])
    both = hits.hit & expected_hit & clear
    expected_t = -b[both] - np.sqrt(disc[both])
    np.testing.assert_allclose(hits.distances[both], expected_t, atol=0.2 * res)
    np.testing.assert_allclose(
        hits.points[both], starts[both] + expected_t[:, None] * u[both], atol=0.2 * res
    )
    normals = hits.points[both] / np.linalg.norm(hits.points[both], axis=1)[:, None]
    assert np.min(np.einsum("ij,ij->i", hits.normals[both], normals)) > 0.99
    assert np.isnan(hits.points[~hits.hit]).all()
    assert np.isnan(hits.distances[~hits.hit]).all()


def test_ray_hits_limits_and_starts_inside():
    data, origin, res = ball_grid()
    grid = GridSDF(data, origin, res)
    o = [[-2.0, 0.0, 0.0], [-2.0, 0.0, 0.0], [0.0, 0.0, 0.0], [-2.0, 0.0, 0.0]]
    d = [[1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]
    hits = grid.ray_hits(o, d, max_distance=[1.8, 1.6, 1.0, 10.0])
    np.testing.assert_array_equal(hits.hit, [True, False, True, False])
    assert hits.distances[0] == pytest.approx(1.7, abs=1e-3)
    assert hits.distances[2] == 0.0


def test_gaze_rays_from_a_moving_frame_hit_a_moving_object():
    ts, t, q = moving_object()
    rbm.register_frame("eye", parent="world", translation=[0.0, -1.5, 0.0])
    data, origin, res = ball_grid()
    grid = GridSDF(data, origin, res, frame="object")
    # the eye looks at the object's centre at every sample
    to_centre = t - [0.0, -1.5, 0.0]
    hits = grid.ray_hits(np.zeros((len(ts), 3)), to_centre, frame="eye", timestamps=ts)
    assert hits.hit.all()
    np.testing.assert_allclose(
        hits.distances, np.linalg.norm(to_centre, axis=1) - RADIUS, atol=0.1 * res
    )
    in_world = hits.points + [0.0, -1.5, 0.0]
    np.testing.assert_allclose(
        np.linalg.norm(in_world - t, axis=1), RADIUS, atol=0.1 * res
    )
    # normals face the eye (represented in the eye frame, which is not rotated)
    assert np.all(np.einsum("ij,ij->i", hits.normals, to_centre) < 0)


# -- meshes -------------------------------------------------------------------------------


def box_sdf(points, half):
    q = np.abs(points) - half
    outside = np.linalg.norm(np.maximum(q, 0.0), axis=-1)
    inside = np.minimum(np.max(q, axis=-1), 0.0)
    return outside + inside


def test_from_mesh_box_is_exact_at_the_nodes(tmp_path):
    extents = np.array([0.3, 0.2, 0.1])
    box = trimesh.creation.box(extents=extents)
    grid = GridSDF.from_mesh(box, 0.02, padding=0.05)
    lower, upper = grid.bounds
    assert np.all(lower <= -extents / 2 - 0.05 + 1e-12)
    assert np.all(upper >= extents / 2 + 0.05 - 1e-12)
    axes = [lower[a] + np.arange(grid.shape[a]) * 0.02 for a in range(3)]
    nodes = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)
    np.testing.assert_allclose(grid.data, box_sdf(nodes, extents / 2), atol=1e-12)
    # same field from a file and from (vertices, faces)
    path = tmp_path / "box.obj"  # STL would round the vertices to float32
    box.export(path)
    np.testing.assert_allclose(
        GridSDF.from_mesh(path, 0.02, padding=0.05).data, grid.data, atol=1e-9
    )
    np.testing.assert_allclose(
        GridSDF.from_mesh((box.vertices, box.faces), 0.02, padding=0.05).data,
        grid.data,
    )


def test_from_mesh_matches_trimesh_signed_distance():
    sphere = trimesh.creation.icosphere(subdivisions=2, radius=0.2)
    grid = GridSDF.from_mesh(sphere, 0.025)
    rng = np.random.default_rng(15)
    idx = np.stack([rng.integers(0, s, 300) for s in grid.shape], axis=1)
    nodes = grid.origin + idx * grid.resolution
    expected = -trimesh.proximity.signed_distance(sphere, nodes)  # trimesh: + inside
    np.testing.assert_allclose(grid.data[tuple(idx.T)], expected, atol=1e-9)


def test_from_mesh_signs_a_hollow_shell_and_its_cavity():
    outer = trimesh.creation.icosphere(subdivisions=2, radius=0.3)
    inner = trimesh.creation.icosphere(subdivisions=2, radius=0.15)
    inner.invert()  # faces towards the cavity: the solid is the shell between
    shell = trimesh.util.concatenate([outer, inner])
    assert shell.is_watertight
    grid = GridSDF.from_mesh(shell, 0.02)
    probes = np.array([[0.0, 0.0, 0.0], [0.22, 0.0, 0.0], [0.0, 0.0, 0.38]])
    d = grid.sdf(probes)
    assert d[0] > 0.1  # the cavity is outside the solid
    assert d[1] < -0.05  # inside the shell's wall
    assert d[2] > 0.05
    idx = np.stack(
        [np.random.default_rng(16).integers(0, s, 400) for s in grid.shape], 1
    )
    nodes = grid.origin + idx * grid.resolution
    expected = -trimesh.proximity.signed_distance(shell, nodes)
    np.testing.assert_allclose(grid.data[tuple(idx.T)], expected, atol=1e-9)


def test_from_mesh_signs_every_node_like_the_winding_number():
    # the region shortcut against a winding number at every node
    from rbm_nb._door.unpack import kernel_array
    from rbm_nb._kernels.sdf import winding_numbers

    mesh = trimesh.creation.torus(major_radius=0.2, minor_radius=0.06)
    grid = GridSDF.from_mesh(mesh, 0.02)
    axes = [grid.origin[a] + np.arange(grid.shape[a]) * 0.02 for a in range(3)]
    nodes = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    # kernels take what the door makes (trimesh's cached arrays are read-only)
    triangles = kernel_array(mesh.triangles)
    inside = np.abs(winding_numbers(nodes, triangles)) > 0.5
    signed = grid.data.reshape(-1)
    np.testing.assert_array_equal((signed < 0)[signed != 0], inside[signed != 0])
    assert inside.sum() > 100


@pytest.mark.parametrize("n_triangles", [1, 3, 5, 60])
def test_mesh_distance_kernel_against_brute_force(n_triangles):
    from rbm_nb._kernels.sdf import mesh_distances

    rng = np.random.default_rng(n_triangles)
    triangles = rng.normal(size=(n_triangles, 3, 3))
    triangles[0, 2] = triangles[0, 1]  # a degenerate (zero-area) triangle too
    points = rng.normal(size=(300, 3)) * 2
    # naive twin: trimesh's closest point on every triangle, smallest distance
    pairs_t = np.repeat(triangles, len(points), axis=0)
    pairs_p = np.tile(points, (n_triangles, 1))
    closest = trimesh.triangles.closest_point(pairs_t, pairs_p)
    naive = np.linalg.norm(closest - pairs_p, axis=1).reshape(n_triangles, -1).min(0)
    np.testing.assert_allclose(mesh_distances(points, triangles), naive, atol=1e-9)


def test_from_mesh_refuses_open_meshes_unless_unsigned():
    box = trimesh.creation.box(extents=[0.2, 0.2, 0.2])
    open_box = trimesh.Trimesh(box.vertices, box.faces[:-2])
    with pytest.raises(ValueError, match="watertight"):
        GridSDF.from_mesh(open_box, 0.05)
    grid = GridSDF.from_mesh(open_box, 0.05, use_abs=True)
    assert grid.use_abs and np.all(grid.data >= 0)


def test_missing_extra_is_named(monkeypatch):
    monkeypatch.setitem(sys.modules, "trimesh", None)
    with pytest.raises(ImportError, match=r"rbm_nb\[sdf\]"):
        GridSDF.from_mesh("whatever.stl", 0.1)
    monkeypatch.setitem(sys.modules, "skimage.measure", None)
    data, origin, res = ball_grid()
    with pytest.raises(ImportError, match=r"rbm_nb\[sdf\]"):
        GridSDF(data, origin, res).surface_mesh()


def test_surface_mesh_lies_on_the_zero_level_and_faces_outwards():
    data, origin, res = ball_grid()
    grid = GridSDF(data, origin, res)
    vertices, faces = grid.surface_mesh()
    # marching cubes interpolates linearly along cell edges, where the
    # trilinear field is linear too: its vertices are zeros (skimage works
    # in float32, hence the tolerance)
    np.testing.assert_allclose(grid.sdf(vertices), 0.0, atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(vertices, axis=1), RADIUS, atol=0.01)
    mesh = trimesh.Trimesh(vertices, faces)
    assert mesh.is_watertight and mesh.volume > 0
    centres = mesh.triangles_center
    assert np.mean(np.einsum("ij,ij->i", mesh.face_normals, centres) > 0) == 1.0
    with pytest.raises(ValueError, match="not crossed"):
        grid.surface_mesh(level=5.0)


class RecordingScene:
    """Stands in for Scene: records what add_mesh received."""

    def add_mesh(self, frame, mesh, **style):
        self.frame, self.style = frame, style
        with open(mesh) as f:
            self.text = f.read()
        return object.__new__(type("Handle", (), {}))


def test_add_to_scene_hands_the_level_set_to_add_mesh():
    rbm.register_frame("world")
    data, origin, res = ball_grid()
    grid = GridSDF(data, origin, res, frame="world")
    scene = RecordingScene()
    grid.add_to_scene(scene, color="#ff0000", opacity=0.4)
    vertices, faces = grid.surface_mesh()
    lines = scene.text.splitlines()
    assert sum(line.startswith("v ") for line in lines) == len(vertices)
    assert sum(line.startswith("f ") for line in lines) == len(faces)
    assert scene.frame == "world"
    assert scene.style["color"] == "#ff0000" and scene.style["opacity"] == 0.4
    with pytest.raises(ValueError, match="not attached to a frame"):
        GridSDF(data, origin, res).add_to_scene(scene)


def test_add_to_scene_with_the_real_scene(recording_comm):
    pytest.importorskip("meshcat")
    from rbm_nb.scene import Scene

    moving_object()
    data, origin, res = ball_grid()
    scene = Scene("world")
    handle = GridSDF(data, origin, res, frame="object").add_to_scene(scene)
    assert handle is not None


# -- bad input -------------------------------------------------------------------------


def test_bad_construction_is_refused():
    data, origin, res = ball_grid()
    with pytest.raises(ValueError, match="sdf_data"):
        GridSDF(np.zeros((3, 3)), origin, res)
    with pytest.raises(ValueError, match="sdf_data"):
        GridSDF(np.zeros((3, 1, 3)), origin, res)
    with pytest.raises(ValueError, match="sdf_data"):
        GridSDF(np.full((3, 3, 3), np.nan), origin, res)
    with pytest.raises(ValueError, match="origin"):
        GridSDF(data, [0.0, 0.0], res)
    with pytest.raises(ValueError, match="resolution"):
        GridSDF(data, origin, 0.0)
    with pytest.raises(ValueError, match="resolution"):
        GridSDF(data, origin, "fine")
    with pytest.raises(ValueError, match="fill_value"):
        GridSDF(data, origin, res, fill_value=np.nan)
    with pytest.raises(TypeError, match="frame"):
        GridSDF(data, origin, res, frame=3)


def test_bad_queries_are_refused_with_clear_messages():
    moving_object()
    rbm.register_frame("elsewhere")  # a second tree
    data, origin, res = ball_grid()
    grid = GridSDF(data, origin, res, frame="object")
    pts = np.zeros((3, 3))
    with pytest.raises(ValueError, match="points"):
        grid.sdf(np.zeros((3, 2)))
    with pytest.raises(ValueError, match="points"):
        grid.sdf([[np.nan, 0.0, 0.0]])
    with pytest.raises(ValueError, match="pass timestamps"):
        grid.sdf(pts, frame="world")
    with pytest.raises(ValueError, match="outside the time range"):
        grid.sdf(pts, frame="world", timestamps=[0.5, 1.0, 7.0])
    with pytest.raises(ValueError, match=r"timestamps must have shape \(3,\)"):
        grid.sdf(pts, frame="world", timestamps=[0.5, 1.0])
    with pytest.raises(ValueError, match="only used together with frame"):
        grid.sdf(pts, timestamps=[0.5, 1.0, 1.5])
    with pytest.raises(ValueError, match="nowhere"):
        grid.sdf(pts, frame="nowhere")
    with pytest.raises(ValueError, match="not attached to a frame"):
        GridSDF(data, origin, res).sdf(pts, frame="world")
    with pytest.raises(ValueError, match="directions"):
        grid.ray_hits(pts, [0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="max_distance"):
        grid.ray_hits(pts, [1.0, 0.0, 0.0], max_distance=-1.0)
    with pytest.raises(ValueError, match="tolerance"):
        grid.ray_hits(pts, [1.0, 0.0, 0.0], tolerance=0.0)
    with pytest.raises(ValueError, match="broadcast"):
        grid.ray_hits(pts, np.ones((2, 3)))
    with pytest.raises(ValueError):
        grid.sdf(pts, frame="elsewhere", timestamps=[0.5, 1.0, 1.5])
    with pytest.raises(ValueError, match="faces"):
        GridSDF.from_mesh((np.zeros((3, 3)), [[0, 1, 5]]), 0.1)
    with pytest.raises(ValueError, match="does not exist"):
        GridSDF.from_mesh("/no/such/mesh.stl", 0.1)
    with pytest.raises(ValueError, match="resolution"):
        GridSDF.from_mesh(trimesh.creation.box(), -1.0)
    with pytest.raises(ValueError, match="coarser"):
        GridSDF.from_mesh(trimesh.creation.box(), 1e-4)


def test_the_package_exposes_sdf_lazily():
    assert rbm.sdf.GridSDF is GridSDF


def test_docstring_examples_run():
    import doctest
    import importlib

    attempted = 0
    for name in ("rbm_nb.sdf", "rbm_nb.sdf._grid", "rbm_nb.sdf._mesh"):
        module = importlib.import_module(name)
        result = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE)
        assert result.failed == 0, name
        attempted += result.attempted
    assert attempted > 0
