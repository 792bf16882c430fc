"""The explorer's dashboard in JupyterLab under chromium, at 5.5 min, 1 h and 3 h (issue 35).

    RBM_NB_DATA_DIR=/work/shared/data/rbm-data PYTHONPATH=. \\
        python benchmarks/bench_dashboard_lab.py [--hours 0 1 3] [--tree OTHER_CHECKOUT]

For each length, a fresh JupyterLab (loopback, token in the environment, as
``tests/browser_support.py`` starts it) and a fresh Debian chromium (headless,
software WebGL, every request to another port aborted) run a notebook of two
cells: the example recording tiled in time (``tiled_recording.py``: head 200
Hz, eyes ~340 Hz, NaN rows kept), then ``explorer.dashboard(*data)``.
Everything is read from outside, through the page and the processes, so the
same script measures any tree (``--tree`` runs the kernel on another
checkout, e.g. main before a change):

* ``kernel build``: seconds of the ``dashboard()`` call, as the kernel times it;
* ``sent``: bytes the Jupyter server sent the page (counted on the wire by a
  loopback relay the page talks through) from the end of the loading cell to
  the first frame (3D view and plots drawn), by the relay's clock;
* ``cell -> drawn``: seconds from the start of the dashboard cell (after the
  data is loaded; the kernel's clock) until the page painted a frame in which
  the 3D view had drawn its content and every plot panel's uPlot canvas
  existed. The page times this itself (``FIRST_FRAME``, on the same machine's
  clock): the first animation frame after one in which a scene view had
  rendered a frame holding content and the frames' labels, and every panel
  its chart. Afterwards screenshots of the canvas must show a picture (else
  the run fails). Polling from playwright instead (waiting for the cell's
  printout, then screenshots every 0.1 s) lags the page by up to ~1 s at 3 h;
  that figure is kept as ``drawn_polled_s`` in the JSON rows;
  ``sent in all``: the bytes received by 8 s later;
* ``renderer``: resident memory (RSS) summed over chromium's renderer
  processes after drawing (as in earlier tables; it counts spare renderers
  and chromium's shared code in each: an empty JupyterLab notebook reads
  ~500 MB), then the tab's renderer alone as private memory (USS) and the
  GPU process's PSS (software WebGL draws there), as
  ``bench_renderer_memory.py`` reads them; that script also measures the
  empty notebook, the floor these figures sit on;
* ``kernel RSS``: the kernel's resident memory after the build (and its peak,
  VmHWM), and its growth over the RSS before the data was loaded (rbm_nb's
  modules already imported) per byte of the loaded datasets' own arrays (the
  issue's target: <= 1.5; numba's compiled kernels load during the first
  build, a fixed ~0.2 GB that weighs most at 5.5 min);
* ``zoom 10 s``: the plot zoomed (uPlot's setScale, as a drag does) into three
  10 s windows in turn (at 10 %, 50 % and 90 % of the recording): ms until the
  page holds every sample there (the kernel's answer marked full resolution)
  and a frame was painted; the slowest of the three;
* ``fps 1x / 10x``: requestAnimationFrame callbacks per second during 6 s of
  playback (started by setting the Player's ``speed`` and ``playing``), and how far the
  Player's readout advanced per wall-clock second (1.0 / 10.0: the clock
  never waited).

One length at a time (the 3 h dashboard of today's main needs about 5 GB of
kernel memory). Prints a Markdown table.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
sys.path.insert(0, str(REPO / "tests"))
sys.path.insert(0, str(HERE))

LOAD_CELL = """
import os, sys, time, psutil
sys.path.insert(0, {bench!r})
from rbm_nb import explorer
import rbm_nb.scene, rbm_nb.widgets, ipywidgets  # imports are not the data's memory
from tiled_recording import tiled_head_eye, loaded_bytes
_proc = psutil.Process()
rss_before = _proc.memory_info().rss
data = tiled_head_eye({hours})
import gc, json; gc.collect()
print("LOADED " + json.dumps({{"loaded": loaded_bytes(data), "rss_before": rss_before,
    "rss_loaded": _proc.memory_info().rss, "pid": os.getpid(),
    "span_s": float((data[0].time.values[-1] - data[0].time.values[0]) / 1e9)}}))
"""

BUILD_CELL = """
cell_start = time.time()
board = explorer.dashboard(*data)
built = time.time() - cell_start
import gc; gc.collect()
with open("/proc/self/status") as _f:
    _peak = [int(l.split()[1]) * 1024 for l in _f if l.startswith("VmHWM")][0]
print("BUILT " + json.dumps({"start": cell_start, "build_s": built,
    "rss": _proc.memory_info().rss, "rss_peak": _peak}))
board
"""

# the Player's menu stops at 8x: 10x is set through the Player's public traits
SPEED_CELL = """
import ipywidgets as widgets

def _play(speed):
    def click(_):
        board.player.speed = speed
        board.player.playing = speed > 0
    return click

_buttons = [widgets.Button(description=f"bench {s}x") for s in (1, 10)]
_buttons.append(widgets.Button(description="bench stop"))
for _b, _s in zip(_buttons, (1, 10, 0)):
    _b.on_click(_play(_s))
widgets.HBox(_buttons)
"""

# every plot panel has its uPlot; the 3D view is measured by screenshots
PLOTS_DRAWN = """() => {
  const roots = [...document.querySelectorAll('.rbm-ts')];
  return roots.length > 0 && roots.every((r) => r.rbmCharts && r.rbmCharts.length > 0
    && r.querySelectorAll('canvas').length >= r.rbmCharts.length);
}"""

# The page's own clock for the first frame: an animation-frame loop, from the
# page's start, notes (Date.now(), the machine's clock as the kernel's
# time.time()) the frame after the first in which a scene view had rendered
# content (meshcat commands in its store, at least one frame drawn, labels
# placed) and every plot panel had its charts: that frame was on screen.
FIRST_FRAME = (
    """(() => {
  const plots = """
    + PLOTS_DRAWN
    + """;
  const scene = () => [...document.querySelectorAll('.rbm-scene')].some((r) => r.rbmView
    && r.rbmView.frames > 0 && r.rbmView.store.commands.length > 0
    && r.querySelectorAll('.rbm-label').length > 0);
  const marks = (window.rbmBenchFrames = {});
  const tick = () => {
    const now = Date.now();
    if (!marks.plotsSeen && plots()) marks.plotsSeen = now;
    if (!marks.sceneSeen && scene()) marks.sceneSeen = now;
    if (marks.plotsSeen && marks.sceneSeen) {
      marks.drawn = now;  // the frame of both is on screen
      return;
    }
    requestAnimationFrame(tick);
  };
  requestAnimationFrame(tick);
})();"""
)

ZOOM_JS = """async ([start, end]) => {
  const root = document.querySelector('.rbm-ts');
  const u = root.rbmCharts[0];
  const t0 = performance.now();
  u.setScale('x', {min: start, max: end});
  while (true) {
    const w = root.rbmWindow;
    // (a page without w.full sends a 10 s window at full resolution: <= 20000 rows)
    if (w && w.start === start && w.end === end && (!w.full || w.full.every(Boolean))) break;
    if (performance.now() - t0 > 60000) return null;
    await new Promise((r) => setTimeout(r, 2));
  }
  await new Promise((r) => requestAnimationFrame(() => r()));
  return performance.now() - t0;
}"""

# the page's frame rate and the Player's readout over ``ms``
PLAY_JS = """async (ms) => {
  const readout = () => parseFloat(document.querySelector('.rbm-player .rbm-readout').textContent);
  const s0 = readout(), t0 = performance.now();
  let n = 0;
  await new Promise((resolve) => {
    function tick() { n += 1; if (performance.now() - t0 < ms) requestAnimationFrame(tick); else resolve(); }
    requestAnimationFrame(tick);
  });
  const seconds = (performance.now() - t0) / 1000;
  return {fps: n / seconds, clock: (readout() - s0) / seconds};
}"""


class CountingProxy:
    """A loopback TCP relay to the Jupyter server counting the bytes it sends back.

    Counted on the wire (what a remote browser would download), whatever the
    page's tools report: chromium's devtools leave very large websocket frames
    out of their events (a 100 MB scene message was not seen).
    """

    def __init__(self, port: int):
        import socket
        import threading

        self.target = port
        # (time.time(), bytes) of every read sent back: bytes between two
        # instants of the kernel's clock, however late the page is watched
        self.log: list[tuple[float, int]] = []
        self._lock = threading.Lock()
        self._server = socket.create_server(("127.0.0.1", 0))
        self.port = self._server.getsockname()[1]
        self._open = True
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self) -> None:
        import socket
        import threading

        while self._open:
            try:
                client, _ = self._server.accept()
            except OSError:
                return
            upstream = socket.create_connection(("127.0.0.1", self.target))
            for src, dst, count in (
                (client, upstream, False),
                (upstream, client, True),
            ):
                threading.Thread(
                    target=self._pump, args=(src, dst, count), daemon=True
                ).start()

    def _pump(self, src, dst, count: bool) -> None:
        try:
            while data := src.recv(1 << 16):
                dst.sendall(data)
                if count:
                    with self._lock:
                        self.log.append((time.time(), len(data)))
        except OSError:
            pass
        finally:
            for sock in (src, dst):
                try:
                    sock.shutdown(2)
                except OSError:
                    pass

    def sent_between(self, start: float, end: float) -> int:
        with self._lock:
            return sum(n for t, n in self.log if start <= t <= end)

    def close(self) -> None:
        self._open = False
        self._server.close()


def _renderer_rss() -> int:
    """Resident bytes of this process tree's chromium renderers."""
    import psutil

    total = 0
    for child in psutil.Process().children(recursive=True):
        try:
            if "--type=renderer" in " ".join(child.cmdline()):
                total += child.memory_info().rss
        except psutil.NoSuchProcess:
            pass
    return total


def _scene_drawn(page) -> bool:
    """Whether the 3D view shows its content: frame labels and a picture.

    The grid and axes draw before the scene's content arrives; the frames'
    labels come with it (and the head model with its pose).
    """
    from browser_support import png_pixels

    if page.locator(".rbm-scene .rbm-label").count() == 0:
        return False
    canvas = page.locator(".rbm-scene canvas").first
    if canvas.count() == 0 or not canvas.is_visible():
        return False
    img = png_pixels(canvas.screenshot(timeout=5000))
    return float(img.reshape(-1, 3).std(axis=0).max()) > 8.0


def _output(page, marker: str, timeout_ms: float) -> dict:
    out = page.locator(".jp-OutputArea-output", has_text=marker)
    out.wait_for(timeout=timeout_ms)
    text = out.inner_text()
    return json.loads(re.search(marker + r" (\{.*\})", text).group(1))


def measure(hours: float, tree: Path) -> dict:
    import nbformat
    from bench_renderer_memory import chromium_processes
    from browser_support import CHROMIUM, CHROMIUM_ARGS, JupyterLab, block_other_ports
    from playwright.sync_api import TimeoutError as PlaywrightTimeout
    from playwright.sync_api import sync_playwright

    tmp = Path(tempfile.mkdtemp(prefix="bench_lab_"))
    nb = nbformat.v4.new_notebook()
    load = LOAD_CELL.format(bench=str(HERE), hours=hours)
    nb.cells = [
        nbformat.v4.new_code_cell(load),
        nbformat.v4.new_code_cell(BUILD_CELL),
        nbformat.v4.new_code_cell(SPEED_CELL),
    ]
    nb.metadata["kernelspec"] = {
        "name": "python3",
        "display_name": "Python 3",
        "language": "python",
    }
    nbformat.write(nb, tmp / "bench.ipynb")
    (tmp / "lab").mkdir()
    os.environ["PYTHONPATH"] = str(tree)
    server = JupyterLab(tmp / "lab", [tmp / "bench.ipynb"])
    row: dict = {"hours": hours}
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            try:
                context = browser.new_context(viewport={"width": 1400, "height": 1000})
                proxy = CountingProxy(server.port)
                blocked = block_other_ports(context, proxy.port)
                page = context.new_page()
                page.add_init_script(FIRST_FRAME)
                errors: list[str] = []
                page.on("pageerror", lambda e: errors.append(str(e)))
                page.goto(
                    server.notebook_url("bench.ipynb").replace(
                        f":{server.port}/", f":{proxy.port}/"
                    ),
                    timeout=120000,
                )
                page.wait_for_selector(".jp-Notebook .jp-Cell", timeout=120000)
                try:
                    page.locator(".jp-Dialog").get_by_role(
                        "button", name="Select", exact=True
                    ).click(timeout=15000)
                except PlaywrightTimeout:
                    pass
                page.wait_for_selector(
                    ".jp-Notebook-ExecutionIndicator[data-status='idle']",
                    timeout=120000,
                )
                page.get_by_role("menuitem", name="Run", exact=True).click()
                page.get_by_text("Run All Cells", exact=True).click()
                loaded = _output(page, "LOADED", 900000)
                built = _output(page, "BUILT", 1800000)
                page.wait_for_function(PLOTS_DRAWN, timeout=600000, polling=50)
                plots_at = time.time()
                deadline = time.time() + 600
                while not _scene_drawn(page):
                    if time.time() > deadline:
                        raise RuntimeError("the 3D view did not draw in 10 minutes")
                    page.wait_for_timeout(100)
                polled_at = max(time.time(), plots_at)
                page.wait_for_function(
                    "() => window.rbmBenchFrames.drawn", timeout=60000, polling=50
                )
                marks = page.evaluate("window.rbmBenchFrames")
                drawn_at = marks["drawn"] / 1000
                row["drawn_s"] = drawn_at - built["start"]
                row["drawn_polled_s"] = polled_at - built["start"]
                # what the dashboard cell costs: from its start to the first frame
                row["sent_MB"] = proxy.sent_between(built["start"], drawn_at) / 1e6
                row["build_s"] = built["build_s"]
                # settle: what the views still fetch (plots at their own width,
                # poses) and the page's work on it
                page.wait_for_timeout(8000)
                row["sent_all_MB"] = (
                    proxy.sent_between(built["start"], time.time()) / 1e6
                )
                row["renderer_MB"] = _renderer_rss() / 1e6
                procs = chromium_processes()
                tab = max(
                    (p for p in procs if p["type"] == "renderer"),
                    key=lambda p: p["pss"],
                )
                row["tab_uss_MB"] = tab["uss"] / 1e6
                row["gpu_pss_MB"] = (
                    sum(p["pss"] for p in procs if p["type"] == "gpu-process") / 1e6
                )
                row["loaded_MB"] = loaded["loaded"] / 1e6
                row["rss_GB"] = built["rss"] / 1e9
                row["rss_peak_GB"] = built["rss_peak"] / 1e9
                row["rss_per_loaded"] = (built["rss"] - loaded["rss_before"]) / loaded[
                    "loaded"
                ]
                span = loaded["span_s"]
                zooms = []
                for frac in (0.1, 0.5, 0.9):
                    start = round(frac * span, 3)
                    zooms.append(page.evaluate(ZOOM_JS, [start, start + 10.0]))
                row["zoom_ms"] = None if None in zooms else max(zooms)
                row["zoom_all_ms"] = zooms
                page.evaluate(
                    "(() => { const u = document.querySelector('.rbm-ts').rbmCharts[0];"
                    " u.setScale('x', {min: u.data[0][0], max: u.data[0][u.data[0].length - 1]}); })()"
                )
                for speed in ("1", "10"):
                    page.get_by_role("button", name=f"bench {speed}x").click()
                    page.wait_for_timeout(1500)
                    played = page.evaluate(PLAY_JS, 6000)
                    page.get_by_role("button", name="bench stop").click()
                    page.wait_for_timeout(500)
                    row[f"fps_{speed}x"] = played["fps"]
                    row[f"clock_{speed}x"] = played["clock"]
                row["blocked"] = len(blocked)
                row["page_errors"] = errors[:3]
                page.screenshot(path=str(tmp / "dashboard.png"), full_page=True)
                row["screenshot"] = str(tmp / "dashboard.png")
            finally:
                browser.close()
    finally:
        server.stop()
    return row


def label(hours: float) -> str:
    return "5.5 min (real)" if hours <= 0 else f"{hours:g} h"


def table(rows: list[dict]) -> str:
    head = (
        "| recording | kernel build | sent before first frame (in all) | cell -> 3D + plots drawn "
        "| renderer: sum of RSS (tab private, GPU) | kernel RSS (growth / loaded) | zoom 10 s -> full resolution drawn "
        "| fps 1x (clock) | fps 10x (clock) |\n|---|---|---|---|---|---|---|---|---|"
    )
    lines = [head]
    for r in rows:
        zoom = "-" if r.get("zoom_ms") is None else f"{r['zoom_ms']:.0f} ms"
        lines.append(
            f"| {label(r['hours'])} | {r['build_s']:.1f} s | {r['sent_MB']:.1f} MB ({r['sent_all_MB']:.1f}) "
            f"| {r['drawn_s']:.1f} s | {r['renderer_MB']:.0f} MB "
            f"({r['tab_uss_MB']:.0f}, {r['gpu_pss_MB']:.0f} MB) "
            f"| {r['rss_GB']:.2f} GB, peak {r['rss_peak_GB']:.2f} ({r['rss_per_loaded']:.2f} x {r['loaded_MB']:.0f} MB) "
            f"| {zoom} | {r['fps_1x']:.0f} ({r['clock_1x']:.2f} s/s) "
            f"| {r['fps_10x']:.0f} ({r['clock_10x']:.2f} s/s) |"
        )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--hours", type=float, nargs="+", default=[0.0, 1.0, 3.0])
    parser.add_argument(
        "--tree",
        type=Path,
        default=REPO,
        help="checkout the kernel imports rbm_nb from",
    )
    parser.add_argument("--json", type=Path, help="also write the rows here")
    args = parser.parse_args()
    rows = []
    for hours in args.hours:
        try:
            row = measure(hours, args.tree.resolve())
        except Exception as err:  # the next length may still run
            # (today's 3 h scene is one 313 MB message: playwright's driver,
            # which sees every websocket frame, runs out of memory on it)
            print(
                f"{label(hours)}: failed: {type(err).__name__}: {err}"[:500], flush=True
            )
            continue
        print(json.dumps(row), flush=True)
        rows.append(row)
    print(f"\nkernel on {args.tree.resolve()}\n")
    print(table(rows))
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
