"""gaze's public calls at one door call each, with their messages (issue 32, item 2).

``gaze.directions`` used to check its arguments itself and then call two
other facades (``rotate_vectors``, ``transform_vectors``), each with its own
door calls: five or six in all. Now each gaze call hands its arguments to
one entry of :mod:`rbm_nb._door.gaze` and computes on the value it gets
back (the rotation kernel and the engine's transform called directly).
The messages are the ones the gaze calls always gave, byte for byte (the
table below was written from the code before the change); times out of
order are refused by ``gaze.rates``, which used to return wrong slopes
without a word.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import rbm_nb as rbm
from rbm_nb import gaze

sys.path.insert(0, str(Path(__file__).parent))
from test_one_door_call import door_calls  # noqa: E402

T = np.arange(5) * 0.1
DT = np.datetime64("2020-01-01", "ns") + np.arange(5) * np.timedelta64(100, "ms")
CONFIDENCE = xr.DataArray(np.ones(5), coords={"time": T}, dims="time")
D = xr.DataArray(
    np.tile([0.0, 0.0, 1.0], (5, 1)), dims=("time", "cartesian_axis"),
    coords={"time": T}, attrs={"representation_frame": "camera"},
)  # fmt: skip
ANGLES = xr.DataArray(np.zeros((5, 2)), dims=("time", "angle"), coords={"time": T})


@pytest.fixture(autouse=True)
def tree():
    rbm.clear_registry()
    rbm.register_frame("world")
    rbm.register_frame(
        "camera", parent="world", timestamps=T,
        rotation=rbm.from_euler_angles(yaw=np.deg2rad(np.arange(5.0))),
    )  # fmt: skip
    q = rbm.from_euler_angles(pitch=np.deg2rad(np.arange(5.0)))
    rbm.register_frame("eye", parent="camera", rotation=q, timestamps=T)
    rbm.register_frame("still", parent="camera")
    rbm.register_frame("deye", parent="camera", rotation=q, timestamps=DT)
    yield
    rbm.clear_registry()


CALLS = [
    ("directions", lambda: gaze.directions("eye", "camera")),
    ("directions into a moving frame", lambda: gaze.directions("eye", "world")),
    ("directions with every option",
     lambda: gaze.directions("eye", "world", confidence=CONFIDENCE, max_gap=0.05,
                             max_angle=50.0)),
    ("directions with an array of confidence",
     lambda: gaze.directions("eye", "camera", confidence=np.linspace(0, 1, 5))),
    ("directions of a static eye", lambda: gaze.directions("still", "world",
                                                           confidence=CONFIDENCE)),
    ("angles", lambda: gaze.angles(D, "camera")),
    ("angles in a moving frame", lambda: gaze.angles(D, "world")),
    ("rates", lambda: gaze.rates(ANGLES)),
]  # fmt: skip


@pytest.mark.parametrize("label, call", CALLS, ids=[c[0] for c in CALLS])
def test_each_gaze_call_calls_the_door_once(label, call):
    call()  # compile, fill the caches
    assert door_calls(call) == 1, label


REGISTERED = "(registered: 'world', 'camera', 'eye', 'still', 'deye')"
MESSAGES = [
    ("d eye missing", lambda: gaze.directions("nope", "camera"),
     f"eye_frame: frame 'nope' not found in registry {REGISTERED}"),
    ("d into missing", lambda: gaze.directions("eye", "nope"),
     f"into: frame 'nope' not found in registry {REGISTERED}"),
    ("d root", lambda: gaze.directions("world", "camera"),
     "eye_frame 'world' is a root frame; it has no orientation to look along"),
    ("d min_confidence str", lambda: gaze.directions("eye", "camera", min_confidence="a"),
     "min_confidence must be a number, got 'a'"),
    ("d min_confidence nan",
     lambda: gaze.directions("eye", "camera", min_confidence=np.nan),
     "min_confidence must be finite, got nan"),
    ("d min_confidence bool",
     lambda: gaze.directions("eye", "camera", min_confidence=True),
     "min_confidence must be a number, got True"),
    ("d max_gap negative", lambda: gaze.directions("eye", "camera", max_gap=-1),
     "max_gap must be positive (seconds), got -1"),
    ("d max_gap nan", lambda: gaze.directions("eye", "camera", max_gap=np.nan),
     "max_gap must be finite, got nan"),
    ("d max_gap str", lambda: gaze.directions("eye", "camera", max_gap="x"),
     "max_gap must be a number, got 'x'"),
    ("d max_angle 0", lambda: gaze.directions("eye", "camera", max_angle=0),
     "max_angle must be in (0, 180] degrees, got 0"),
    ("d max_angle 200", lambda: gaze.directions("eye", "camera", max_angle=200),
     "max_angle must be in (0, 180] degrees, got 200"),
    ("d max_angle inf", lambda: gaze.directions("eye", "camera", max_angle=np.inf),
     "max_angle must be finite, got inf"),
    ("d static", lambda: gaze.directions("still", "camera"),
     "eye_frame 'still' is static; pass confidence as a DataArray with a 'time' "
     "coordinate to give the sample times"),
    ("d confidence 2-d",
     lambda: gaze.directions("eye", "camera", confidence=xr.DataArray(
         np.ones((5, 2)), dims=("time", "x"))),
     "confidence must be a 1-d DataArray along 'time', got dims ('time', 'x')"),
    ("d confidence without time",
     lambda: gaze.directions("eye", "camera",
                             confidence=xr.DataArray(np.ones(5), dims=("t",))),
     "confidence must be a 1-d DataArray along 'time', got dims ('t',)"),
    ("d confidence without time coordinate",
     lambda: gaze.directions("eye", "camera",
                             confidence=xr.DataArray(np.ones(5), dims=("time",))),
     "confidence has a 'time' dimension but no 'time' coordinate"),
    ("d confidence shape", lambda: gaze.directions("eye", "camera", confidence=np.ones(4)),
     "confidence must have shape (5,) like the timestamps of eye_frame 'eye', got (4,)"),
    ("d confidence strings",
     lambda: gaze.directions("eye", "camera", confidence=["a"] * 5),
     "confidence must be an array of numbers"),
    ("d confidence kinds", lambda: gaze.directions("deye", "camera", confidence=CONFIDENCE),
     "confidence times (float64) and the timestamps of eye_frame 'deye' "
     "(datetime64[ns]) must both be datetime64 or both numeric"),
    ("d confidence out of order, into a moving frame",
     lambda: gaze.directions("eye", "world",
                             confidence=CONFIDENCE.isel(time=[0, 2, 1, 3, 4])),
     "timestamps must be strictly increasing: timestamps[2] = 0.1 is earlier than "
     "timestamps[1] = 0.2"),
    ("a not a DataArray", lambda: gaze.angles(np.zeros((5, 3)), "camera"),
     "directions must be a DataArray from gaze.directions, got ndarray"),
    ("a no frame attribute", lambda: gaze.angles(D.copy().assign_attrs(
        representation_frame=None).drop_attrs(), "camera"),
     "directions has no 'representation_frame' attribute naming the frame they are "
     "given in"),
    ("a dims", lambda: gaze.angles(D.rename(cartesian_axis="xyz"), "camera"),
     "directions must have dims ('time', 'cartesian_axis'), got ('time', 'xyz')"),
    ("a forward", lambda: gaze.angles(D, "camera", forward="w"),
     "forward must be one of x, y, z with an optional sign, got 'w'"),
    ("a up", lambda: gaze.angles(D, "camera", up=3),
     "up must be an axis like 'z' or '-y', got 3"),
    ("a up twice signed", lambda: gaze.angles(D, "camera", up="--y"),
     "up must be one of x, y, z with an optional sign, got '--y'"),
    ("a same axes", lambda: gaze.angles(D, "camera", forward="y", up="-y"),
     "forward ('y') and up ('-y') must be different axes"),
    ("a reference missing", lambda: gaze.angles(D, "nope"),
     f"reference: frame 'nope' not found in registry {REGISTERED}"),
    ("a frame missing", lambda: gaze.angles(D.assign_attrs(representation_frame="nope"),
                                            "camera"),
     f"directions' frame: frame 'nope' not found in registry {REGISTERED}"),
    ("a out of order", lambda: gaze.angles(D.isel(time=[0, 2, 1, 3, 4]), "eye"),
     "timestamps must be strictly increasing: timestamps[2] = 0.1 is earlier than "
     "timestamps[1] = 0.2"),
    ("a datetime out of order",
     lambda: gaze.angles(D.assign_coords(time=DT[[0, 2, 1, 3, 4]])
                         .assign_attrs(representation_frame="deye"), "camera"),
     "timestamps must be strictly increasing: timestamps[2] = "
     "2020-01-01T00:00:00.100000000 is earlier than timestamps[1] = "
     "2020-01-01T00:00:00.200000000"),
    ("r not a DataArray", lambda: gaze.rates(np.zeros((5, 2))),
     "angles must be a DataArray with a 'time' dimension"),
    ("r no time", lambda: gaze.rates(ANGLES.rename(time="t")),
     "angles must be a DataArray with a 'time' dimension"),
    ("r window 0", lambda: gaze.rates(ANGLES, window=0),
     "window must be positive (seconds), got 0"),
    ("r window nan", lambda: gaze.rates(ANGLES, window=np.nan),
     "window must be finite, got nan"),
    ("r window str", lambda: gaze.rates(ANGLES, window="x"),
     "window must be a number, got 'x'"),
    # new: the slopes of times out of order were wrong without a word
    ("r out of order", lambda: gaze.rates(ANGLES.isel(time=[0, 2, 1, 3, 4])),
     "angles time must be non-decreasing: angles time[2] = 0.1 is earlier than "
     "angles time[1] = 0.2"),
]  # fmt: skip


@pytest.mark.parametrize("label, call, message", MESSAGES, ids=[m[0] for m in MESSAGES])
def test_gaze_messages(label, call, message):
    with pytest.raises(ValueError) as err:
        call()
    assert str(err.value) == message


def test_rates_of_repeated_times_are_still_slopes():
    # non-decreasing is enough: a repeated stamp is no reason to refuse
    t = np.array([0.0, 0.01, 0.01, 0.02, 0.03])
    angles = xr.DataArray(np.c_[t * 100.0], dims=("time", "angle"), coords={"time": t})
    rate = gaze.rates(angles, window=0.02)
    assert np.nanmax(np.abs(rate.values - 100.0)) < 1e-9
