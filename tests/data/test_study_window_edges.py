"""Study windows take their edges from the core's time rule (no drift, no epoch floats)."""

from __future__ import annotations

import numpy as np

from rbm_nb.study._windows import split

T0 = np.datetime64("2020-02-02T00:27:14.123456789", "ns")


def test_edges_of_a_third_of_a_second_do_not_drift():
    # 1/3 s is no whole number of ns: adding k rounded steps drifted by k/3 ns
    # (1 µs after 3000 windows); edges are k/3 s from the start, to the ns
    stop = T0 + np.timedelta64(1000, "s")
    windows = split(T0, stop, 1 / 3, 0.0)
    assert len(windows) == 3000
    assert windows[-1].start == T0 + np.timedelta64(999_666_666_667, "ns")
    assert windows[2999 - 1].stop == windows[-1].start
    assert windows[-1].stop == stop
    for k in (0, 1, 1500, 2999):
        expected = T0 + np.timedelta64(round(k * 1e9 / 3), "ns")
        assert windows[k].start == expected


def test_float_windows_and_margins_are_unchanged():
    windows = split(0.0, 1.05, 0.5, 0.1)
    assert [(w.start, w.stop) for w in windows] == [(0.0, 0.5), (0.5, 1.0), (1.0, 1.05)]
    assert [w.last for w in windows] == [False, False, True]
    assert windows[0].read_start == -0.1 and windows[-1].read_stop == 1.05 + 0.1
