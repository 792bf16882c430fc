"""rbm_nb.coordinates: conversions, round trips, DataArray behaviour, bad input."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import rbm_nb as rbm
from rbm_nb.core.coordinates import (
    cartesian_to_polar,
    cartesian_to_spherical,
    polar_to_cartesian,
    spherical_to_cartesian,
    transform_coordinates,
)

RNG = np.random.default_rng(3)


def test_known_values():
    np.testing.assert_allclose(
        cartesian_to_polar([[1.0, 1.0], [0, -2]]),
        [[np.sqrt(2), np.pi / 4], [2, -np.pi / 2]],
    )
    np.testing.assert_allclose(polar_to_cartesian([2.0, np.pi / 2]), [0, 2], atol=1e-15)
    # ISO 80000-2: theta is the polar angle from +z, phi the azimuth from +x
    np.testing.assert_allclose(cartesian_to_spherical([0.0, 0, -3]), [3, np.pi, 0])
    np.testing.assert_allclose(
        cartesian_to_spherical([0.0, 2, 0]), [2, np.pi / 2, np.pi / 2]
    )
    np.testing.assert_allclose(
        spherical_to_cartesian([2.0, np.pi / 2, np.pi]), [-2, 0, 0], atol=1e-15
    )
    # the origin is well defined (arccos(z / r) would give NaN)
    np.testing.assert_array_equal(cartesian_to_spherical([0.0, 0, 0]), [0, 0, 0])


def test_axis_argument():
    xy = RNG.standard_normal((5, 2))
    np.testing.assert_allclose(
        cartesian_to_polar(xy.T, axis=0), cartesian_to_polar(xy).T
    )
    xyz = RNG.standard_normal((4, 3, 5))
    moved = np.moveaxis(cartesian_to_spherical(np.moveaxis(xyz, 1, -1)), -1, 1)
    np.testing.assert_allclose(cartesian_to_spherical(xyz, axis=1), moved)
    np.testing.assert_allclose(spherical_to_cartesian(moved, axis=1), xyz)


finite = st.floats(-1e6, 1e6)


@settings(max_examples=100, deadline=None)
@given(arrays(np.float64, (3, 2), elements=finite))
def test_property_polar_round_trip(xy):
    np.testing.assert_allclose(
        polar_to_cartesian(cartesian_to_polar(xy)), xy, rtol=1e-9, atol=1e-6
    )


@settings(max_examples=100, deadline=None)
@given(arrays(np.float64, (3, 3), elements=finite))
def test_property_spherical_round_trip(xyz):
    sph = cartesian_to_spherical(xyz)
    assert np.all(sph[:, 0] >= 0) and np.all((sph[:, 1] >= 0) & (sph[:, 1] <= np.pi))
    np.testing.assert_allclose(spherical_to_cartesian(sph), xyz, rtol=1e-9, atol=1e-6)


@settings(max_examples=100, deadline=None)
@given(
    st.floats(1e-3, 1e3),
    st.floats(1e-3, np.pi - 1e-3),
    st.floats(-np.pi + 1e-3, np.pi),
)
def test_property_spherical_inverse_round_trip(r, theta, phi):
    np.testing.assert_allclose(
        cartesian_to_spherical(spherical_to_cartesian([r, theta, phi])),
        [r, theta, phi],
        rtol=1e-9,
        atol=1e-12,  # angles near zero (even subnormal) compare absolutely
    )


def test_transform_coordinates_arrays():
    xyz = RNG.standard_normal((6, 3))
    np.testing.assert_allclose(
        transform_coordinates(xyz, "spherical", outof="cartesian"),
        cartesian_to_spherical(xyz),
    )
    np.testing.assert_allclose(
        transform_coordinates(xyz.T, "spherical", outof="cartesian", axis=0),
        cartesian_to_spherical(xyz).T,
    )
    assert rbm.transform_coordinates is transform_coordinates


def make_da():
    return xr.DataArray(
        RNG.standard_normal((5, 3)),
        {
            "time": np.arange(5.0),
            "cartesian_axis": ["x", "y", "z"],
            "label": ("cartesian_axis", list("abc")),
        },
        ("time", "cartesian_axis"),
        name="gaze",
        attrs={"coordinate_system": "cartesian", "units": "m"},
    )


def test_transform_coordinates_dataarray_replaces_dim():
    da = make_da()
    out = transform_coordinates(da, "spherical")
    assert out.dims == ("time", "spherical_axis")
    assert list(out.spherical_axis.values) == ["r", "theta", "phi"]
    assert "label" not in out.coords and "cartesian_axis" not in out.coords
    assert out.attrs == {"coordinate_system": "spherical", "units": "m"}
    assert out.name == "gaze"
    np.testing.assert_array_equal(out.time, da.time)
    np.testing.assert_allclose(out.values, cartesian_to_spherical(da.values))
    back = transform_coordinates(out, "cartesian")
    assert back.dims == da.dims and list(back.cartesian_axis.values) == ["x", "y", "z"]
    np.testing.assert_allclose(back.values, da.values)
    assert da.attrs["coordinate_system"] == "cartesian"  # input untouched


def test_transform_coordinates_dataarray_options():
    da = make_da()
    kept = transform_coordinates(da, "spherical", replace_dim=False)
    assert kept.dims == da.dims and "label" in kept.coords
    transposed = transform_coordinates(da.T, "spherical", dim="cartesian_axis")
    assert transposed.dims == ("spherical_axis", "time")
    # without a coordinate_system entry, attrs stay as they are
    plain = da.copy()
    plain.attrs = {"units": "m"}
    out = transform_coordinates(plain, "spherical", outof="cartesian")
    assert out.attrs == {"units": "m"}
    polar = xr.DataArray(RNG.standard_normal((4, 2)), dims=("time", "xy"))
    out = transform_coordinates(polar, "polar", outof="cartesian")
    assert out.dims == ("time", "polar_axis") and list(out.polar_axis.values) == [
        "r",
        "phi",
    ]


@pytest.mark.parametrize(
    "call,match",
    [
        (lambda: cartesian_to_polar(np.ones((4, 3))), "length 2"),
        (lambda: polar_to_cartesian(np.ones(3)), "length 2"),
        (lambda: cartesian_to_spherical(np.ones((4, 2))), "length 3"),
        (lambda: spherical_to_cartesian(np.ones((2, 4)), axis=0), "length 3"),
        (lambda: cartesian_to_spherical(1.0), "scalar"),
        (lambda: cartesian_to_spherical(np.ones(3), axis=2), "out of range"),
        (lambda: transform_coordinates(np.ones(3), "spherical"), "outof must be given"),
        (
            lambda: transform_coordinates(np.ones(3), "polar", outof="spherical"),
            "cannot transform",
        ),
        (
            lambda: transform_coordinates(np.ones(3), "cartesian", outof="cartesian"),
            "cannot transform",
        ),
        (
            lambda: transform_coordinates(np.ones(3), "polar", outof="cartesian"),
            "length 2",
        ),
        (
            lambda: transform_coordinates(
                np.ones(3), "spherical", outof="cartesian", dim="c"
            ),
            "DataArray",
        ),
        (
            lambda: transform_coordinates(make_da(), "spherical", dim="nope"),
            "not a dimension",
        ),
        (
            lambda: transform_coordinates(make_da(), "spherical", dim="time", axis=0),
            "either dim or axis",
        ),
    ],
)
def test_bad_input_raises_value_error(call, match):
    with pytest.raises(ValueError, match=match):
        call()
