"""rerun's notebook viewer on the explorer's content, in JupyterLab under chromium (issue 35).

    # rerun in a throwaway venv outside the repo (never a project dependency):
    uv venv /work/rr-venv && uv pip install --python /work/rr-venv/bin/python \\
        rerun-sdk rerun-notebook ipykernel
    RBM_NB_DATA_DIR=/work/shared/data/rbm-data PYTHONPATH=. \\
        python benchmarks/bench_rerun_lab.py --venv /work/rr-venv [--hours 0 1]

Without a venv that imports rerun and rerun_notebook it says so and exits
(status 0): rbm_nb never imports rerun.

This process (rbm_nb's environment) computes what the explorer shows for the
recording tiled to ``hours`` (``tiled_recording.py``): the head's pose, both
eyes' orientation in the head, the head's path and the five plotted series
(head yaw rate; gaze yaw and gaze yaw rate of each eye), and saves them. A
kernel of the rerun venv logs them with ``send_columns`` (a head ellipsoid,
eye axes and a gaze arrow moving with the transforms, the path as a line
strip, one Scalars entity per plotted series) into the
viewer of ``rr.notebook_show()`` (inlined: ``RERUN_NOTEBOOK_ASSET=inline``,
nothing from the network), shown *before* logging: the viewer's sink gets
what is logged after it exists (logged first, the viewer stays empty).
Measured as ``bench_dashboard_lab.py`` measures rbm_nb's dashboard: bytes
over the wire from the cell's start until the viewer reports the recording
open (its ``recording_open`` event, seen on the page's websocket) and 8 s
later, seconds from the cell's start to that event, and the page's memory
as ``bench_renderer_memory.py`` reads it (sum of renderer RSS, the tab's
renderer PSS and private memory, the GPU process). Screenshots of the viewer
go to ``RBM_NB_SHOTS`` when set.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
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
# shown first: the viewer receives what is logged once it is there
rr.notebook_show(width=1100, height=700)
shown_s = time.time() - cell_start
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
rr.get_data_recording().flush()
print("LOGGED " + json.dumps({{"start": cell_start, "shown_s": shown_s, "log_s": time.time() - cell_start}}))
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


def measure(hours: float, venv: Path, settle: float = 8.0) -> dict:
    import nbformat
    from bench_dashboard_lab import CountingProxy
    from bench_renderer_memory import chromium_processes
    from browser_support import (
        CHROMIUM,
        CHROMIUM_ARGS,
        JupyterLab,
        block_other_ports,
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
                # the viewer reports each recording it opens to the kernel
                opened: dict = {"at": None, "down": 0}

                def watch(ws):
                    def sent(payload):
                        if opened["at"] is None and "recording_open" in str(payload):
                            opened["at"], opened["down"] = time.time(), proxy.down

                    ws.on("framesent", sent)

                page.on("websocket", watch)
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
                while opened["at"] is None:
                    if time.time() > deadline:
                        raise RuntimeError(
                            "rerun's viewer opened no recording in 10 minutes"
                        )
                    page.wait_for_timeout(50)
                row["shown_s"] = logged["shown_s"]
                row["log_s"] = logged["log_s"]
                row["opened_s"] = opened["at"] - logged["start"]
                row["sent_MB"] = opened["down"] / 1e6
                page.wait_for_timeout(settle * 1000)
                row["sent_all_MB"] = proxy.down / 1e6
                procs = chromium_processes()
                renderers = [p for p in procs if p["type"] == "renderer"]
                tab = max(renderers, key=lambda p: p["pss"])
                row["renderers_rss_MB"] = sum(p["rss"] for p in renderers) / 1e6
                row["tab_pss_MB"] = tab["pss"] / 1e6
                row["tab_uss_MB"] = tab["uss"] / 1e6
                row["gpu_pss_MB"] = (
                    sum(p["pss"] for p in procs if p["type"] == "gpu-process") / 1e6
                )
                row["blocked"] = blocked[:3]
                shots = Path(os.environ.get("RBM_NB_SHOTS", tmp))
                shot = shots / f"rerun_{hours:g}h.png"
                page.screenshot(path=str(shot))
                row["screenshot"] = str(shot)
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
    parser.add_argument(
        "--settle", type=float, default=8.0, help="seconds after the recording opened"
    )
    args = parser.parse_args()
    python = args.venv / "bin" / "python"
    check = [str(python), "-c", "import rerun, rerun_notebook, ipykernel"]
    if not python.exists() or subprocess.run(check, capture_output=True).returncode:
        print(f"skipped: {args.venv} has no rerun-sdk, rerun-notebook and ipykernel")
        return
    for hours in args.hours:
        print(json.dumps(measure(hours, args.venv.resolve(), args.settle)), flush=True)


if __name__ == "__main__":
    main()
