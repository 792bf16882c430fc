"""Fill numba's on-disk cache with every rbm_nb kernel, so first calls are fast.

Binder's ``postBuild`` runs ``python -P -m rbm_nb._warmup`` once, while the
image is built. Each step below calls public functions on tiny inputs, in all
the variants that give a kernel a distinct type signature: static, moving,
inverse and discrete frames; float and datetime64 timestamps (int64 sort
keys); read-only frame arrays; both angular velocity modes with outlier
rejection and low-pass filtering; estimators, conversions, the tf2-style
``Transformer``, the ``DataArray.rbm`` accessor and the synthetic recording.
A later process then loads the compiled kernels instead of compiling them.
The meshcat scene has no kernels of its own: a player step is a binary search
and a 4 x 4 matrix in numpy, and the lookups it makes when objects are added
are the ones warmed here.

Why the cache is found again: numba stores it next to the kernel sources
(``rbm_nb/_kernels/__pycache__``, inside site-packages for a normal install)
and keys it on each source file's path and modification time, the function's
bytecode and the CPU. Building the image neither moves nor touches the
installed files after this has run, so the notebooks' first cell finds it.
Run it from outside the repository (``-P`` or another working directory) so
that it compiles the installed package rather than the source tree.

The frame registry is left as it was: the frames here are never registered
(the API accepts frame objects wherever it accepts names), and anything that
appears in the registry anyway is removed again.
"""

from __future__ import annotations

import importlib
import pkgutil
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

N_SAMPLES = 40  # enough for the low-pass filter (more than 24 samples)
START = np.datetime64("2021-06-01T12:00:00", "ns")
# generous, so that no series loses all its samples; the kernels run all the same
OUTLIER_THRESH = 1.0


@dataclass(frozen=True)
class KernelStats:
    """Signatures compiled and loaded from the cache, over all rbm_nb kernels."""

    kernels: int
    compiled: int
    loaded: int
    cache_dirs: tuple[str, ...]


def kernel_dispatchers() -> list:
    """Every numba dispatcher defined in ``rbm_nb._kernels`` (imports the modules)."""
    from numba.core.dispatcher import Dispatcher

    from . import _kernels

    found = []
    for info in pkgutil.iter_modules(_kernels.__path__):
        module = importlib.import_module(f"{_kernels.__name__}.{info.name}")
        for value in vars(module).values():
            if isinstance(value, Dispatcher) and value.__module__ == module.__name__:
                found.append(value)
    return found


def kernel_stats() -> KernelStats:
    """Totals of this process so far: what numba compiled, what it loaded."""
    dispatchers = kernel_dispatchers()
    compiled = loaded = 0
    dirs = set()
    for d in dispatchers:
        stats = d.stats
        compiled += sum(stats.cache_misses.values())
        loaded += sum(stats.cache_hits.values())
        if stats.cache_path:
            dirs.add(str(stats.cache_path))
    return KernelStats(len(dispatchers), compiled, loaded, tuple(sorted(dirs)))


# ---------------------------------------------------------------------------
# inputs
# ---------------------------------------------------------------------------


def _times(kind: str, n: int = N_SAMPLES, step: float = 0.01, offset: float = 0.0):
    seconds = offset + step * np.arange(n)
    if kind == "float":
        return seconds
    return START + (seconds * 1e9).astype("timedelta64[ns]")


def _motion(n: int = N_SAMPLES, phase: float = 0.0):
    """A smooth translation (n, 3) and unit rotation (n, 4) with a little noise."""
    s = np.linspace(0.0, 1.0, n) + phase
    translation = np.column_stack([np.sin(s), np.cos(2 * s), 0.1 * s])
    angle = 0.5 * s
    axis = np.array([0.3, -0.2, 0.9]) / np.linalg.norm([0.3, -0.2, 0.9])
    rotation = np.column_stack([np.cos(angle / 2), np.outer(np.sin(angle / 2), axis)])
    return translation, rotation


def _tree(kind: str):
    """A tree with every kind of frame, none of them registered."""
    from .frames import ReferenceFrame

    t, r = _motion()
    t2, r2 = _motion(N_SAMPLES, phase=0.3)
    world = ReferenceFrame("warmup-world")
    frames = {
        "world": world,
        "static": ReferenceFrame(
            "warmup-static", world, translation=(1.0, 0.0, 0.5), rotation=r[3]
        ),
        "static_inverse": ReferenceFrame(
            "warmup-static-inverse",
            world,
            translation=(0.0, 2.0, 0.0),
            rotation=r[7],
            inverse=True,
        ),
        "moving": ReferenceFrame(
            "warmup-moving", world, translation=t, rotation=r, timestamps=_times(kind)
        ),
    }
    frames["child"] = ReferenceFrame(
        "warmup-child",
        frames["moving"],
        translation=t2,
        rotation=r2,
        timestamps=_times(kind, step=0.013, offset=0.002),
    )
    frames["moving_inverse"] = ReferenceFrame(
        "warmup-moving-inverse",
        frames["static"],
        translation=t2,
        rotation=r2,
        timestamps=_times(kind, step=0.009),
        inverse=True,
    )
    frames["discrete"] = ReferenceFrame(
        "warmup-discrete",
        world,
        translation=t[::5],
        rotation=r[::5],
        timestamps=_times(kind, N_SAMPLES // 5, step=0.05),
        discrete=True,
    )
    frames["discrete_child"] = ReferenceFrame(
        "warmup-discrete-child",
        frames["discrete"],
        translation=t2[::4],
        rotation=r2[::4],
        timestamps=_times(kind, N_SAMPLES // 4, step=0.04, offset=0.01),
        discrete=True,
    )
    frames["from_matrix"] = ReferenceFrame.from_rotation_matrix(
        np.array([[0.0, 0.0, -1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]),
        frames["moving"],
        "warmup-from-matrix",
        inverse=True,
    )
    frames["single"] = ReferenceFrame(
        "warmup-single",
        world,
        translation=t[:1],
        rotation=r[:1],
        timestamps=_times(kind, 1),
    )
    return frames


# ---------------------------------------------------------------------------
# steps
# ---------------------------------------------------------------------------


def _quaternion_utilities() -> None:
    from . import quaternions as q

    t, r = _motion()
    _, r2 = _motion(phase=0.2)
    q.from_euler_angles(rpy=t)
    q.from_euler_angles(roll=t[:, 0], pitch=t[:, 1], yaw=t[:, 2], order="ypr")
    q.from_euler_angles(yaw=0.3, return_quaternion=True)
    q.qinv(r)
    q.qinv(r[0])
    q.qmul(r, r2)
    q.qmul(r[0], r2, r)
    q.qmean(r)
    q.qmean(np.stack([r, r2]), axis=0)
    for kind in ("float", "datetime"):
        ts = _times(kind)
        q.qinterp(r, ts, ts[1:-1] + (ts[1] - ts[0]) / 2)
    q.rotate_vectors(r, t)
    q.rotate_vectors(r[0], t)
    q.rotate_vectors(r, t[:5], one_to_one=False)
    q.rotate_vectors(r.T, t.T, axis=0, qaxis=0)


def _lookups(kind: str) -> None:
    from . import _at_time, lookups

    f = _tree(kind)
    pairs = [
        ("static", "static_inverse"),  # static only
        ("child", "world"),  # moving chain, two timestamp tracks
        ("world", "child"),  # the same, inverted
        ("moving_inverse", "child"),  # inverse frames on both sides
        ("static", "moving"),
        ("discrete_child", "world"),  # discrete only: union of events
        ("discrete", "moving"),  # discrete held at the moving timestamps
        ("single", "moving"),  # a one-sample moving frame
        ("from_matrix", "static"),
    ]
    for outof, into in pairs:
        lookups.lookup_transform(f[outof], f[into], return_timestamps=True)
        lookups.lookup_pose(f[outof], f[into])
    lookups.lookup_transform(f["child"], f["world"], as_dataset=True)
    lookups.lookup_pose(f["child"], f["world"], as_dataset=True)
    times = f["child"].timestamps
    inside = times[3:9][::-1]  # any order, inside the range
    for outof, into in (
        ("child", "world"),
        ("discrete_child", "moving"),
        ("static", "world"),
    ):
        lookups.lookup_transform(f[outof], f[into], time=inside)
        lookups.lookup_transform(f[outof], f[into], time=inside[0])
        lookups.lookup_transform(f[outof], f[into], time=inside, as_matrix=True)
        lookups.lookup_transform(f[outof], f[into], time=inside, as_transform=True)
    lookups.lookup_transform(f["child"], f["world"], as_matrix=True)
    _at_time.latest_common_time(f["child"], f["world"])
    f["child"].lookup_transform(f["static"])


def _transforms(kind: str) -> None:
    from . import transforms as tr

    f = _tree(kind)
    t, r = _motion(12, phase=0.1)
    ts = f["moving"].timestamps[2:14]
    for into, outof in (
        ("static", "world"),
        ("child", "world"),
        ("world", "moving_inverse"),
        ("discrete_child", "world"),
        ("discrete", "static"),
    ):
        a, b = f[into], f[outof]
        tr.transform_points(t[0], a, b)
        tr.transform_vectors(t[0], a, b)
        tr.transform_quaternions(r[0], a, b)
        tr.transform_points(t, a, b, timestamps=ts, return_timestamps=True)
        tr.transform_vectors(t, a, b, timestamps=ts)
        tr.transform_quaternions(r, a, b, timestamps=ts)
        # several vectors per time step, time not first
        tr.transform_points(np.stack([t, t]), a, b, timestamps=ts, time_axis=1)
        tr.transform_quaternions(np.stack([r, r], axis=1), a, b, timestamps=ts, axis=2)
    if kind == "float":  # static arrays through a static chain
        tr.transform_points(t, f["static"], f["static_inverse"])
        tr.transform_quaternions(r, f["static"], f["static_inverse"])


def _velocities(kind: str) -> None:
    from . import lookups
    from . import transforms as tr

    f = _tree(kind)
    moving, child, world = f["moving"], f["child"], f["world"]
    for options in (
        {},
        {"outlier_thresh": OUTLIER_THRESH},
        {"cutoff": 0.3},
        {"outlier_thresh": OUTLIER_THRESH, "cutoff": 0.3},
    ):
        for mode in ("quaternion", "rotation_vector"):
            lookups.lookup_twist(child, world, mode=mode, **options)
            lookups.lookup_angular_velocity(
                child, world, represent_in=child, mode=mode, **options
            )
        lookups.lookup_linear_velocity(child, world, represent_in=moving, **options)
    lookups.lookup_twist(moving, as_dataset=True)
    lookups.lookup_linear_velocity(moving, as_dataarray=True)
    lookups.lookup_angular_velocity(moving, as_dataarray=True)
    lookups.lookup_twist(f["moving_inverse"], child)
    ts = child.timestamps
    v, _ = lookups.lookup_twist(child, moving)  # child wrt moving, at ts
    changes = (
        # (what changes, from, to, the other frame the linear velocity needs)
        ("reference_frame", moving, world, {"moving_frame": child}),
        ("moving_frame", child, f["static"], {"reference_frame": world}),
        ("representation_frame", moving, world, {}),
    )
    for what, outof, into, other in changes:
        tr.transform_angular_velocity(v, into, outof, what=what, timestamps=ts)
        tr.transform_angular_velocity(
            v, into, outof, what=what, timestamps=ts, cutoff=0.3
        )
        tr.transform_linear_velocity(v, into, outof, what=what, timestamps=ts, **other)
        tr.transform_linear_velocity(
            v,
            into,
            outof,
            what=what,
            timestamps=ts,
            cutoff=0.3,
            outlier_thresh=OUTLIER_THRESH,
            **other,
        )


def _estimators() -> None:
    from . import estimators as est

    t, r = _motion()
    flipped = r.copy()
    flipped[10:20] *= -1  # sign flips are handled by the kernels
    for kind in ("float", "datetime"):
        ts = _times(kind)
        for options in ({}, {"outlier_thresh": OUTLIER_THRESH}, {"cutoff": 0.3}):
            est.estimate_linear_velocity(t, timestamps=ts, **options)
            for mode in ("quaternion", "rotation_vector"):
                est.estimate_angular_velocity(
                    flipped, timestamps=ts, mode=mode, **options
                )
    gappy = r.copy()
    gappy[5] = np.nan  # dropped samples take another path
    est.estimate_angular_velocity(gappy, timestamps=_times("float"))
    est.estimate_linear_velocity(np.stack([t, t], axis=1), timestamps=_times("float"))
    est.estimate_angular_velocity(np.stack([r, r], axis=1), timestamps=_times("float"))
    est.shortest_arc_rotation(t[0], t[1])
    est.shortest_arc_rotation(t, t[::-1])
    rotated = est.best_fit_rotation(t, t[::-1])
    est.best_fit_transform(t, t[::-1] + 1.0)
    est.iterative_closest_point(
        t, t[::-1] + 0.01, init_transform=((0.0, 0, 0), rotated)
    )
    est.iterative_closest_point(t[:20], t + 0.01)


def _conversions() -> None:
    from . import conversions as cv
    from .rigid_transform import Transform

    t, r = _motion(8)
    m = cv.matrix_from_quaternion(r)
    cv.quaternion_from_matrix(m)
    cv.matrix_from_quaternion(r[0])
    rv = cv.rotation_vector_from_quaternion(r)
    cv.quaternion_from_rotation_vector(rv)
    axis, angle = cv.axis_angle_from_quaternion(r)
    cv.quaternion_from_axis_angle(axis, angle)
    for extrinsic in (False, True):
        e = cv.euler_from_quaternion(r, "zyx", extrinsic=extrinsic)
        cv.quaternion_from_euler(e, "zyx", extrinsic=extrinsic)
        cv.euler_from_quaternion(r, "xyx", extrinsic=extrinsic, degrees=True)
    h = cv.homogeneous_from_transform(t, r)
    cv.transform_from_homogeneous(h)
    a, b = Transform(t, r), Transform(t[::-1], r[::-1])
    single = Transform(t[0], r[0])
    (a @ b).inv()
    (single @ a).apply(t)
    a.apply_vectors(t)
    a.as_matrix()
    Transform.from_matrix(h)
    a.slerp(b, 0.25)
    a.lerp(b, np.linspace(0, 1, len(t)))
    a.difference(b)
    Transform.identity((3,)).allclose(Transform.identity((3,)))


def _ros_transformer() -> None:
    from .ros.transformer import Transformer

    f = _tree("float")
    tf = Transformer.from_reference_frame(f["world"])
    t = float(f["child"].timestamps[5])
    tf.lookup_transform("warmup-world", "warmup-child", time=t)
    tf.transform_point((1.0, 2.0, 3.0), "warmup-world", "warmup-child", time=t)
    tf.transform_vector((1.0, 2.0, 3.0), "warmup-static", "warmup-child", time=t)
    tf.transform_quaternion(
        (1.0, 0.0, 0.0, 0.0), "warmup-world", "warmup-child", time=t
    )
    tf.transform_pose(
        (1.0, 2.0, 3.0), (1.0, 0.0, 0.0, 0.0), "warmup-world", "warmup-discrete"
    )
    tf.set_transform(
        (0.0, 0.0, 1.0), (1.0, 0.0, 0.0, 0.0), "warmup-world", "warmup-extra"
    )
    tf.lookup_transform("warmup-extra", "warmup-moving", time=t)


def _xarray() -> None:
    import xarray as xr

    from . import accessors  # noqa: F401  (registers DataArray.rbm)
    from . import transforms as tr
    from .frames import ReferenceFrame

    t, r = _motion()
    ds = xr.Dataset(
        {
            "position": (("time", "cartesian_axis"), t),
            "orientation": (("time", "quaternion_axis"), r),
        },
        coords={
            "time": _times("datetime"),
            "cartesian_axis": list("xyz"),
            "quaternion_axis": list("wxyz"),
        },
    )
    world = ReferenceFrame("warmup-world")
    head = ReferenceFrame.from_dataset(
        ds, "position", "orientation", "time", world, "warmup-head"
    )
    ReferenceFrame.from_translation_dataarray(ds.position, "time", world, "warmup-t")
    ReferenceFrame.from_rotation_dataarray(ds.orientation, "time", world, "warmup-r")
    ds.orientation.rbm.qinterp(time=ds.time[1:-1] + np.timedelta64(5, "ms"))
    ds.orientation.rbm.qinv()
    tr.transform_points(ds.position, head, world, dim="cartesian_axis")
    tr.transform_quaternions(ds.orientation, head, world, dim="quaternion_axis")


def _read_only_inputs() -> None:
    # A frame's translation, rotation and timestamps are read-only arrays, and
    # numba compiles read-only arguments separately: users pass them straight
    # on (``rbm.qinterp(rf.rotation, rf.timestamps, t)``), so warm those too.
    from . import conversions as cv
    from . import estimators as est
    from . import lookups
    from . import quaternions as q
    from . import transforms as tr
    from .frames import ReferenceFrame
    from .rigid_transform import Transform

    for kind in ("float", "datetime"):
        f = _tree(kind)
        t, r, ts = (
            f["moving"].translation,
            f["moving"].rotation,
            f["moving"].timestamps,
        )
        ReferenceFrame(
            "warmup-copy", f["world"], translation=t, rotation=r, timestamps=ts
        )
        q.qinterp(r, ts, ts)
        q.qinterp(r, ts, ts[1:-1] + (ts[1] - ts[0]) / 2)
        lookups.lookup_transform(
            f["child"], f["world"], time=f["child"].timestamps[2:5]
        )
        for into, outof in (
            ("static", "world"),
            ("child", "world"),
            ("discrete", "static"),
        ):
            tr.transform_points(t, f[into], f[outof], timestamps=ts)
            tr.transform_vectors(t, f[into], f[outof], timestamps=ts)
            tr.transform_quaternions(r, f[into], f[outof], timestamps=ts)
        for options in ({}, {"outlier_thresh": OUTLIER_THRESH}, {"cutoff": 0.3}):
            est.estimate_linear_velocity(t, timestamps=ts, **options)
            for mode in ("quaternion", "rotation_vector"):
                est.estimate_angular_velocity(r, timestamps=ts, mode=mode, **options)
    q.from_euler_angles(rpy=t)
    q.qinv(r)
    q.qmul(r, r)
    q.qmean(r)
    q.rotate_vectors(r, t)
    q.rotate_vectors(r, t[:5], one_to_one=False)
    tr.transform_points(t[0], f["static"], f["world"])
    est.shortest_arc_rotation(t, t[::-1])
    est.best_fit_rotation(t, t[::-1])
    est.best_fit_transform(t, t[::-1])
    est.iterative_closest_point(t, t[::-1])
    cv.matrix_from_quaternion(r)
    cv.quaternion_from_matrix(cv.matrix_from_quaternion(r)[:1].copy())
    cv.rotation_vector_from_quaternion(r)
    cv.axis_angle_from_quaternion(r)
    cv.euler_from_quaternion(r)
    cv.quaternion_from_euler(t)
    cv.quaternion_from_rotation_vector(t)
    cv.homogeneous_from_transform(t, r)
    a = Transform(t, r)
    a.apply(t)
    a.apply_vectors(t)
    a.slerp(a, 0.5)
    a.difference(a)


def _signed_distances() -> None:
    from .sdf import GridSDF

    axis = np.linspace(-1.0, 1.0, 5)
    x, y, z = np.meshgrid(axis, axis, axis, indexing="ij")
    grid = GridSDF(np.sqrt(x**2 + y**2 + z**2) - 0.5, [-1.0, -1.0, -1.0], 0.5)
    points = np.array([[0.1, 0.2, 0.3], [3.0, 0.0, 0.0]])
    grid.sdf(points)
    grid.gradient(points)
    grid.ray_hits(points - [2.0, 0.0, 0.0], [1.0, 0.0, 0.0])
    try:  # meshes need the optional 'sdf' extra
        import trimesh  # noqa: F401
    except ImportError:
        return
    tetrahedron = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    faces = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    GridSDF.from_mesh((tetrahedron, faces), 0.5)


def _synthetic_data() -> None:
    from .data.synthetic import synthetic_head_eye

    synthetic_head_eye(duration=15.0)


STEPS: tuple[tuple[str, Callable[[], None]], ...] = (
    ("quaternion utilities", _quaternion_utilities),
    ("lookups, float timestamps", lambda: _lookups("float")),
    ("lookups, datetime64 timestamps", lambda: _lookups("datetime")),
    ("transforms, float timestamps", lambda: _transforms("float")),
    ("transforms, datetime64 timestamps", lambda: _transforms("datetime")),
    ("velocities, float timestamps", lambda: _velocities("float")),
    ("velocities, datetime64 timestamps", lambda: _velocities("datetime")),
    ("estimators", _estimators),
    ("conversions and Transform", _conversions),
    ("ros Transformer", _ros_transformer),
    ("xarray frames and accessor", _xarray),
    ("read-only inputs (frame properties)", _read_only_inputs),
    ("synthetic recording", _synthetic_data),
    ("signed distance grids", _signed_distances),
)


def warm_up(verbose: bool = False) -> KernelStats:
    """Call every numba-backed code path once so that its kernels are cached.

    Parameters
    ----------
    verbose : bool, default False
        Print one line per step (name, seconds, signatures compiled).

    Returns
    -------
    KernelStats
        What this process compiled and loaded from the cache in total
        (``compiled == 0`` after a previous warm-up: the cache is effective).
    """
    from .frames import deregister_frame, registry

    before = dict(registry)
    try:
        for name, step in STEPS:
            start, compiled = time.perf_counter(), kernel_stats().compiled
            step()
            if verbose:
                print(
                    f"  {name}: {time.perf_counter() - start:.1f} s, "
                    f"{kernel_stats().compiled - compiled} compiled"
                )
    finally:
        for name in [n for n in registry if n not in before]:
            deregister_frame(name)
    return kernel_stats()


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    verbose = "-v" in argv or "--verbose" in argv
    start = time.perf_counter()
    stats = warm_up(verbose=verbose)
    where = ", ".join(stats.cache_dirs) or "no cache directory"
    print(
        f"rbm_nb warm-up: {stats.compiled} kernel signatures compiled, "
        f"{stats.loaded} loaded from the cache ({stats.kernels} kernels), "
        f"{time.perf_counter() - start:.1f} s; cache: {where}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
