"""The explorer as a standalone Voilà app, on the real recording, in chromium.

Voilà serves the app notebook (``rbm_nb.app``) on 127.0.0.1 with a random
token; the page must show the frame tree, the time-series plot and the 3D
view, with every request going to Voilà's own port (but the Font Awesome
CSS that Voilà's template links from a CDN, blocked here). Screenshots go to
test-artifacts/.
"""

from __future__ import annotations

import json
import os
import re
import secrets
import signal
import socket
import subprocess
import time
import urllib.error
import urllib.request
from pathlib import Path

import pytest

from rbm_nb.app import server as app

pytestmark = [pytest.mark.browser, pytest.mark.slow]

from browser_support import free_port, png_pixels, save  # noqa: E402
from conftest import REPO  # noqa: E402


def test_app_notebook_in_the_repo_is_the_generated_one():
    on_disk = json.loads((REPO / "apps" / app.APP_NOTEBOOK).read_text(encoding="utf-8"))
    assert on_disk == app.app_notebook()


def test_voila_command_listens_on_loopback_with_a_token(tmp_path):
    command = app.voila_command(tmp_path / "x.ipynb", port=1234)
    assert "--Voila.ip=127.0.0.1" in command and "--Voila.auto_token=True" in command
    assert app.voila_environment("abc", {})["JUPYTER_TOKEN"] == "abc"
    with pytest.raises(ValueError, match="token"):
        app.voila_environment("")
    with pytest.raises(ValueError, match="source must be one of"):
        app.app_notebook("nope")


class Voila:
    """Voilà on loopback in a temporary home, and its cleanup."""

    def __init__(self, tmp: Path, data_dir: Path):
        self.port = free_port()
        self.token = secrets.token_hex(16)
        notebook = app.write_app_notebook(tmp)
        env = dict(os.environ)
        for var, sub in (
            ("JUPYTER_CONFIG_DIR", "config"),
            ("JUPYTER_RUNTIME_DIR", "runtime"),
            ("JUPYTER_DATA_DIR", "data"),
            ("IPYTHONDIR", "ipython"),
            ("MPLCONFIGDIR", "mpl"),
        ):
            (tmp / sub).mkdir()
            env[var] = str(tmp / sub)
        env["JUPYTER_PLATFORM_DIRS"] = "1"
        env["RBM_NB_DATA_DIR"] = str(data_dir)
        self.log_path = tmp / "voila.log"
        self.log = open(self.log_path, "wb")
        self.process = subprocess.Popen(
            app.voila_command(notebook, port=self.port),
            cwd=tmp,
            env=app.voila_environment(self.token, env),
            stdout=self.log,
            stderr=subprocess.STDOUT,
            start_new_session=True,  # its own process group, stopped as a whole
        )
        deadline = time.monotonic() + 120
        while True:
            if self.process.poll() is not None:
                raise RuntimeError(f"Voila exited early:\n{self.log_text()}")
            try:
                with socket.create_connection(("127.0.0.1", self.port), timeout=1):
                    break
            except OSError:
                if time.monotonic() > deadline:
                    raise RuntimeError(
                        f"Voila did not start:\n{self.log_text()}"
                    ) from None
                time.sleep(0.5)

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.port}/?token={self.token}"

    def log_text(self) -> str:
        self.log.flush()
        return self.log_path.read_text(errors="replace")[-4000:]

    def stop(self) -> None:
        if self.process.poll() is None:
            os.killpg(self.process.pid, signal.SIGTERM)
            try:
                self.process.wait(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(self.process.pid, signal.SIGKILL)
                self.process.wait(timeout=10)
        self.log.close()


@pytest.fixture(scope="module")
def voila(tmp_path_factory, shared_data):
    server = Voila(tmp_path_factory.mktemp("voila"), shared_data / "rbm-data")
    try:
        yield server
    finally:
        server.stop()
        assert server.process.poll() is not None


def test_the_app_needs_its_token(voila):
    class NoRedirect(urllib.request.HTTPRedirectHandler):
        def redirect_request(self, *args, **kwargs):
            return None

    opener = urllib.request.build_opener(NoRedirect)
    for url in (
        f"http://127.0.0.1:{voila.port}/",
        f"http://127.0.0.1:{voila.port}/?token=wrong",
    ):
        with pytest.raises(urllib.error.HTTPError) as err:
            opener.open(url, timeout=60)
        # sent to the login page instead of running the notebook
        assert err.value.code in (302, 401, 403)
        if err.value.code == 302:
            assert "/login" in err.value.headers["Location"]


def test_the_app_renders_tree_plot_and_3d_view(browser, voila):
    context = browser.new_context(viewport={"width": 1280, "height": 1300})
    page = context.new_page()
    errors, elsewhere = [], []
    page.on("pageerror", lambda err: errors.append(str(err)))

    def only_voila(route):
        if (
            f"127.0.0.1:{voila.port}" in route.request.url
            or route.request.url.startswith(("data:", "blob:"))
        ):
            route.continue_()
        else:
            elsewhere.append(route.request.url)
            route.abort()

    page.route("**/*", only_voila)
    try:
        page.goto(voila.url, timeout=180000)
        page.locator(".rbm-frame-node", has_text="head").first.wait_for(timeout=240000)
        page.wait_for_function(
            "document.querySelector('.rbm-ts') && document.querySelector('.rbm-ts').rbmCharts"
            " && document.querySelector('.rbm-ts').rbmCharts.length === 3",
            timeout=120000,
        )
        canvas = page.locator(".rbm-scene canvas").first
        canvas.wait_for(timeout=120000)
        page.wait_for_timeout(2000)
        # the app is the dashboard alone: no code cell shows
        assert page.locator("text=explorer_dashboard").count() == 0
        nodes = page.locator(".rbm-frame-node").all_inner_texts()
        assert {"world", "t265/tracker", "head", "pupil/left_eye"} <= set(nodes)
        legends = page.locator(".rbm-ts .u-legend").all_inner_texts()
        assert any("left eye" in text for text in legends)
        assert any("head yaw rate" in text for text in legends)
        # the 3D view draws something: not one flat colour
        pixels = png_pixels(canvas.screenshot())
        assert pixels.reshape(-1, 3).std(axis=0).max() > 10
        # a click on a frame in the tree shows its details with the shared readout
        page.locator(".rbm-frame-node", has_text="head").first.click()
        details = page.locator(".rbm-frame-details")
        details.locator("text=yaw").first.wait_for(timeout=30000)
        assert (
            "yaw 90.00\u00b0, pitch 90.00\u00b0, roll 0.00\u00b0"
            in details.inner_text()
        )
        assert "quaternion (w, x, y, z) = (0.5, -0.5, 0.5, 0.5)" in details.inner_text()
        page.locator(".rbm-frame-node", has_text="head").first.click()  # unselect
        page.locator(".rbm-frame-node", has_text="t265/tracker").first.click()
        details.locator("text=t265/tracker \u2014 moving").wait_for(timeout=30000)
        # the sample's time as everywhere: seconds from the start · absolute date
        # (the explorer opens at the first instant with head and both eyes)
        assert re.search(
            r"\(at 0\.0\d\d s \u00b7 2020-02-02 00:27:14\.3\d\d\)", details.inner_text()
        ), details.inner_text()
        # the Player's clock runs in the page: play moves the plot's cursor
        page.click(".rbm-play")
        page.wait_for_function(
            "parseFloat(document.querySelector('.rbm-ts-time').textContent.slice(4)) > 1.0",
            timeout=30000,
        )
        page.click(".rbm-play")
        save("voila_app.png", page.screenshot(full_page=True))
        assert not errors, errors
        # Voila's lab template links Font Awesome's CSS from a CDN (its own
        # bundle has the icon font too, so the icons show with it blocked):
        # nothing else may leave Voila's port
        cdn = "https://cdn.jsdelivr.net/npm/@fortawesome/fontawesome-free@"
        assert [url for url in elsewhere if not url.startswith(cdn)] == []
    except Exception:
        save("voila_failure.png", page.screenshot(full_page=True))
        print(voila.log_text())
        raise
    finally:
        context.close()
