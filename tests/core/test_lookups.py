"""lookup_* functions: return conventions, datasets and defaults."""

from __future__ import annotations

import numpy as np
import pytest

import rbm_nb as rbm

xr = pytest.importorskip("xarray")
ref = pytest.importorskip("rigid_body_motion")


def _register(module, datetime=False):
    n = 200
    t = np.arange(n) * 0.01
    ts = (np.arange(n) * 10_000_000).astype("datetime64[ns]") if datetime else t
    rot = np.column_stack(
        [np.cos(t / 2), np.sin(t / 2) * 0.6, np.zeros(n), np.sin(t / 2) * 0.8]
    )
    trans = np.column_stack([np.sin(t), np.cos(2 * t), t**2])
    module.register_frame("world")
    module.register_frame(
        "body", parent="world", translation=trans, rotation=rot, timestamps=ts
    )
    module.register_frame(
        "cam",
        parent="body",
        translation=(0.1, 0, 0.2),
        rotation=(np.sqrt(0.5), np.sqrt(0.5), 0, 0),
    )
    module.register_frame("static", parent="world", translation=(0, 1, 0))


@pytest.fixture
def trees():
    ref.clear_registry()
    _register(rbm)
    _register(ref)
    yield
    ref.clear_registry()


def test_lookup_transform_return_conventions(trees):
    out = rbm.lookup_transform("cam", "world")
    assert len(out) == 2 and out[0].shape == (200, 3) and out[1].shape == (200, 4)
    t, r, ts = rbm.lookup_transform("cam", "world", return_timestamps=True)
    assert ts.shape == (200,)
    t, r, ts = rbm.lookup_transform("static", "world", return_timestamps=True)
    assert t.shape == (3,) and r.shape == (4,) and ts is None


@pytest.mark.parametrize("func", ["lookup_transform", "lookup_pose"])
def test_datasets_equal_the_reference(trees, func):
    for a, b in (("cam", "world"), ("static", "cam"), ("static", "world")):
        got = getattr(rbm, func)(a, b, as_dataset=True)
        expected = getattr(ref, func)(a, b, as_dataset=True)
        xr.testing.assert_allclose(got, expected)
        for name in got.data_vars:
            assert got[name].attrs == expected[name].attrs
        assert list(got.data_vars) == list(expected.data_vars)


def test_twist_dataset_and_velocity_dataarrays_equal_the_reference(trees):
    got = rbm.lookup_twist("cam", "world", represent_in="body", as_dataset=True)
    expected = ref.lookup_twist("cam", "world", represent_in="body", as_dataset=True)
    xr.testing.assert_allclose(got, expected)
    for name in got.data_vars:
        assert got[name].attrs == expected[name].attrs
    for func in ("lookup_linear_velocity", "lookup_angular_velocity"):
        got = getattr(rbm, func)("cam", "world", as_dataarray=True)
        expected = getattr(ref, func)("cam", "world", as_dataarray=True)
        xr.testing.assert_allclose(got, expected)
        assert got.attrs == expected.attrs and got.name == expected.name


def test_velocity_lookup_defaults(trees):
    # top level: reference defaults to the parent, represent_in to the reference
    np.testing.assert_allclose(
        rbm.lookup_linear_velocity("body"),
        rbm.lookup_linear_velocity("body", "world", "world"),
    )
    # frame level: represent_in defaults to the parent
    cam = rbm.registry["cam"]
    np.testing.assert_allclose(
        cam.lookup_angular_velocity("world"),
        rbm.lookup_angular_velocity("cam", "world", "body"),
    )
    lin, ang, ts = rbm.lookup_twist("body", return_timestamps=True)
    assert lin.shape == ang.shape == (200, 3) and ts.shape == (200,)


@pytest.mark.parametrize("datetime", [False, True])
def test_filters_and_modes_equal_the_reference(datetime):
    ref.clear_registry()
    _register(rbm, datetime)
    _register(ref, datetime)
    try:
        for kwargs in (
            {"cutoff": 0.3},
            {"outlier_thresh": 1e-3},
            {"mode": "rotation_vector"},
        ):
            got = rbm.lookup_twist("cam", "world", **kwargs)
            expected = ref.lookup_twist("cam", "world", **kwargs)
            for g, e in zip(got, expected, strict=True):
                np.testing.assert_allclose(g, e, rtol=1e-6, atol=1e-9)
            if "mode" not in kwargs:
                got = rbm.lookup_linear_velocity("cam", "world", **kwargs)
                expected = ref.lookup_linear_velocity("cam", "world", **kwargs)
                np.testing.assert_allclose(got, expected, rtol=1e-6, atol=1e-9)
            got = rbm.lookup_angular_velocity("cam", "world", **kwargs)
            expected = ref.lookup_angular_velocity("cam", "world", **kwargs)
            np.testing.assert_allclose(got, expected, rtol=1e-6, atol=1e-9)
    finally:
        ref.clear_registry()


def test_static_velocity(trees):
    static = rbm.registry["static"]
    lin, ang, ts = static.lookup_twist(allow_static=True, return_timestamps=True)
    np.testing.assert_array_equal(lin, np.zeros(3))
    np.testing.assert_array_equal(ang, np.zeros(3))
    assert ts is None
    assert static.lookup_linear_velocity(allow_static=True).shape == (3,)
    with pytest.raises(ValueError, match="static"):
        rbm.lookup_twist("static")


def test_lookups_see_re_registered_frames(trees):
    before, _ = rbm.lookup_transform("cam", "world")
    n = 200
    rbm.register_frame(
        "body",
        parent="world",
        translation=np.ones((n, 3)),
        timestamps=np.arange(n) * 0.01,
        update=True,
    )
    after, _ = rbm.lookup_transform("cam", "world")
    assert not np.allclose(before, after)
    np.testing.assert_allclose(after[:, 1], 1.0)


def test_the_plain_call_is_lookup_at_and_hands_out_copies():
    """lookup_transform(outof, into) takes a short path; it must give what
    the general one gives, and arrays the caller may change."""
    from rbm_nb.core.lookups import lookup_at

    rbm.clear_registry()
    rbm.register_frame("world")
    rbm.register_frame("a", parent="world", translation=(1.0, 2.0, 3.0),
                       rotation=(np.cos(0.3), 0.0, np.sin(0.3), 0.0))  # fmt: skip
    ts = np.arange(20) * 0.1
    rbm.register_frame("m", parent="a", translation=np.ones((20, 3)) * ts[:, None],
                       rotation=np.tile([1.0, 0.0, 0.0, 0.0], (20, 1)), timestamps=ts)  # fmt: skip
    for outof, into in (("a", "world"), ("world", "a"), ("m", "world"), ("world", "m")):
        t, r = rbm.lookup_transform(outof, into)
        t_at, r_at = lookup_at(outof, into)
        np.testing.assert_array_equal(t, t_at)
        np.testing.assert_array_equal(r, r_at)
        t[...] = 99.0
        r[...] = 99.0
        np.testing.assert_array_equal(rbm.lookup_transform(outof, into)[0], t_at)
    with pytest.raises(ValueError, match="into"):
        rbm.lookup_transform("nowhere", "nothere")
    rbm.clear_registry()
