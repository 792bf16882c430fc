"""An HTML export of a long scene stays small, and says what it shows.

A scene alone (no plots) with a frame, its path and a moving point, 10 min
and 3 h at 200 Hz: the page is under 5 MB at both lengths, hardly larger at
3 h, and names the rate of its poses and the points of its path.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

import rbm_nb as rbm
from rbm_nb.scene import Scene

RATE = 200.0
LIMIT = 5_000_000


def export(tmp_path, minutes: float) -> tuple[int, str]:
    rbm.clear_registry()
    rbm.register_frame("world")
    n = int(minutes * 60 * RATE)
    ts = np.arange(n) / RATE
    xyz = np.c_[np.cos(ts / 60) * 10, np.sin(ts / 45) * 10, 0.2 * np.sin(ts)]
    for start in range(60_000, n, 120_000):  # 10 s lost every 10 min
        xyz[start : start + 2000] = np.nan
    angle = ts / 10
    quat = np.c_[np.cos(angle / 2), np.zeros(n), np.zeros(n), np.sin(angle / 2)]
    rbm.register_frame(
        "body", parent="world", timestamps=ts, translation=xyz, rotation=quat
    )
    scene = Scene("world")
    scene.add_frame("body")
    scene.add_path("body", max_points=2000)
    scene.add_points(np.nan_to_num(xyz) + 1.0, timestamps=ts, size=0.1)
    path = scene.to_html(tmp_path / f"walk_{minutes}.html")
    scene.close()
    text = path.read_text()
    [note] = re.findall(r'<p class="rbm-export-note">(.*?)</p>', text)
    return path.stat().st_size, note


@pytest.mark.slow
def test_a_page_of_hours_is_as_small_as_one_of_minutes(tmp_path):
    short, short_note = export(tmp_path, 10)
    long, long_note = export(tmp_path, 180)
    assert long <= LIMIT
    assert long < 1.3 * short
    # 20000 poses per object: every 0.54 s over 3 h, recorded at 200 Hz
    assert "poses at 1.85 Hz over 3 h (recorded at up to 200 Hz" in long_note
    assert "poses at 33.3 Hz over 10 min" in short_note
    drawn = int(
        re.search(r"path body: ([\d,]+) of", long_note).group(1).replace(",", "")
    )
    assert drawn <= 2000 and "of 2,160,000 samples drawn, within" in long_note


def test_a_short_page_says_it_has_every_sample(tmp_path):
    size, note = export(tmp_path, 1)
    assert note.startswith("poses: every sample over 60 s")
    assert size < LIMIT
