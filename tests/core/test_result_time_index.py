"""Results with a time index keep no copy of their times (issue 32, item 2).

pandas 3 copies an array made into an index unless told not to, and the
DataArray constructor deep-copies its coordinates: a velocity DataArray of
an hour of the head's 200 Hz samples held two more copies of its times than
its values need (6 MB in the explorer). The door builds the index over the
times themselves (they are immutable there); what a result keeps is its
values and nothing of the size of its times.
"""

from __future__ import annotations

import numpy as np
import pytest
from memory_support import kept_by

import rbm_nb as rbm

N = 100_000


@pytest.fixture(params=["numeric", "datetime64"])
def head(request):
    rbm.clear_registry()
    rbm.register_frame("world")
    s = np.arange(N) * 0.005
    t = s
    if request.param == "datetime64":
        t = np.datetime64("2020-01-01", "ns") + (s * 1e9).astype("timedelta64[ns]")
    half = 0.5 * np.sin(s)
    rbm.register_frame(
        "head",
        translation=np.c_[s, 0 * s, 0 * s],
        rotation=np.c_[np.cos(half), 0 * s, 0 * s, np.sin(half)],
        timestamps=t,
        parent="world",
    )
    yield
    rbm.clear_registry()


@pytest.mark.parametrize(
    "call, values",
    [
        (lambda: rbm.lookup_angular_velocity("head", "world", as_dataarray=True), 1),
        (lambda: rbm.lookup_linear_velocity("head", "world", as_dataarray=True), 1),
        (lambda: rbm.lookup_twist("head", "world", as_dataset=True), 2),
    ],
    ids=["angular DataArray", "linear DataArray", "twist Dataset"],
)
def test_a_velocity_result_keeps_no_copy_of_its_times(head, call, values):
    call()  # compile, fill the caches
    out, kept = kept_by(call)
    times = N * 8
    # the (N, 3) values, and less than one copy of the times besides
    assert kept < values * N * 3 * 8 + times // 2, kept
    assert not out["time"].values.flags.writeable


def test_the_times_are_the_same_values(head):
    da = rbm.lookup_angular_velocity("head", "world", as_dataarray=True)
    _, ts = rbm.lookup_angular_velocity("head", "world", return_timestamps=True)
    np.testing.assert_array_equal(da["time"].values, ts)
    assert da.indexes["time"].name == "time"
