"""A scene as one self-contained HTML file that plays offline.

The file inlines meshcat's viewer bundle (``main.min.js``), our glue
(``viewer.js``) and the data: the static objects as lowered meshcat commands
and every moving node as float32 keyframes (times, positions, quaternions),
turned into three.js animation clips in the browser. No server, no network.
Size is bounded by keeping at most ``max_frames`` samples per moving node.
"""

from __future__ import annotations

import base64
import html
import json
import os
from pathlib import Path

import numpy as np

from .server import VIEWER_DIR, meshcat_js_path

_TEMPLATE = """<!DOCTYPE html>
<html>
<head>
<meta charset="utf-8">
<meta name="generator" content="rbm_nb">
<title>{title}</title>
<style>
  body {{ margin: 0; overflow: hidden; font: 13px sans-serif; }}
  #meshcat-pane {{ width: 100vw; height: 100vh; overflow: hidden; }}
  #rbm-controls {{
    position: fixed; left: 0; right: 0; bottom: 0; display: flex; align-items: center;
    gap: 8px; padding: 6px 10px; background: rgba(0, 0, 0, 0.5); color: #fff;
  }}
  #rbm-controls button {{ width: 44px; }}
  #rbm-slider {{ flex: 1; }}
  #rbm-time {{ min-width: 190px; text-align: right; font-variant-numeric: tabular-nums; }}
</style>
</head>
<body>
<div id="meshcat-pane"></div>
<div id="rbm-controls">
  <button id="rbm-play" type="button" title="Play / pause">&#9654;</button>
  <input id="rbm-slider" type="range" min="0" max="1000" step="any" value="0" aria-label="time">
  <span id="rbm-time"></span>
</div>
<script>
{meshcat_js}
</script>
<script>
{viewer_js}
</script>
<script id="rbm-data" type="application/json">{data}</script>
<script>
  (function () {{
    var data = JSON.parse(document.getElementById("rbm-data").textContent);
    rbmViewer.loadExport(document.getElementById("meshcat-pane"), data, {{
      play: document.getElementById("rbm-play"),
      slider: document.getElementById("rbm-slider"),
      readout: document.getElementById("rbm-time"),
    }});
  }})();
</script>
</body>
</html>
"""


def _b64(array: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(array, dtype="<f4").tobytes()).decode(
        "ascii"
    )


def subsample_indices(n: int, max_frames: int) -> np.ndarray:
    """At most ``max_frames`` evenly strided indices of ``n``, always with the last."""
    stride = max(int(np.ceil(n / max_frames)), 1)
    idx = np.arange(0, n, stride)
    if idx[-1] != n - 1:
        if len(idx) >= max_frames:
            idx[-1] = n - 1
        else:
            idx = np.append(idx, n - 1)
    return idx


def build_payload(scene, max_frames: int, autoplay: bool) -> dict:
    """The data the export page loads: commands, keyframe tracks, camera."""
    from .scene import ROOT

    if scene._camera is None:
        scene.fit_camera()
    commands = [m.data for m in scene._objects.values()]
    commands += [m.data for m in scene._static_transforms.values()]
    commands += [m.data for m in scene._properties.values()]
    nodes = list(scene._dynamic)
    t0 = min((n.track.start for n in nodes), default=0.0)
    t1 = max((n.track.end for n in nodes), default=0.0)
    tracks = []
    for node in nodes:
        track = node.track
        idx = subsample_indices(len(track), max_frames)
        entry = {
            "path": node.path,
            "times": _b64(track.seconds[idx] - t0),
            "position": _b64(track.translation[idx]),
            # three.js quaternions are (x, y, z, w)
            "quaternion": _b64(track.rotation[idx][:, [1, 2, 3, 0]]),
        }
        if track.scale is not None:
            entry["scale"] = _b64(np.repeat(track.scale[idx, np.newaxis], 3, axis=1))
        start = track.start - t0
        if start > 0:
            entry["visible"] = {"times": [0.0, start], "values": [False, True]}
        tracks.append(entry)
    camera = json.loads(scene._camera.data) if scene._camera is not None else None
    return {
        "root": ROOT,
        "commands": [base64.b64encode(c).decode("ascii") for c in commands],
        "tracks": tracks,
        "t0": t0,
        "duration": t1 - t0,
        "datetime": scene.timestamps_kind == "datetime",
        "camera": camera,
        "autoplay": bool(autoplay and tracks),
    }


def render_html(payload: dict, title: str) -> str:
    """The export page for ``payload``."""
    data = json.dumps(payload, separators=(",", ":")).replace("</", "<\\/")
    meshcat_js = meshcat_js_path().read_text(encoding="utf-8")
    viewer_js = (VIEWER_DIR / "viewer.js").read_text(encoding="utf-8")
    for name, code in (("meshcat", meshcat_js), ("viewer", viewer_js)):
        if "</script" in code.lower():
            raise RuntimeError(
                f"the {name} script contains '</script' and cannot be inlined"
            )
    return _TEMPLATE.format(
        title=html.escape(title), meshcat_js=meshcat_js, viewer_js=viewer_js, data=data
    )


def write_atomic(path: Path, text: str, what: str = "to_html") -> None:
    """Write ``text`` to ``path`` so that a failure leaves an existing file untouched.

    Errors name ``what`` was writing and the path.
    """
    from .._atomic import atomic_path

    if path.is_dir():
        raise IsADirectoryError(
            21, f"{what}: {str(path)!r} is a directory, give a file name"
        )
    if not path.parent.is_dir():
        raise FileNotFoundError(
            2,
            f"{what}: cannot write {str(path)!r}: folder {str(path.parent)!r} does not exist",
        )
    try:
        with atomic_path(path) as tmp:
            tmp.write_text(text, encoding="utf-8")
    except OSError as err:
        raise type(err)(
            err.errno, f"{what}: cannot write {str(path)!r}: {err.strerror or err}"
        ) from err


def write_html(
    scene,
    path,
    *,
    max_frames: int = 5000,
    title: str | None = None,
    autoplay: bool = True,
) -> Path:
    """Write ``scene`` to ``path`` as a self-contained animation (see :meth:`Scene.to_html`)."""
    if (
        isinstance(max_frames, bool)
        or not isinstance(max_frames, (int, np.integer))
        or max_frames < 2
    ):
        raise ValueError(
            f"to_html: max_frames must be an integer >= 2, got {max_frames!r}"
        )
    if len(scene) == 0:
        raise ValueError(
            f"to_html: scene {scene.name!r} is empty; add objects before exporting it"
        )
    try:
        path = Path(os.fspath(path)).expanduser()
    except TypeError:
        raise ValueError(
            f"to_html: path must be a file path, got {type(path).__name__}"
        ) from None
    payload = build_payload(scene, int(max_frames), autoplay)
    text = render_html(payload, title or f"rbm_nb scene {scene.name}")
    write_atomic(path, text)
    return path
