"""A looked-up chain with one moving frame is composed in one pass (issue 35).

The explorer's tracks (head -> tracker -> world, eye -> scene camera ->
head) have one moving frame between static ones. Their bounds, their coarse
copy and a path's blocks are composed by ``rbm_nb.scene.one_mover`` from
the mover's stored rows, without the engine's windowed lookups, and are the
engine's values bit for bit; an object reaching past the scene's limit is
still refused by name.
"""

from __future__ import annotations

import numpy as np
import pytest

import rbm_nb as rbm
from rbm_nb._engine import chain as _chain
from rbm_nb.scene import Scene
from rbm_nb.scene.looked_up import COARSE_SAMPLES, even_rows
from rbm_nb.scene.tracks import PoseTrack

HZ = 200


def _quaternions(rng, n: int, scale: float) -> np.ndarray:
    q = np.c_[np.ones(n), rng.normal(scale=scale, size=(n, 3))]
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def register_chain(
    seconds: float = 90.0, *, inverse: bool = False, outlier: float | None = None
) -> None:
    """world <- room (static) <- body (moving, NaN runs, masked rows, gaps
    longer than ``max_gap``) <- mount (static) <- sensor (static, inverse)."""
    rng = np.random.default_rng(7)
    rbm.clear_registry()
    rbm.register_frame("world")
    rbm.register_frame(
        "room",
        parent="world",
        translation=(1.5, -2.0, 0.25),
        rotation=_quaternions(rng, 1, 0.4)[0],
    )
    n = int(seconds * HZ)
    start = np.datetime64("2024-03-01T10:00:00", "ns")
    steps = np.full(n - 1, 1e9 / HZ)
    steps[n // 4 :: n // 3] += 4e8  # dropped stretches longer than max_gap
    times = start + np.r_[0, np.cumsum(steps)].astype("timedelta64[ns]")
    walk = np.cumsum(rng.normal(scale=0.01, size=(n, 3)), axis=0)
    rotation = _quaternions(rng, n, 0.3)
    walk[n // 5 : n // 5 + 30] = np.nan  # missing translations
    rotation[n // 2 : n // 2 + 17] = np.nan  # missing rotations only
    if outlier is not None:
        walk[n // 3] = (outlier, 0.0, 0.0)
    missing = np.zeros(n, dtype=bool)
    missing[::53] = True  # low-confidence rows: numbers stored, treated as missing
    rbm.ReferenceFrame(
        name="body",
        parent="room",
        translation=walk,
        rotation=rotation,
        timestamps=times,
        inverse=inverse,
        max_gap=0.1,
        missing=missing,
    ).register()
    rbm.register_frame(
        "mount",
        parent="body",
        translation=(0.1, 0.02, -0.03),
        rotation=_quaternions(rng, 1, 0.5)[0],
    )
    rbm.ReferenceFrame(
        name="sensor",
        parent="mount",
        translation=(0.0, 0.05, 0.01),
        rotation=_quaternions(rng, 1, 0.5)[0],
        inverse=True,
    ).register()


@pytest.fixture(params=[False, True], ids=["forward", "inverse"])
def chain(request):
    register_chain(inverse=request.param)
    yield
    rbm.clear_registry()


# (frame, base): the mover first and raw, after static steps, inverse steps
PAIRS = [("body", "room"), ("body", "world"), ("sensor", "world"), ("sensor", "room")]


def _pair(outof: str, into: str):
    """The same lookup twice: planned, and left to the engine's windows."""
    frame, base = rbm.registry[outof], rbm.registry[into]
    planned = PoseTrack.lookup(frame, base)
    engine = PoseTrack.lookup(frame, base)
    assert planned._mover is not None
    engine._mover = None
    return planned, engine


def _assert_same(got, want) -> None:
    for a, b in zip(got, want, strict=True):
        if b is None:
            assert a is None
        else:
            assert a.dtype == b.dtype
            np.testing.assert_array_equal(a, b)
            # bit for bit, NaN rows and signs of zeros included
            assert a.tobytes() == b.tobytes()


@pytest.mark.parametrize("outof, into", PAIRS)
def test_bounds_are_the_engine_windows_bit_for_bit(chain, outof, into):
    planned, engine = _pair(outof, into)
    for got, want in zip(planned.bounds, engine.bounds, strict=True):
        np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("outof, into", PAIRS)
def test_coarse_rows_and_picks_are_the_stored_samples(chain, outof, into):
    planned, engine = _pair(outof, into)
    planned.bounds  # noqa: B018 - gathers the coarse copy
    engine.bounds  # noqa: B018
    picks = even_rows(len(planned), COARSE_SAMPLES)
    _assert_same(planned.take(picks), engine.take(picks))
    # rows of every kind: hidden ones (after a long gap), masked, missing
    n = len(planned)
    hidden = planned._hidden_rows_at
    assert len(hidden) > 0
    rows = np.unique(np.r_[0, hidden, hidden - 1, np.arange(0, n, 53), n - 1])
    _assert_same(planned.take(rows), engine.take(rows))
    _assert_same(planned.take(even_rows(n, 5000)), engine.take(even_rows(n, 5000)))


@pytest.mark.parametrize("outof, into", PAIRS)
def test_path_blocks_are_the_engine_translations(chain, outof, into):
    planned, engine = _pair(outof, into)
    got = np.concatenate(list(planned.blocks()))
    want = np.concatenate(list(engine.blocks()))
    assert got.tobytes() == want.tobytes()
    assert planned.window(10, 900)[1].tobytes() == engine.window(10, 900)[1].tobytes()


def test_whole_recording_passes_make_no_windowed_lookups(chain, monkeypatch):
    """Bounds, the coarse copy, the saved copy and the path's blocks: no
    call of the engine's ``evaluate`` (which the windows made thousands of)."""
    planned, _ = _pair("sensor", "world")
    calls = []
    real = _chain.evaluate
    monkeypatch.setattr(
        _chain, "evaluate", lambda *a, **k: calls.append(1) or real(*a, **k)
    )
    planned.bounds  # noqa: B018
    planned.take(even_rows(len(planned), COARSE_SAMPLES))
    planned.take(even_rows(len(planned), 5000))
    for _ in planned.blocks():
        pass
    assert calls == []
    planned.window(0, 100)  # a chunk around the playhead: the engine's, as before
    assert calls == [1]


def test_a_chain_with_two_movers_is_left_to_the_engine():
    register_chain()
    rng = np.random.default_rng(1)
    n = 500
    times = np.datetime64("2024-03-01T10:00:00", "ns") + (
        np.arange(n) * 7_000_000
    ).astype("timedelta64[ns]")
    rbm.register_frame(
        "probe",
        parent="sensor",
        translation=rng.normal(size=(n, 3)),
        rotation=_quaternions(rng, n, 0.2),
        timestamps=times,
    )
    track = PoseTrack.lookup(rbm.registry["probe"], rbm.registry["world"])
    assert track._mover is None
    assert track.bounds is not None
    rbm.clear_registry()


@pytest.mark.parametrize("inverse", [False, True])
def test_an_outlier_beyond_the_limit_is_refused_by_name(inverse):
    """One sample 2e9 m away in a composed track (sensor -> world passes
    three static steps): refused, by the object's name."""
    register_chain(inverse=inverse, outlier=2e9)
    try:
        track = PoseTrack.lookup(rbm.registry["sensor"], rbm.registry["world"])
        assert track._mover is not None
        scene = Scene("world", grid=False)
        with pytest.raises(
            ValueError, match=r"add_frame: '\w*sensor' reaches \d(\.\d+)?e\+09 m"
        ):
            scene.add_frame("sensor")
        with pytest.raises(
            ValueError, match=r"add_path: '\w*sensor' reaches \d(\.\d+)?e\+09 m"
        ):
            scene.add_path("sensor")
        scene.close()
    finally:
        rbm.clear_registry()
