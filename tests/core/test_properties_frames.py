"""Algebraic properties of transforms across frame trees (hypothesis).

Moving frames share their timestamps here, so that resampling is exact and
the properties hold to rounding: a -> b -> a is the identity, a -> b -> c
equals a -> c, and rotations keep vector norms.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import rbm_nb as rbm
from rbm_nb.core import frames

N = 6
TS = np.linspace(0.0, 1.0, N)

finite = st.floats(-5, 5, allow_nan=False, allow_infinity=False)
quaternion = arrays(np.float64, 4, elements=finite).filter(
    lambda q: np.linalg.norm(q) > 0.1
)


@st.composite
def trees(draw):
    """Frame specs: (parent index, moving, inverse, seed) for up to 5 frames."""
    n = draw(st.integers(2, 5))
    return [
        (
            draw(st.integers(0, k)),
            draw(st.booleans()),
            draw(st.booleans()),
            draw(st.integers(0, 2**31)),
        )
        for k in range(n)
    ]


def build(specs):
    frames.clear_registry()
    names = ["root"]
    rbm.register_frame("root")
    for k, (parent, moving, inverse, seed) in enumerate(specs):
        rng = np.random.default_rng(seed)
        name = f"f{k}"
        if moving:
            q = rng.normal(size=(N, 4))
            q /= np.linalg.norm(q, axis=1, keepdims=True)
            rbm.register_frame(
                name, parent=names[parent], translation=rng.normal(size=(N, 3)),
                rotation=q, timestamps=TS, inverse=inverse,
            )  # fmt: skip
        else:
            q = rng.normal(size=4)
            rbm.register_frame(
                name, parent=names[parent], translation=rng.normal(size=3),
                rotation=q / np.linalg.norm(q), inverse=inverse,
            )  # fmt: skip
        names.append(name)
    return names


def pick(draw_data, names, k):
    return [names[draw_data.draw(st.integers(0, len(names) - 1))] for _ in range(k)]


points = arrays(np.float64, (N, 3), elements=finite)


@settings(max_examples=40, deadline=None)
@given(trees(), points, st.data())
def test_there_and_back_is_identity(specs, p, data):
    names = build(specs)
    a, b = pick(data, names, 2)
    there = rbm.transform_points(p, into=b, outof=a, timestamps=TS)
    back = rbm.transform_points(there, into=a, outof=b, timestamps=TS)
    np.testing.assert_allclose(back, p, atol=1e-9)
    q = data.draw(quaternion)
    q = np.tile(q / np.linalg.norm(q), (N, 1))
    there = rbm.transform_quaternions(q, into=b, outof=a, timestamps=TS)
    back = rbm.transform_quaternions(there, into=a, outof=b, timestamps=TS)
    np.testing.assert_allclose(np.abs(np.sum(back * q, axis=1)), 1.0, atol=1e-9)


@settings(max_examples=40, deadline=None)
@given(trees(), points, st.data())
def test_composition_through_an_intermediate_frame(specs, p, data):
    names = build(specs)
    a, b, c = pick(data, names, 3)
    via_b = rbm.transform_points(
        rbm.transform_points(p, into=b, outof=a, timestamps=TS),
        into=c,
        outof=b,
        timestamps=TS,
    )
    direct = rbm.transform_points(p, into=c, outof=a, timestamps=TS)
    np.testing.assert_allclose(via_b, direct, atol=1e-9)
    t_ab, r_ab = rbm.lookup_transform(a, b)
    t_bc, r_bc = rbm.lookup_transform(b, c)
    t_ac, r_ac = rbm.lookup_transform(a, c)
    # static lookups are (3,) / (4,), moving ones (N, 3) / (N, 4)
    t_ab, r_ab, t_bc, r_bc = (
        np.broadcast_to(x, (N, x.shape[-1])) for x in (t_ab, r_ab, t_bc, r_bc)
    )
    t_ac, r_ac = (np.broadcast_to(x, (N, x.shape[-1])) for x in (t_ac, r_ac))
    np.testing.assert_allclose(rbm.rotate_vectors(r_bc, t_ab) + t_bc, t_ac, atol=1e-9)
    r = rbm.qmul(r_bc, r_ab)
    np.testing.assert_allclose(np.abs(np.sum(r * r_ac, axis=-1)), 1.0, atol=1e-9)


@settings(max_examples=40, deadline=None)
@given(trees(), points, st.data())
def test_vectors_keep_their_norm(specs, v, data):
    names = build(specs)
    a, b = pick(data, names, 2)
    out = rbm.transform_vectors(v, into=b, outof=a, timestamps=TS)
    np.testing.assert_allclose(
        np.linalg.norm(out, axis=1), np.linalg.norm(v, axis=1), rtol=1e-10, atol=1e-10
    )
