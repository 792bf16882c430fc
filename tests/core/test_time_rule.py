"""rbm_nb._engine.time as the notebook layer uses it: one ordering rule with a
``repeats`` switch, second 0 (TimeBase) counted from exact keys, one search."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rbm_nb._engine.time import (
    TIE,
    TimeBase,
    as_track,
    epoch_seconds,
    from_epoch_seconds,
    latest_index,
)

T0 = np.datetime64("2020-02-02T00:27:14.300365210", "ns")
NS = T0 + np.array([0, 1, 2, 3_000_000_000]).astype("timedelta64[ns]")


def test_one_rule_two_strictnesses():
    repeated = NS[[0, 1, 1, 2]]
    with pytest.raises(
        ValueError, match=r"strictly increasing: ts\[2\] = .* is a duplicate"
    ):
        as_track(repeated, "ts")
    assert len(as_track(repeated, "ts", repeats=True)) == 4
    with pytest.raises(
        ValueError,
        match=r"ts must be sorted \(repeats allowed\): ts\[2\] = .* is earlier",
    ):
        as_track(NS[[0, 2, 1]], "ts", repeats=True)
    with pytest.raises(ValueError, match=r"ts\[1\] is NaT"):
        as_track(np.array([T0, np.datetime64("NaT")]), "ts", repeats=True)


def test_time_base_counts_from_exact_keys():
    base = TimeBase.of(NS)
    assert base == TimeBase(t0_ns=int(NS[0].astype(np.int64)))
    np.testing.assert_array_equal(base.seconds(NS), [0.0, 1e-9, 2e-9, 3.0])
    assert base.at(NS[2]) == 2e-9
    assert base.at(pd.Timestamp(NS[1])) == 1e-9
    assert base.value(2e-9) == NS[2] and base.value(3.0) == NS[3]
    assert base.key(1e-9) == int(NS[1].astype(np.int64))
    later = TimeBase.of(NS[1:])
    assert later.shift_to(base) == 1e-9 and base.shift_to(later) == -1e-9
    # the epoch floats cannot tell the first three apart; the base can
    assert len(set(NS.astype(np.int64) / 1e9)) == 2


def test_kinds_do_not_meet():
    base = TimeBase.of(NS)
    with pytest.raises(
        ValueError, match="cannot match datetime64 timestamps with numeric"
    ):
        base.seconds(np.array([1.0, 2.0]), "x")
    with pytest.raises(
        ValueError, match="cannot match numeric timestamps with timedelta64"
    ):
        TimeBase.of(np.array([1.0])).at(np.timedelta64(1, "s"))
    elapsed = TimeBase.of(NS - NS[0])
    assert elapsed.kind == "timedelta64" and not elapsed.absolute


def test_latest_index_is_one_search():
    track = as_track(NS)
    base = TimeBase.of(track)
    assert [latest_index(track, base, t) for t in (0.0, 1e-9, 2.4e-9, 3.0)] == [
        0,
        1,
        2,
        3,
    ]
    assert latest_index(track, base, -1e-9) == -1
    floats = as_track(np.arange(5) * 0.1)
    fb = TimeBase.of(floats)
    assert latest_index(floats, fb, 0.1 * 3) == 3  # 0.30000000000000004
    assert latest_index(floats, fb, 0.3 - TIE / 2) == 3


def test_epoch_seconds_only_where_asked():
    assert epoch_seconds(NS[3]) == int(NS[3].astype(np.int64)) / 1e9
    assert epoch_seconds(5.0, "datetime64") == 5.0
    with pytest.raises(ValueError, match="cannot match"):
        epoch_seconds(NS[0], "numeric")
    back = from_epoch_seconds(epoch_seconds(NS[[0, 3]]), "datetime64")
    assert back.dtype == np.dtype("datetime64[ns]")
    assert abs(int((back[1] - NS[3]).astype(np.int64))) < 300  # ~0.25 us coarse
