"""rerun's notebook viewer on the explorer's content, in JupyterLab under chromium (issue 35).

    # rerun in a throwaway venv outside the repo (never a project dependency):
    python -m venv /tmp/rerun-venv && /tmp/rerun-venv/bin/pip install rerun-sdk rerun-notebook ipykernel
    RBM_NB_DATA_DIR=/work/shared/data/rbm-data PYTHONPATH=. \\
        python benchmarks/bench_rerun_lab.py --venv /tmp/rerun-venv [--hours 0]

This process (rbm_nb's environment) computes what the explorer shows for the
recording tiled to ``hours`` (``tiled_recording.py``): the head's pose, both
eyes' orientation in the head, the head's path and the five plotted series
(head yaw rate; gaze yaw and gaze yaw rate of each eye), and saves them. A
kernel of the rerun venv logs them with ``send_columns`` (a head ellipsoid,
eye axes and a gaze arrow moving with the transforms, the path as a line
strip, one Scalars entity per plotted series) and shows
``rr.notebook_show()`` with the viewer inlined (``RERUN_NOTEBOOK_ASSET=inline``:
nothing from the network). Measured as ``bench_dashboard_lab.py`` measures
rbm_nb's dashboard: bytes over the wire from the cell's start to the first
frame (the viewer's canvas shows a picture) and 8 s later, seconds from the
cell's start to that frame, the renderer's resident memory.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "tests"))

CELL = """
import os, time, json
cell_start = time.time()
os.environ["RERUN_NOTEBOOK_ASSET"] = "inline"
import numpy as np
import rerun as rr
d = np.load({data!r})
rr.init("explorer", spawn=False)
ht = d["head_t"]
rr.log("world/head/model", rr.Ellipsoids3D(half_sizes=[[0.09, 0.075, 0.11]], colors=[[222, 184, 135]]), static=True)
rr.log("world/path", rr.LineStrips3D([d["path"]], colors=[[255, 255, 255]]), static=True)
rr.send_columns("world/head", indexes=[rr.TimeColumn("time", timestamp=ht)],
    columns=rr.Transform3D.columns(translation=d["head_p"], quaternion=d["head_q"]))
for eye, colour in (("left_eye", [230, 159, 0]), ("right_eye", [0, 148, 214])):
    rr.log(f"world/head/{{eye}}/gaze", rr.Arrows3D(vectors=[[0, 0, 2.0]], colors=[colour]), static=True)
    rr.send_columns(f"world/head/{{eye}}", indexes=[rr.TimeColumn("time", timestamp=d[eye + "_t"])],
        columns=rr.Transform3D.columns(quaternion=d[eye + "_q"]))
for name in ("head_yaw_rate", "gaze_yaw_left", "gaze_yaw_right", "gaze_rate_left", "gaze_rate_right"):
    rr.send_columns(f"plots/{{name}}", indexes=[rr.TimeColumn("time", timestamp=d[name + "_t"])],
        columns=rr.Scalars.columns(scalars=d[name]))
print("LOGGED " + json.dumps({{"start": cell_start, "log_s": time.time() - cell_start}}))
rr.notebook_show(width=1100, height=700)
"""


def content(hours: float, path: Path) -> None:
    """Save what the explorer shows for the recording tiled to ``hours``."""
    from tiled_recording import tiled_head_eye

    from rbm_nb import explorer

    head, left, right = tiled_head_eye(hours)
    explorer.register_head_eye_frames(head, left, right)
    series = explorer.explorer_series(head, left, right)
    out = {}

    def seconds(t):
        return t.astype("datetime64[ns]").astype(np.int64) / 1e9

    # the tracker's own pose (its axes; the explorer's world is a fixed turn of them)
    ok = np.isfinite(head.orientation.values).all(axis=1)
    out["head_t"] = seconds(head.time.values[ok])
    out["head_p"] = head.position.values[ok].astype(np.float32)
    out["head_q"] = head.orientation.values[ok][:, [1, 2, 3, 0]].astype(
        np.float32
    )  # xyzw
    out["path"] = out["head_p"][:: max(1, int(ok.sum()) // 2000)]
    for eye in ("left_eye", "right_eye"):
        times, rotation = explorer._motion(
            getattr(explorer.EXAMPLE_FRAMES, eye), explorer.EXAMPLE_FRAMES.head
        )
        ok = ~np.isnan(rotation).any(axis=1)
        out[eye + "_t"] = seconds(np.asarray(times)[ok])
        out[eye + "_q"] = rotation[ok][:, [1, 2, 3, 0]].astype(np.float32)
    names = {
        "head_yaw_rate": ("head yaw rate", None),
        "gaze_yaw_left": ("gaze yaw", 0),
        "gaze_yaw_right": ("gaze yaw", 1),
        "gaze_rate_left": ("gaze yaw rate", 0),
        "gaze_rate_right": ("gaze yaw rate", 1),
    }
    for key, (label, column) in names.items():
        da = series[label]
        values = da.values if column is None else da.values[:, column]
        values = values.reshape(len(da.time), -1)[:, 0]
        ok = np.isfinite(values)
        out[key + "_t"] = seconds(da.time.values[ok])
        out[key] = values[ok]
    np.savez(path, **out)


def measure(hours: float, venv: Path) -> dict:
    import nbformat
    from bench_dashboard_lab import CountingProxy, _renderer_rss
    from browser_support import (
        CHROMIUM,
        CHROMIUM_ARGS,
        JupyterLab,
        block_other_ports,
        png_pixels,
    )
    from playwright.sync_api import TimeoutError as PlaywrightTimeout
    from playwright.sync_api import sync_playwright

    tmp = Path(tempfile.mkdtemp(prefix="bench_rerun_"))
    content(hours, tmp / "content.npz")
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(CELL.format(data=str(tmp / "content.npz")))]
    nb.metadata["kernelspec"] = {
        "name": "rerun",
        "display_name": "rerun",
        "language": "python",
    }
    nbformat.write(nb, tmp / "rerun.ipynb")
    (tmp / "lab").mkdir()
    server = JupyterLab(tmp / "lab", [tmp / "rerun.ipynb"])
    spec = tmp / "lab" / "data" / "kernels" / "rerun"
    spec.mkdir(parents=True)
    (spec / "kernel.json").write_text(
        json.dumps(
            {
                "argv": [
                    str(venv / "bin" / "python"),
                    "-m",
                    "ipykernel_launcher",
                    "-f",
                    "{connection_file}",
                ],
                "display_name": "rerun",
                "language": "python",
            }
        )
    )
    row: dict = {"hours": hours}
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            try:
                context = browser.new_context(viewport={"width": 1400, "height": 1000})
                proxy = CountingProxy(server.port)
                blocked = block_other_ports(context, proxy.port)
                page = context.new_page()
                page.goto(
                    server.notebook_url("rerun.ipynb").replace(
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
                proxy.down = 0
                page.get_by_role("menuitem", name="Run", exact=True).click()
                page.get_by_text("Run All Cells", exact=True).click()
                out = page.locator(".jp-OutputArea-output", has_text="LOGGED")
                out.wait_for(timeout=900000)
                logged = json.loads(
                    re.search(r"LOGGED (\{.*\})", out.inner_text()).group(1)
                )
                deadline = time.time() + 600
                while True:
                    canvas = page.locator(".jp-OutputArea-output canvas").first
                    if canvas.count() and canvas.is_visible():
                        img = png_pixels(canvas.screenshot(timeout=5000))
                        if float(img.reshape(-1, 3).std(axis=0).max()) > 8.0:
                            break
                    if time.time() > deadline:
                        raise RuntimeError("rerun's viewer did not draw in 10 minutes")
                    page.wait_for_timeout(100)
                row["drawn_s"] = time.time() - logged["start"]
                row["log_s"] = logged["log_s"]
                row["sent_MB"] = proxy.down / 1e6
                page.wait_for_timeout(8000)
                row["sent_all_MB"] = proxy.down / 1e6
                row["renderer_MB"] = _renderer_rss() / 1e6
                row["blocked"] = len(blocked)
                page.screenshot(path=str(tmp / "rerun.png"))
                row["screenshot"] = str(tmp / "rerun.png")
            finally:
                browser.close()
    finally:
        server.stop()
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument(
        "--venv",
        type=Path,
        required=True,
        help="venv with rerun-sdk, rerun-notebook, ipykernel",
    )
    parser.add_argument("--hours", type=float, nargs="+", default=[0.0])
    args = parser.parse_args()
    for hours in args.hours:
        print(json.dumps(measure(hours, args.venv.resolve())), flush=True)


if __name__ == "__main__":
    main()
