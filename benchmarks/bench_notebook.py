"""The head/eye explorer in JupyterLab, measured in headless chromium.

Prints:

* first frame: seconds from running the dashboard cell to the 3D view drawn
  with the scene's content (tracks received, a frame rendered);
* frames per second during playback, counted in the page with
  requestAnimationFrame, with the kernel idle and while a cell sleeps;
* bytes the page received over the kernel's websocket to show the dashboard,
  and per second while playing;
* the size of the explorer's HTML export;
* kernel CPU while the browser plays (the clock runs in the browser).

The Jupyter server runs without jupyter-server-proxy; the real recording is
used when ``../shared/data/rbm-data`` exists (else the synthetic one).

Run: ``.venv/bin/python benchmarks/bench_notebook.py``
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests"))

from browser_support import (  # noqa: E402
    CHROMIUM,
    CHROMIUM_ARGS,
    MEASURE_JS,
    JupyterLab,
    block_other_ports,
)

SHARED = (
    Path(os.environ.get("RBM_NB_SHARED", REPO.parent / "shared")) / "data" / "rbm-data"
)

CELLS = [
    """import ipywidgets as widgets
import rbm_nb as rbm
from rbm_nb import explorer
head, left_eye, right_eye, note = explorer.load_head_eye()
print("data:", note)
rbm.clear_registry()
explorer.register_head_eye_frames(head, left_eye, right_eye)
series = explorer.explorer_series(head, left_eye, right_eye)""",
    """scene = explorer.explorer_scene()
player = scene.player()
plot = explorer.explorer_plot(series, player)
widgets.VBox([scene.widget, player] + ([plot] if plot is not None else []))""",
    """import time
time.sleep(6)""",
]

SCENE_READY = """() => { const el = document.querySelector('.rbm-scene');
  return el && el.rbmView && el.rbmView.store.tracks.size >= 3 && el.rbmView.frames > 0; }"""


def run_cell(page, index: int) -> None:
    """Run code cell ``index`` (shift+enter), again while the UI is not ready for it."""
    from playwright.sync_api import TimeoutError as PlaywrightTimeout

    cell = page.locator(".jp-Notebook .jp-CodeCell").nth(index)
    for _ in range(10):
        cell.locator(".jp-InputArea-editor").click()
        page.keyboard.press("Shift+Enter")
        try:
            page.wait_for_function(
                """(i) => /\\[(\\*|\\d+)\\]/.test(document.querySelectorAll(
                    '.jp-Notebook .jp-CodeCell')[i].querySelector('.jp-InputPrompt').innerText)""",
                arg=index,
                timeout=5000,
            )
            return
        except PlaywrightTimeout:
            continue
    raise RuntimeError(f"cell {index} did not start running")


def wait_done(page, index: int, timeout: float = 600000) -> None:
    page.wait_for_function(
        """(i) => /\\[\\d+\\]/.test(document.querySelectorAll('.jp-Notebook .jp-CodeCell')[i]
                  .querySelector('.jp-InputPrompt').innerText)""",
        arg=index,
        timeout=timeout,
    )


def main() -> None:
    import nbformat
    import psutil
    from playwright.sync_api import sync_playwright

    if SHARED.is_dir():
        os.environ["RBM_NB_DATA_DIR"] = str(SHARED)
    os.environ["PYTHONPATH"] = str(REPO)  # the kernel imports this checkout
    tmp = Path(tempfile.mkdtemp(prefix="bench_notebook_"))
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(c) for c in CELLS]
    nb.metadata["kernelspec"] = {
        "name": "python3",
        "display_name": "Python 3",
        "language": "python",
    }
    path = tmp / "bench.ipynb"
    nbformat.write(nb, path)
    (tmp / "home").mkdir()
    server = JupyterLab(tmp / "home", [path], proxy=False)
    rows = []
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            context = browser.new_context(viewport={"width": 1300, "height": 1400})
            block_other_ports(context, server.port)
            page = context.new_page()
            received = [0]

            def on_socket(ws):
                def count(payload):
                    received[0] += len(payload) if payload is not None else 0

                ws.on("framereceived", count)

            page.on("websocket", on_socket)
            page.goto(server.notebook_url(path.name), timeout=120000)
            page.wait_for_selector(".jp-Notebook .jp-CodeCell", timeout=120000)
            page.wait_for_selector(
                ".jp-Notebook-ExecutionIndicator[data-status='idle']", timeout=120000
            )
            run_cell(page, 0)
            wait_done(page, 0)
            [kernel] = [
                c
                for c in psutil.Process(server.process.pid).children(recursive=True)
                if "ipykernel" in " ".join(c.cmdline())
            ]
            before = received[0]
            start = time.perf_counter()
            run_cell(page, 1)
            page.wait_for_function(SCENE_READY, timeout=600000, polling=50)
            first_frame = time.perf_counter() - start
            wait_done(page, 1)
            page.wait_for_timeout(1500)  # let the plot finish too
            dashboard_bytes = received[0] - before
            rows.append(
                ("first 3D frame after running the cell", f"{first_frame:.2f} s")
            )
            rows.append(
                (
                    "bytes kernel->browser for the dashboard",
                    f"{dashboard_bytes / 1e6:.2f} MB",
                )
            )

            page.click(".rbm-play")
            page.wait_for_timeout(500)
            cpu0 = sum(kernel.cpu_times()[:2])
            bytes0, wall0 = received[0], time.perf_counter()
            idle = page.evaluate(MEASURE_JS, 5000)
            cpu = sum(kernel.cpu_times()[:2]) - cpu0
            wall = time.perf_counter() - wall0
            rows.append(("frames/s playing, kernel idle (rAF)", f"{idle['raf']:.1f}"))
            rows.append(
                ("3D renders/s playing, kernel idle", f"{idle['rendered']:.1f}")
            )
            rows.append(
                ("kernel CPU while the browser plays", f"{100 * cpu / wall:.1f} %")
            )
            rows.append(
                (
                    "bytes kernel->browser per s while playing",
                    f"{(received[0] - bytes0) / wall:.0f} B/s",
                )
            )
            run_cell(page, 2)
            page.wait_for_timeout(700)
            busy = page.evaluate(MEASURE_JS, 4000)
            rows.append(("frames/s playing, kernel busy (sleep)", f"{busy['raf']:.1f}"))
            rows.append(
                (
                    "scene seconds per wall second, kernel busy",
                    f"{busy['advanced'] / busy['seconds']:.3f}",
                )
            )
            wait_done(page, 2)
            context.close()
            browser.close()
    finally:
        server.stop()

    from rbm_nb.app.explorer import write_explorer_html

    start = time.perf_counter()
    out = write_explorer_html(tmp / "explorer.html", progress=False)
    rows.append(("HTML export of the explorer", f"{out.stat().st_size / 1e6:.2f} MB"))
    rows.append(("HTML export time", f"{time.perf_counter() - start:.1f} s"))
    width = max(len(r[0]) for r in rows)
    print(
        f"data: {'real (rbm-data)' if SHARED.is_dir() else 'synthetic'}; load: {os.getloadavg()[0]:.1f}"
    )
    for name, value in rows:
        print(f"{name:<{width}}  {value}")


if __name__ == "__main__":
    main()
