"""What the browser's page costs: the floor of JupyterLab / Notebook 7, and what rbm_nb adds (issue 35).

    RBM_NB_DATA_DIR=/work/shared/data/rbm-data PYTHONPATH=. \\
        python benchmarks/bench_renderer_memory.py [--apps lab notebook] [--hours 0 3]
        [--only empty import scene ...] [--tree OTHER_CHECKOUT] [--json rows.json]

``bench_dashboard_lab.py``'s ``renderer`` column is the resident memory
(RSS) *summed over every chromium process started with --type=renderer*:
that counts the tab's renderer, any spare renderer chromium keeps warm, and
in each of them the pages of chromium's own code and fonts shared with
every other chromium process. This script measures the same page in fairer
ways, side by side, for each configuration on its own fresh chromium
(headless, software WebGL: ``tests/browser_support.py``'s flags, every
request to another port aborted) and the same Jupyter server:

* ``empty``: the notebook with one empty cell (JupyterLab's or Notebook 7's
  own page: the floor);
* ``import``: a cell ``import rbm_nb, rbm_nb.widgets, rbm_nb.scene``;
* ``scene``, ``player``, ``plot``, ``tree``: one widget of the explorer on
  the real recording (``tiled_recording.py`` at ``--hours``' first value),
  shown alone: the 3D view (``explorer_scene()``), the Player (its scene's
  model exists in the page, no view of it), the TimeSeries of the
  explorer's series (``explorer_plot``) and the FrameTree (ipywidgets only);
* ``dashboard``: ``explorer.dashboard(*data)`` at each of ``--hours``.

For each, 8 s after the widgets drew and a garbage collection, the columns are:

* ``renderers RSS (old)``: bench_dashboard_lab.py's figure;
* ``tab RSS / PSS / private``: the tab's renderer process (the renderer
  with the largest PSS; chromium's spare renderers hold ~no page) as
  resident, proportional (shared pages split among the processes sharing
  them) and private (USS: only this process's pages) memory;
* ``JS heap``: the page's V8 heap in use (CDP ``Performance.getMetrics``
  JSHeapUsedSize), and DOM nodes (``Memory.getDOMCounters``);
* ``GPU PSS``: chromium's GPU process (software WebGL through SwiftShader
  runs there: its textures, buffers and drawing surfaces).

Prints a Markdown table per frontend, and "adds over empty" (tab private
memory minus the empty notebook's).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
sys.path.insert(0, str(REPO / "tests"))

SETUP = """
import sys, time
sys.path.insert(0, {bench!r})
from rbm_nb import explorer
from tiled_recording import tiled_head_eye
head, left, right = tiled_head_eye({hours})
"""

CELLS = {
    "empty": None,
    "import": "import rbm_nb, rbm_nb.widgets, rbm_nb.scene\nprint('READY')",
    "scene": SETUP
    + """explorer.register_head_eye_frames(head, left, right)
scene = explorer.explorer_scene()
print('READY')
scene.widget
""",
    "player": SETUP
    + """explorer.register_head_eye_frames(head, left, right)
scene = explorer.explorer_scene()
player = scene.player(speed=1.0)
print('READY')
player
""",
    "plot": SETUP
    + """explorer.register_head_eye_frames(head, left, right)
series = explorer.explorer_series(head, left, right)
plot = explorer.explorer_plot(series, None)
print('READY')
plot
""",
    "tree": SETUP
    + """from rbm_nb.widgets.frame_tree import FrameTree
explorer.register_head_eye_frames(head, left, right)
tree = FrameTree(explorer.EXAMPLE_FRAMES.world)
print('READY')
tree
""",
    "dashboard": SETUP
    + """board = explorer.dashboard(head, left, right)
print('READY')
board
""",
}

# what must be in the page before the settling time starts
DRAWN = {
    "empty": "() => true",
    "import": "() => true",
    "scene": """() => { const el = document.querySelector('.rbm-scene');
        return el && el.rbmView && el.rbmView.frames > 0
          && document.querySelectorAll('.rbm-scene .rbm-label').length > 0; }""",
    "player": "() => document.querySelector('.rbm-player .rbm-readout') !== null",
    "plot": """() => { const r = document.querySelector('.rbm-ts');
        return r && r.rbmCharts && r.rbmCharts.length > 0; }""",
    "tree": "() => document.querySelectorAll('.jp-OutputArea-output .widget-vbox').length > 0",
}
DRAWN["dashboard"] = (
    "() => ("
    + DRAWN["scene"]
    + ")() && ("
    + DRAWN["plot"]
    + ")() && ("
    + DRAWN["player"]
    + ")()"
)

SETTLE_MS = 8000


def chromium_processes() -> list[dict]:
    """Every chromium process under this one: type, RSS, PSS, USS (bytes)."""
    import psutil

    out = []
    for child in psutil.Process().children(recursive=True):
        try:
            cmd = child.cmdline()
            if not cmd or "chrom" not in os.path.basename(cmd[0]):
                continue
            kind = next(
                (a.split("=", 1)[1] for a in cmd if a.startswith("--type=")),
                "browser",
            )
            if kind == "utility":
                sub = next(
                    (
                        a.split("=", 1)[1]
                        for a in cmd
                        if a.startswith("--utility-sub-type=")
                    ),
                    "",
                )
                kind = f"utility:{sub.rsplit('.', 1)[-1]}"
            full = child.memory_full_info()
            out.append(
                {
                    "pid": child.pid,
                    "type": kind,
                    "rss": full.rss,
                    "pss": full.pss,
                    "uss": full.uss,
                }
            )
        except (psutil.NoSuchProcess, psutil.AccessDenied):
            pass
    return out


def measure_one(browser_type, server, name: str, wait_ms: float) -> dict:
    from browser_support import CHROMIUM, CHROMIUM_ARGS, block_other_ports
    from playwright.sync_api import TimeoutError as PlaywrightTimeout

    browser = browser_type.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
    try:
        context = browser.new_context(viewport={"width": 1400, "height": 1000})
        blocked = block_other_ports(context, server.port)
        page = context.new_page()
        page.goto(server.notebook_url(f"{name}.ipynb"), timeout=120000)
        page.wait_for_selector(".jp-Notebook .jp-CodeCell", timeout=120000)
        try:
            page.locator(".jp-Dialog").get_by_role(
                "button", name="Select", exact=True
            ).click(timeout=10000)
        except PlaywrightTimeout:
            pass
        t0 = time.time()
        if CELLS[name] is not None:
            cell = page.locator(".jp-Notebook .jp-CodeCell").first
            ready = page.locator(".jp-OutputArea-output", has_text="READY")
            for _ in range(20):
                cell.locator(".jp-InputArea-editor").click()
                page.keyboard.press("Shift+Enter")
                try:
                    ready.wait_for(timeout=15000)
                    break
                except PlaywrightTimeout:
                    if "*" in cell.locator(".jp-InputPrompt").inner_text():
                        ready.wait_for(timeout=wait_ms)
                        break
        else:
            page.wait_for_selector(
                ".jp-Notebook-ExecutionIndicator[data-status='idle'], "
                ".jp-KernelStatus, #jp-top-panel",
                timeout=120000,
            )
        page.wait_for_function(DRAWN[name], timeout=wait_ms, polling=100)
        drawn_s = time.time() - t0
        page.wait_for_timeout(SETTLE_MS)
        cdp = context.new_cdp_session(page)
        # what the page holds, not what V8 has yet to collect
        cdp.send("HeapProfiler.collectGarbage")
        page.wait_for_timeout(1000)
        cdp.send("Performance.enable")
        metrics = {
            m["name"]: m["value"] for m in cdp.send("Performance.getMetrics")["metrics"]
        }
        dom = cdp.send("Memory.getDOMCounters")
        procs = chromium_processes()
        renderers = [p for p in procs if p["type"] == "renderer"]
        tab = max(renderers, key=lambda p: p["pss"])
        gpu = [p for p in procs if p["type"] == "gpu-process"]
        row = {
            "name": name,
            "drawn_s": drawn_s,
            "renderers_rss_MB": sum(p["rss"] for p in renderers) / 1e6,
            "renderers": len(renderers),
            "tab_rss_MB": tab["rss"] / 1e6,
            "tab_pss_MB": tab["pss"] / 1e6,
            "tab_uss_MB": tab["uss"] / 1e6,
            "js_heap_MB": metrics.get("JSHeapUsedSize", 0) / 1e6,
            "js_heap_total_MB": metrics.get("JSHeapTotalSize", 0) / 1e6,
            "dom_nodes": dom.get("nodes"),
            "gpu_pss_MB": sum(p["pss"] for p in gpu) / 1e6,
            "gpu_uss_MB": sum(p["uss"] for p in gpu) / 1e6,
            "all_pss_MB": sum(p["pss"] for p in procs) / 1e6,
            "processes": [(p["type"], round(p["pss"] / 1e6)) for p in procs],
            "blocked": len(blocked),
            "canvases": page.evaluate("document.querySelectorAll('canvas').length"),
            "webgl_contexts": page.evaluate(WEBGL_CONTEXTS),
        }
        shots = os.environ.get("RBM_NB_SHOTS")
        if shots:
            page.screenshot(
                path=str(Path(shots) / f"renderer_{server.app}_{name}.png"),
                full_page=True,
            )
        return row
    finally:
        browser.close()


# three.js renderers of the 3D views on the page, and their GPU objects
WEBGL_CONTEXTS = """(() => {
  const views = [...document.querySelectorAll('.rbm-scene')].map((e) => e.rbmView).filter(Boolean);
  return views.map((v) => { const r = v.viewer.renderer;
    return {geometries: r.info.memory.geometries, textures: r.info.memory.textures,
            pixelRatio: r.getPixelRatio(),
            antialias: !!(r.getContextAttributes && r.getContextAttributes().antialias)}; });
})()"""


def write_notebooks(tmp: Path, names: list[str], hours: float) -> list[Path]:
    import nbformat

    paths = []
    for name in names:
        nb = nbformat.v4.new_notebook()
        source = CELLS[name] or ""
        nb.cells = [
            nbformat.v4.new_code_cell(source.format(bench=str(HERE), hours=hours))
        ]
        nb.metadata["kernelspec"] = {
            "name": "python3",
            "display_name": "Python 3",
            "language": "python",
        }
        path = tmp / f"{name}.ipynb"
        nbformat.write(nb, path)
        paths.append(path)
    return paths


def run(app: str, names: list[str], hours: float, tree: Path) -> list[dict]:
    """Each configuration on its own Jupyter server (a JupyterLab workspace
    reopens the notebooks of the last page) and its own chromium."""
    from browser_support import JupyterLab
    from playwright.sync_api import sync_playwright

    tmp = Path(tempfile.mkdtemp(prefix=f"bench_renderer_{app}_"))
    notebooks = dict(zip(names, write_notebooks(tmp, names, hours), strict=True))
    os.environ["PYTHONPATH"] = str(tree)
    rows = []
    with sync_playwright() as pw:
        for name in names:
            home = tmp / f"home_{name}"
            home.mkdir()
            server = JupyterLab(home, [notebooks[name]], app=app, proxy=False)
            try:
                row = measure_one(
                    pw.chromium, server, name, 900000 if hours >= 1 else 300000
                )
            except Exception as err:  # the next configuration may still run
                print(f"{app} {name}: failed: {type(err).__name__}: {err}"[:400])
                continue
            finally:
                server.stop()
            row.update(app=app, hours=hours)
            print(json.dumps(row), flush=True)
            rows.append(row)
    return rows


def label(row: dict) -> str:
    if row["name"] in ("empty", "import"):
        return row["name"]
    length = "5.5 min" if row["hours"] <= 0 else f"{row['hours']:g} h"
    return f"{row['name']} ({length})"


def table(rows: list[dict]) -> str:
    lines = [
        "| frontend | page | renderers RSS (old figure) | tab RSS | tab PSS | tab private "
        "| adds over empty (tab private + GPU PSS) | JS heap | DOM nodes | GPU process PSS | all chromium PSS |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    empty = {
        r["app"]: r["tab_uss_MB"] + r["gpu_pss_MB"]
        for r in rows
        if r["name"] == "empty"
    }
    for r in rows:
        base = empty.get(r["app"])
        adds = (
            "-"
            if base is None
            else f"{r['tab_uss_MB'] + r['gpu_pss_MB'] - base:+.0f} MB"
        )
        lines.append(
            f"| {'JupyterLab' if r['app'] == 'lab' else 'Notebook 7'} | {label(r)} "
            f"| {r['renderers_rss_MB']:.0f} MB ({r['renderers']}) | {r['tab_rss_MB']:.0f} MB "
            f"| {r['tab_pss_MB']:.0f} MB | {r['tab_uss_MB']:.0f} MB | {adds} "
            f"| {r['js_heap_MB']:.0f} MB | {r['dom_nodes']} | {r['gpu_pss_MB']:.0f} MB "
            f"| {r['all_pss_MB']:.0f} MB |"
        )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--apps", nargs="+", default=["lab", "notebook"])
    parser.add_argument("--hours", type=float, nargs="+", default=[0.0, 3.0])
    parser.add_argument("--only", nargs="+", choices=list(CELLS), default=list(CELLS))
    parser.add_argument("--tree", type=Path, default=REPO)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    rows = []
    for app in args.apps:
        single = [n for n in args.only if n != "dashboard"]
        rows += run(app, single, args.hours[0], args.tree.resolve())
        if "dashboard" in args.only:
            for hours in args.hours:
                rows += run(app, ["dashboard"], hours, args.tree.resolve())
    print(f"\nkernel and bundles from {args.tree.resolve()}\n")
    print(table(rows))
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
