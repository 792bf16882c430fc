"""The shared time readout: Python (_timebase.py) and browser (timeline.js) agree."""

from __future__ import annotations

import json
import shutil
import subprocess

import numpy as np
import pytest
from conftest import REPO

from rbm_nb.widgets._timebase import TimeBase, format_time

JS = REPO / "js" / "src" / "timeline.js"
T0 = int(np.datetime64("2020-02-02T00:27:14.123456789", "ns").astype(np.int64))

CASES = [
    (0.0, None),
    (-0.0, None),
    (12.3456, None),
    (0.0625, None),  # an exact binary tie: both round half away from zero
    (-0.0625, None),
    (-1.5, None),
    (329.9995, None),
    (1e-4, T0),
    (0.0, T0),
    (12.3456, T0),
    (0.8765, T0),
    (-3.25, T0),
    (86399.9996, T0),  # rolls over to the next day
    (float("nan"), T0),
    (None, None),
]


def test_examples():
    assert format_time(12.3456) == "12.346 s"
    assert format_time(0.0625) == "0.063 s"
    assert format_time(-0.0) == "0.000 s"
    assert format_time(1.0, T0) == "1.000 s \u00b7 2020-02-02 00:27:15.123"
    assert format_time(None) == "\u2014"


def test_python_and_javascript_print_the_same():
    node = shutil.which("node")
    if node is None:
        pytest.skip("node is not installed (needed for the JS bundle anyway)")
    script = (
        f"import {{ formatTime }} from {json.dumps(JS.as_uri())};\n"
        f"const cases = {json.dumps([[t if t is None or t == t else 'nan', t0] for t, t0 in CASES])};\n"
        "console.log(JSON.stringify(cases.map(([t, t0]) =>"
        " formatTime(t === 'nan' ? NaN : t, t0))));\n"
    )
    out = subprocess.run(
        [node, "--input-type=module", "-e", script],
        capture_output=True,
        text=True,
        check=True,
        timeout=60,
    )
    js = json.loads(out.stdout)
    py = [format_time(t, t0) for t, t0 in CASES]
    assert js == py


def test_time_base_of_datetime_and_float_timestamps():
    stamps = np.datetime64(T0, "ns") + np.arange(3).astype("timedelta64[ms]")
    base = TimeBase.of(stamps)
    assert base == TimeBase(t0_ns=T0) and base.absolute
    np.testing.assert_array_equal(base.seconds(stamps), [0.0, 1e-3, 2e-3])
    assert format_time(1.0, base.t0_ns).endswith("00:27:15.123")
    floats = TimeBase.of(np.array([5.0, 6.0]))
    assert floats == TimeBase(t0_s=5.0) and not floats.absolute
    np.testing.assert_array_equal(floats.seconds([5.0, 7.5]), [0.0, 2.5])
    with pytest.raises(
        ValueError, match="cannot match datetime64 timestamps with numeric"
    ):
        base.seconds(np.array([1.0]))
    with pytest.raises(
        ValueError, match="cannot match datetime64 timestamps with numeric"
    ):
        floats.seconds(stamps)
    with pytest.raises(ValueError, match="timestamps must not be empty"):
        TimeBase.of(np.array([]))


def test_player_readout_is_the_shared_one():
    from rbm_nb.widgets import Player

    stamps = np.datetime64(T0, "ns") + (np.arange(100) * 10).astype("timedelta64[ms]")
    player = Player(stamps)
    for t in (0.0, 0.0625, 0.3333, 0.99):
        player.time = t
        assert player.readout() == format_time(t, T0)
    player.close()
    floats = Player(np.arange(5.0, 10.0, 0.5))
    floats.time = 1.25
    assert floats.readout() == "1.250 s"
    floats.close()
