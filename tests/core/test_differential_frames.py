"""rbm_nb against rigid-body-motion 0.9.3 on randomly generated frame trees.

Every tree mixes static, moving, inverse and discrete frames with different
sampling rates and time offsets, with float or datetime64 timestamps. For
each tree, lookups and transforms between several frame pairs must give the
reference's timestamps (to 1e-9) and values (rtol 1e-6; quaternions up to
sign). Datetime trees start at the epoch so that the reference's conversion
of nanoseconds to float is exact and both sides compute with the same times.
"""

from __future__ import annotations

import numpy as np
import pytest

import rbm_nb as rbm

ref = pytest.importorskip("rigid_body_motion")

N_TREES = 30
RTOL = 1e-6


# ---------------------------------------------------------------------------
# tree generation
# ---------------------------------------------------------------------------


def _rotation_walk(rng, n, step):
    q = np.cumsum(rng.normal(scale=step, size=(n, 4)), axis=0) + rng.normal(size=4)
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    for i in range(1, n):
        if q[i] @ q[i - 1] < 0:
            q[i] = -q[i]
    return q


def _times(rng, start, stop, rate, datetime):
    t = np.arange(start, stop, 1.0 / rate)
    if datetime:
        # whole microseconds keep float conversions exact on both sides
        return (np.round(t * 1e6).astype(np.int64) * 1000).astype("datetime64[ns]")
    return t


def make_tree(seed):
    """A list of (name, kwargs) for register_frame, plus tree-wide facts."""
    rng = np.random.default_rng(seed)
    datetime = bool(seed % 3 == 2)
    specs = [("world", {})]
    names = ["world"]
    n_frames = int(rng.integers(4, 7))
    for k in range(n_frames):
        name = f"f{k}"
        parent = names[int(rng.integers(len(names)))]
        kind = rng.choice(
            ["static", "moving", "moving", "discrete"], p=[0.3, 0.25, 0.25, 0.2]
        )
        kwargs = {"parent": parent, "inverse": bool(rng.random() < 0.35)}
        if kind == "static":
            kwargs["translation"] = rng.normal(size=3)
            kwargs["rotation"] = _rotation_walk(rng, 1, 0.1)[0]
        elif kind == "moving":
            rate = float(rng.choice([20.0, 50.0, 100.0, 33.0]))
            start = rng.uniform(0.0, 0.4)
            stop = rng.uniform(2.0, 2.6)
            ts = _times(rng, start, stop, rate, datetime)
            n = len(ts)
            tt = np.linspace(0, 1, n)[:, None]
            kwargs["timestamps"] = ts
            kwargs["translation"] = rng.normal(size=3) + np.sin(
                2 * np.pi * tt * rng.uniform(0.2, 1.5, 3)
            ) * rng.normal(size=3)
            kwargs["rotation"] = _rotation_walk(rng, n, 0.3 / np.sqrt(rate))
        else:
            n_events = int(rng.integers(3, 8))
            events = np.sort(rng.uniform(-0.3, 2.8, n_events))
            events = np.unique(np.round(events, 3))
            if datetime:
                events_ns = np.round(events * 1e6).astype(np.int64) * 1000
                kwargs["timestamps"] = events_ns.astype("datetime64[ns]")
            else:
                kwargs["timestamps"] = events
            kwargs["translation"] = rng.normal(size=(len(events), 3))
            kwargs["rotation"] = _rotation_walk(rng, len(events), 0.3)
            kwargs["discrete"] = True
        specs.append((name, kwargs))
        names.append(name)
    return specs, datetime, rng


def register_both(specs):
    for name, kwargs in specs:
        rbm.register_frame(name, **kwargs)
        ref.register_frame(name, **kwargs)


@pytest.fixture(autouse=True)
def _clear_reference_registry():
    ref.clear_registry()
    yield
    ref.clear_registry()


# ---------------------------------------------------------------------------
# comparison helpers
# ---------------------------------------------------------------------------


def same_ts(got, expected):
    if expected is None:
        assert got is None
        return
    assert got is not None and got.shape == expected.shape
    if expected.dtype.kind == "M":
        assert got.dtype.kind == "M"
        np.testing.assert_array_equal(
            got.astype("datetime64[ns]"), expected.astype("datetime64[ns]")
        )
    else:
        np.testing.assert_allclose(got, expected, rtol=0, atol=1e-9)


def close(got, expected, scale=1.0):
    got = np.asarray(got)
    expected = np.asarray(expected)
    assert got.shape == expected.shape, (got.shape, expected.shape)
    np.testing.assert_allclose(got, expected, rtol=RTOL, atol=1e-9 * scale)


def close_quat(got, expected):
    got = np.asarray(got)
    expected = np.asarray(expected)
    assert got.shape == expected.shape, (got.shape, expected.shape)
    sign = np.sign(np.sum(got * expected, axis=-1, keepdims=True))
    sign[sign == 0] = 1
    np.testing.assert_allclose(got * sign, expected, rtol=RTOL, atol=1e-9)


def both(name, *args, **kwargs):
    """Call ``name`` of both packages; if the reference raises ValueError,
    rbm_nb must raise too (then both results are None)."""
    try:
        expected = getattr(ref, name)(*args, **kwargs)
    except ValueError:
        with pytest.raises(ValueError):
            getattr(rbm, name)(*args, **kwargs)
        return None, None
    return getattr(rbm, name)(*args, **kwargs), expected


def pairs(specs, rng, k=5):
    names = [n for n, _ in specs]
    out = []
    for _ in range(k):
        a, b = rng.choice(names, size=2, replace=False)
        out.append((str(a), str(b)))
    return out


def array_times(rng, datetime):
    rate = float(rng.choice([15.0, 40.0, 70.0]))
    start = rng.uniform(-0.2, 0.6)
    stop = rng.uniform(1.8, 2.9)
    return _times(rng, start, stop, rate, datetime)


# ---------------------------------------------------------------------------
# tests
# ---------------------------------------------------------------------------

SEEDS = list(range(N_TREES))


@pytest.mark.parametrize("seed", SEEDS)
def test_lookup_transform_and_pose(seed):
    specs, _, rng = make_tree(seed)
    register_both(specs)
    for a, b in pairs(specs, rng):
        got, expected = both("lookup_transform", a, b, return_timestamps=True)
        if expected is not None:
            close(got[0], expected[0], 10)
            close_quat(got[1], expected[1])
            same_ts(got[2], expected[2])
        got, expected = both("lookup_pose", a, b, return_timestamps=True)
        if expected is not None:
            close(got[0], expected[0], 10)
            close_quat(got[1], expected[1])
            same_ts(got[2], expected[2])


@pytest.mark.parametrize("seed", SEEDS)
def test_transforms_of_arrays(seed):
    specs, datetime, rng = make_tree(seed)
    register_both(specs)
    for a, b in pairs(specs, rng, k=4):
        ts = array_times(rng, datetime)
        n = len(ts)
        points = rng.normal(size=(n, 3))
        quats = _rotation_walk(rng, n, 0.1)
        for name, arr, is_quat in (
            ("transform_points", points, False),
            ("transform_vectors", points, False),
            ("transform_quaternions", quats, True),
        ):
            got, expected = both(
                name, arr, into=b, outof=a, timestamps=ts, return_timestamps=True
            )
            if expected is None:
                continue
            (close_quat if is_quat else close)(got[0], expected[0])
            same_ts(got[1], expected[1])
        # a single untimestamped point / quaternion
        for name, arr, is_quat in (
            ("transform_points", points[0], False),
            ("transform_quaternions", quats[0], True),
        ):
            got, expected = both(name, arr, into=b, outof=a, return_timestamps=True)
            if expected is not None:
                (close_quat if is_quat else close)(got[0], expected[0])
                same_ts(got[1], expected[1])


def _velocity_pairs(specs, rng, k=4):
    """Pairs whose transform is moving, so that velocities exist."""
    out = []
    names = [n for n, _ in specs]
    for _ in range(40):
        a, b = (str(x) for x in rng.choice(names, size=2, replace=False))
        _, _, ts = ref.lookup_transform(a, b, return_timestamps=True)
        if ts is not None and len(ts) > 30:
            out.append((a, b, str(rng.choice(names))))
        if len(out) == k:
            break
    return out


@pytest.mark.parametrize("seed", SEEDS)
def test_velocity_lookups(seed):
    specs, _, rng = make_tree(seed)
    register_both(specs)
    for a, b, c in _velocity_pairs(specs, rng):
        for represent_in in (None, c):
            got, expected = both(
                "lookup_twist", a, b, represent_in, return_timestamps=True
            )
            if expected is not None:
                close(got[0], expected[0], 100)
                close(got[1], expected[1], 100)
                same_ts(got[2], expected[2])
            for name in ("lookup_linear_velocity", "lookup_angular_velocity"):
                got, expected = both(name, a, b, represent_in, return_timestamps=True)
                if expected is not None:
                    close(got[0], expected[0], 100)
                    same_ts(got[1], expected[1])


@pytest.mark.parametrize("seed", SEEDS)
def test_velocity_transforms(seed):
    specs, datetime, rng = make_tree(seed)
    register_both(specs)
    for a, b, c in _velocity_pairs(specs, rng, k=3):
        ts = array_times(rng, datetime)
        arr = rng.normal(size=(len(ts), 3))
        for what in ("reference_frame", "moving_frame", "representation_frame"):
            got, expected = both(
                "transform_angular_velocity",
                arr,
                into=b,
                outof=a,
                what=what,
                timestamps=ts,
                return_timestamps=True,
            )
            if expected is not None:
                close(got[0], expected[0], 100)
                same_ts(got[1], expected[1])
            extra = (
                {"moving_frame": c}
                if what == "reference_frame"
                else {"reference_frame": c}
            )
            got, expected = both(
                "transform_linear_velocity",
                arr,
                into=b,
                outof=a,
                what=what,
                timestamps=ts,
                return_timestamps=True,
                **extra,
            )
            if expected is not None:
                close(got[0], expected[0], 100)
                same_ts(got[1], expected[1])


@pytest.mark.parametrize("seed", SEEDS[:10])
def test_dataarray_transforms(seed):
    xr = pytest.importorskip("xarray")
    specs, datetime, rng = make_tree(seed)
    register_both(specs)
    for a, b in pairs(specs, rng, k=2):
        ts = array_times(rng, datetime)
        da = xr.DataArray(
            rng.normal(size=(len(ts), 3)),
            coords={
                "time": ts,
                "cartesian_axis": ["x", "y", "z"],
                "quality": ("time", rng.random(len(ts))),
            },
            dims=("time", "cartesian_axis"),
            name="position",
            attrs={"reference_frame": a, "units": "m"},
        )
        got, expected = both("transform_points", da, into=b)
        if expected is None:
            continue
        close(got.values, expected.values)
        same_ts(got.time.values, expected.time.values)
        close(got.quality.values, expected.quality.values)
        assert got.attrs == expected.attrs
        assert got.dims == expected.dims and got.name == expected.name
