"""The teaching aids without a browser: check_answer, FrameSliders, show_file."""

from __future__ import annotations

import numpy as np
import pytest
import traitlets

import rbm_nb as rbm
from rbm_nb.widgets import FrameSliders, check_answer
from rbm_nb.widgets.teaching import quaternion_from_ypr_degrees, show_file


def test_check_answer_says_right_wrong_or_waiting(capsys):
    assert check_answer(None, 1, why="w") is None
    assert "No prediction yet" in capsys.readouterr().out
    assert check_answer((1, 0, 0), np.array([1.0, 0, 0]), why="because") is True
    assert capsys.readouterr().out == "Right. because\n"
    assert check_answer(3, 4, why="because") is False
    out = capsys.readouterr().out
    assert (
        out.startswith("Not quite: you said 3, the answer is 4.") and "because" in out
    )
    assert check_answer('"Y"', "y", why="w") is False  # quotes are part of the string
    assert check_answer("Y ", "y", why="w") is True
    assert check_answer((1, 2), (1, 2, 3), why="w") is False
    with pytest.raises(ValueError, match="why"):
        check_answer(1, 1, why="")


def test_ypr_is_z_then_y_then_x():
    q = quaternion_from_ypr_degrees(10, 20, 30)
    angles = rbm.conversions.euler_from_quaternion(q[None], "zyx")[0]
    assert np.degrees(angles) == pytest.approx([10, 20, 30])


@pytest.fixture
def world():
    rbm.clear_registry()
    rbm.register_frame("world")
    yield
    rbm.clear_registry()


def test_sliders_register_the_frame_and_report(world):
    sliders = FrameSliders(
        "observer",
        "world",
        translation=(5, 0, 0),
        angles=(90, 0, 0),
        report=lambda: rbm.transform_points((2, 0, 0), outof="world", into="observer"),
        point=(2, 0, 0),
    )
    assert "3." in sliders.panel.report
    sliders.set(yaw=180)
    t, r = rbm.lookup_transform(outof="observer", into="world")
    assert t == pytest.approx([5, 0, 0])
    assert rbm.rotate_vectors(r, (1.0, 0, 0)) == pytest.approx([-1, 0, 0], abs=1e-12)
    # what the browser sends is a change of `values`: it re-registers too
    sliders.panel.values = {**sliders.panel.values, "x": 2.0}
    assert rbm.transform_points(
        (2, 0, 0), outof="world", into="observer"
    ) == pytest.approx([0, 0, 0], abs=1e-12)
    assert sliders.panel.point == [2.0, 0.0, 0.0]


def test_the_triad_keeps_its_scene_path(world):
    scene = rbm.scene.Scene("world")
    sliders = FrameSliders("f", "world", scene=scene)
    path = sliders.panel.node
    assert path.endswith("/pose")
    sliders.set(pitch=45)
    assert sliders.panel.node == path and list(scene.handles) == ["sliders_f"]
    scene.close()


def test_sliders_refuse_bad_input(world):
    with pytest.raises(ValueError, match="parent 'nowhere'"):
        FrameSliders("f", "nowhere")
    with pytest.raises(ValueError, match="translation must be three finite"):
        FrameSliders("f", "world", translation=(0, np.nan, 0))
    with pytest.raises(ValueError, match="sliders must be among"):
        FrameSliders("f", "world", sliders=("yaw", "spin"))
    sliders = FrameSliders("f", "world")
    with pytest.raises(ValueError, match="unknown sliders"):
        sliders.set(spin=3)
    with pytest.raises(traitlets.TraitError, match="must be a number"):
        sliders.panel.values = {**sliders.panel.values, "yaw": "ninety"}
    with pytest.raises(traitlets.TraitError, match="keys"):
        sliders.panel.values = {"yaw": 1.0}


def test_show_file_embeds_the_page(tmp_path):
    page = tmp_path / "scene.html"
    page.write_text('<p class="x">a & b</p>', encoding="utf-8")
    html = show_file(page, height=300).data
    assert 'srcdoc="&lt;p class=&quot;x&quot;&gt;a &amp; b&lt;/p&gt;"' in html
    assert "height: 300px" in html
    with pytest.raises(ValueError, match="existing .html file"):
        show_file(tmp_path / "missing.html")
    with pytest.raises(ValueError, match="height"):
        show_file(page, height=10)
