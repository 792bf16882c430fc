"""The demo command, the explorer it opens, and the README's quick start."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import numpy as np
import pytest
from browser_support import JupyterLab, changed_pixels, png_pixels, save
from conftest import REPO

import rbm_nb as rbm
from rbm_nb.app import explorer

RBM_NB = Path(sys.executable).with_name("rbm-nb")
EXPLORER = REPO / "notebooks" / "06_head_eye_explorer.ipynb"


def _quick_start() -> str:
    text = (REPO / "README.md").read_text()
    match = re.search(r"## Quick start.*?```python\n(.+?)```", text, re.S)
    assert match, "README.md has no ```python block under '## Quick start'"
    return match.group(1)


def test_readme_quick_start_runs_as_written(tmp_path):
    result = subprocess.run(
        [sys.executable, "-c", _quick_start()],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
        env={**os.environ, "MPLBACKEND": "Agg"},
    )
    assert result.returncode == 0, result.stderr[-3000:]
    assert "world" in result.stdout


def test_demo_text_prints_a_lookup_on_a_moving_tree():
    result = subprocess.run(
        [str(RBM_NB), "demo", "--text"], capture_output=True, text=True, timeout=600
    )
    assert result.returncode == 0, result.stderr
    assert "└── body" in result.stdout
    # the camera, 10 cm above the body, ends at x = 5 m after the body's 90 deg turn
    assert "5.00   [5.  0.  0.1]" in result.stdout


def test_demo_without_notebooks_says_what_to_do(tmp_path):
    result = subprocess.run(
        [str(RBM_NB), "demo", "--no-browser", "--notebook-dir", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode != 0
    assert "06_head_eye_explorer.ipynb not found" in result.stderr


@pytest.mark.slow
def test_demo_serves_jupyterlab_on_the_explorer(tmp_path):
    env = {**os.environ, "JUPYTER_RUNTIME_DIR": str(tmp_path / "runtime")}
    process = subprocess.Popen(
        [str(RBM_NB), "demo", "--no-browser", "--port", "0"],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env=env,
        start_new_session=True,
    )
    try:
        line = ""
        deadline = time.monotonic() + 60
        while "http://" not in line and time.monotonic() < deadline:
            line = process.stdout.readline()
        url = re.search(r"http://\S+", line).group(0)
        assert "/lab/tree/06_head_eye_explorer.ipynb?token=" in url
        base, token = url.split("/lab/")[0], url.split("token=")[1]
        contents = f"{base}/api/contents/06_head_eye_explorer.ipynb?content=0"
        request = urllib.request.Request(
            contents, headers={"Authorization": f"token {token}"}
        )
        deadline = time.monotonic() + 120
        while True:
            try:
                with urllib.request.urlopen(request, timeout=5) as response:
                    assert response.status == 200
                    break
            except OSError:
                if time.monotonic() > deadline or process.poll() is not None:
                    raise
                time.sleep(0.5)
    finally:
        os.killpg(process.pid, signal.SIGTERM)
        process.wait(timeout=30)


def test_port_zero_is_not_requested_literally():
    from rbm_nb.app.cli import _free_port

    assert _free_port(0) > 0


def test_gaze_angles_of_known_eye_orientations():
    import xarray as xr

    # 10 deg to the right: about the camera's y axis (down); 10 deg up: about x
    right = rbm.from_euler_angles(pitch=np.radians(10.0))
    up = rbm.from_euler_angles(roll=np.radians(10.0))
    eye = xr.Dataset(
        {"orientation": (("time", "quaternion_axis"), np.stack([right, up]))},
        coords={"time": [0.0, 1.0], "quaternion_axis": list("wxyz")},
    )
    angles = explorer.gaze_angles(eye)
    np.testing.assert_allclose(angles.values, [[10.0, 0.0], [0.0, 10.0]], atol=1e-9)


def test_html_export_leaves_the_registry_as_it_was(tmp_path):
    rbm.register_frame("mine")
    out = explorer.write_explorer_html(
        tmp_path / "explorer.html", source="synthetic", max_frames=200, progress=False
    )
    assert list(rbm.registry) == ["mine"]
    assert out.stat().st_size > 100_000
    assert oct(out.stat().st_mode & 0o777) == oct(0o666 & ~_umask())


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@pytest.mark.slow
@pytest.mark.browser
def test_demo_html_export_plays_offline_in_chromium(page, tmp_path):
    out = tmp_path / "out.html"
    result = subprocess.run(
        [str(RBM_NB), "demo", "--html", str(out), "--source", "synthetic"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert result.returncode == 0, result.stderr[-3000:]
    assert "wrote" in result.stdout and out.is_file()
    assert "rbm-nb demo --html" in result.stderr  # the progress bar
    assert out.stat().st_size <= 5 * 1024 * 1024  # issue 10: <= 5 MB for 5.5 minutes
    requests = []
    page.on("request", lambda r: requests.append(r.url))
    page.goto(out.as_uri())
    page.wait_for_function("window.rbmExport && window.rbmExport.ready", timeout=60000)
    slider = page.locator(".rbm-slider")

    def scrub(t):
        slider.evaluate(
            "(s, t) => { s.value = String(t); s.dispatchEvent(new Event('input')); }", t
        )
        page.wait_for_timeout(500)

    scrub(20)
    canvas = page.locator(".rbm-scene canvas")
    first = png_pixels(canvas.screenshot())
    scrub(200)
    shot = canvas.screenshot()
    save("demo_export.png", shot)
    save("demo_export_page.png", page.screenshot(full_page=True))
    later = png_pixels(shot)
    assert (first.std(axis=(0, 1)) > 5).any()  # something is drawn
    assert changed_pixels(first, later) > 100  # and it moved
    assert page.inner_text(".rbm-readout").startswith("200.000 s")
    assert [
        u for u in requests if not u.startswith(("file://", "blob:", "data:"))
    ] == []
    assert page.errors == []


@pytest.mark.slow
@pytest.mark.browser
@pytest.mark.timeout(300)  # JupyterLab + the explorer in chromium (about 45 s here)
def test_explorer_in_jupyterlab(browser, tmp_path, monkeypatch):
    """Run notebook 06 in JupyterLab: the tree, the player, the 3D view and the plot."""
    from playwright.sync_api import TimeoutError as PlaywrightTimeout

    shared = REPO.parent / "shared" / "data" / "rbm-data"
    if shared.is_dir():
        monkeypatch.setenv("RBM_NB_DATA_DIR", str(shared))
    lab = JupyterLab(tmp_path, [EXPLORER], proxy=False)
    context = browser.new_context(viewport={"width": 1400, "height": 1800})
    page = context.new_page()
    try:
        page.goto(lab.url(f"lab/tree/{EXPLORER.name}"), timeout=120000)
        page.wait_for_selector(".jp-Notebook .jp-Cell", timeout=120000)
        try:  # JupyterLab may ask which kernel to start
            page.locator(".jp-Dialog").get_by_role(
                "button", name="Select", exact=True
            ).click(timeout=20000)
        except PlaywrightTimeout:
            pass
        page.wait_for_selector(
            ".jp-Notebook-ExecutionIndicator[data-status='idle']", timeout=120000
        )
        page.get_by_role("menuitem", name="Run", exact=True).click()
        page.get_by_text("Run All Cells", exact=True).click()
        page.locator(
            ".jp-OutputArea-output", has_text="head_eye_explorer.html"
        ).wait_for(timeout=300000)
        page.wait_for_function(
            """() => { const el = document.querySelector('.rbm-scene');
                       return el && el.rbmView && el.rbmView.store.tracks.size >= 3; }""",
            timeout=120000,
        )
        canvas = page.locator(".rbm-scene canvas")
        page.wait_for_timeout(1500)
        before = png_pixels(canvas.screenshot())
        readout = page.locator(".rbm-readout")
        start = readout.inner_text()
        page.locator(".rbm-play").click()
        page.wait_for_timeout(2500)
        page.locator(".rbm-play").click()
        assert readout.inner_text() != start
        page.wait_for_timeout(500)
        after = png_pixels(canvas.screenshot())
        assert changed_pixels(before, after) > 50  # the head moved in the view
        dashboard = page.locator(".jp-OutputArea-output").filter(
            has=page.locator(".rbm-scene")
        )
        save("head_eye_explorer.png", dashboard.first.screenshot())
        save("head_eye_explorer_page.png", page.screenshot(full_page=True))
    except Exception:
        save("head_eye_explorer_failure.png", page.screenshot(full_page=True))
        print(lab.log_text())
        raise
    finally:
        context.close()
        lab.stop()
