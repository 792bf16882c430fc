"""What a Player keeps of a long time axis (issue 35): its keys, no float copies.

It used to keep three per-sample arrays: a copy of the timestamps, their float
seconds and those seconds again from the first sample. Now the seconds are
counted from the keys when asked (``playback.SampleTimes``), answering
exactly as the arrays did.
"""

from __future__ import annotations

import numpy as np
import pytest
from memory_support import kept_by

from rbm_nb.widgets import Player
from rbm_nb.widgets.playback import TOLERANCE, SampleTimes

N = 400_000
T0 = np.datetime64("2020-02-02T00:27:14.300365210", "ns")


def _stamps(frozen: bool) -> np.ndarray:
    stamps = T0 + np.arange(N) * np.timedelta64(2_941_176, "ns")
    stamps.setflags(write=not frozen)
    return stamps


def _kept(make):
    # the first Player loads its bundle and widget machinery: not the data's
    Player(_stamps(frozen=False)[:10]).close()
    return kept_by(make)


def test_a_player_over_frozen_stamps_keeps_no_per_sample_array():
    stamps = _stamps(frozen=True)
    player, kept = _kept(lambda: Player(stamps))
    assert np.shares_memory(player.timestamps, stamps)
    assert kept < 0.1 * stamps.nbytes, (kept, stamps.nbytes)
    player.close()


def test_a_player_over_writeable_stamps_keeps_one_copy():
    stamps = _stamps(frozen=False)
    player, kept = _kept(lambda: Player(stamps))
    assert not np.shares_memory(player.timestamps, stamps)
    assert kept < 1.1 * stamps.nbytes, (kept, stamps.nbytes)
    stamps[:] = stamps[0]  # the caller's array changes; the player does not
    assert player.timestamps[-1] > player.timestamps[0]
    player.close()


def _old_index(relative: np.ndarray, t: float) -> int:
    """What the Player answered from its float seconds array."""
    i = int(np.searchsorted(relative, t + TOLERANCE, side="right")) - 1
    return min(max(i, 0), relative.size - 1)


@pytest.mark.parametrize("kind", ["ns", "seconds"])
def test_sample_times_answer_as_the_float_seconds_array_did(kind):
    rng = np.random.default_rng(35)
    steps = rng.choice([0, 1, 2, 999, 2_941_176, 10**9], size=5000)
    ns = T0.astype(np.int64) + np.cumsum(steps)  # repeats and 1 ns apart
    key = ns if kind == "ns" else ns / 1e9
    scale = 1e9 if kind == "ns" else 1.0
    relative = (key - key[0]) / scale
    samples = SampleTimes(key, scale)
    assert [samples.at(i) for i in range(key.size)] == relative.tolist()
    np.testing.assert_array_equal(samples.array(), relative)
    near = relative[rng.integers(0, key.size, 2000)]
    queries = np.r_[
        near,
        np.nextafter(near, np.inf),
        np.nextafter(near, -np.inf),
        near - TOLERANCE,
        rng.uniform(-5, relative[-1] + 5, 2000),
        [-1e300, 1e300, -np.inf, np.inf, np.nan],
    ]
    player_like = [
        min(max(samples.last_at_or_before(t + TOLERANCE), 0), key.size - 1)
        for t in queries
    ]
    assert player_like == [_old_index(relative, t) for t in queries]


def test_player_seconds_and_steps_unchanged():
    stamps = _stamps(frozen=True)[:1000]
    player = Player(stamps)
    relative = (stamps.astype(np.int64) - stamps[0].astype(np.int64)) / 1e9
    np.testing.assert_array_equal(player.seconds, player.timebase.origin + relative)
    assert player.playback.duration == relative[-1]
    player.seek(500)
    assert player.time == relative[500] and player.index == 500
    player.step_forward()
    assert player.index == 501
    player.close()
