"""The dashboard (3D view, plots, player) as one self-contained HTML file.

The page runs the same widget code as the notebook (the bundles in
``rbm_nb/widgets/static`` and meshcat's viewer) on a small offline stand-in
for the kernel (``js/src/export.js``): each widget's state and the content
messages the kernel would send are inlined as JSON with base64 buffers. No
server, no network, no kernel; the player's clock runs in the page. Size is
bounded by keeping at most ``max_frames`` samples per moving object.
"""

from __future__ import annotations

import base64
import html
import json
import os
from pathlib import Path

import numpy as np

from .._infra.atomic import atomic_path
from .tracks import duration as track_duration

_TEMPLATE = """<!DOCTYPE html>
<html>
<head>
<meta charset="utf-8">
<meta name="generator" content="rbm_nb">
<title>{title}</title>
<style>
  body {{ margin: 0; font: 13px sans-serif; background: #fafafa; }}
  h1 {{ font-size: 15px; font-weight: normal; margin: 8px 10px 0; color: #333; }}
  .rbm-export-note {{ margin: 2px 10px 0; color: #666; font-size: 12px; }}
  #rbm-dashboard {{ display: flex; flex-direction: column; gap: 6px; padding: 6px 10px; }}
</style>
</head>
<body>
<h1>{title}</h1>
<p class="rbm-export-note">{note}</p>
<div id="rbm-dashboard"></div>
<script id="rbm-export-data" type="application/json">{data}</script>
<script type="module">
{runtime}
</script>
</body>
</html>
"""


def _b64(data) -> str:
    return base64.b64encode(bytes(data)).decode("ascii")


def _model_spec(
    widget, esm_index: dict, esm: list, overrides: dict | None = None
) -> dict:
    from ipywidgets.widgets.widget import _remove_buffers

    state = widget.get_state()
    text = state.pop("_esm")
    if text not in esm_index:
        esm_index[text] = len(esm)
        esm.append(text)
    state.update(overrides or {})
    state, paths, buffers = _remove_buffers(state)
    return {
        "id": widget.model_id,
        "esm": esm_index[text],
        "state": state,
        "buffers": [
            {"path": list(p), "data": _b64(b)}
            for p, b in zip(paths, buffers, strict=True)
        ],
        "messages": [],
    }


def build_document(
    scene, *, series=(), player=None, max_frames=None, autoplay=False
) -> dict:
    """The JSON document an export page runs (see ``js/src/export.js``)."""
    # lazy (optional dependency): the Player needs anywidget; static exports do not
    from ..widgets.player import Player, bundle

    if player is None:
        # a static scene still gets the page's player, on a single instant
        player = Player(scene) if scene.timestamps_kind is not None else Player([0.0])
    if not isinstance(player, Player):
        raise ValueError(
            f"to_html: player must be a Player, got {type(player).__name__}"
        )
    esm: list[str] = []
    esm_index: dict[str, int] = {}
    widget = scene.widget
    scene_spec = _model_spec(
        widget,
        esm_index,
        esm,
        {
            "player": f"IPY_MODEL_{player.model_id}",
            # the page's player may not be the one the scene follows
            "_player_shift": scene._link.shift_to(player),
            "height": 520,
        },
    )
    content, buffers = scene._snapshot_message(max_samples=max_frames)
    scene_spec["messages"].append(
        {"content": content, "buffers": [_b64(b) for b in buffers]}
    )
    specs = [scene_spec]
    layout = [widget.model_id]
    for view in series:
        overrides = {}
        if hasattr(view, "has_trait") and view.has_trait("player"):
            overrides["player"] = f"IPY_MODEL_{player.model_id}"
        if not hasattr(view, "_esm"):
            raise ValueError(
                f"to_html: series must be anywidgets (with _esm), got {type(view).__name__}"
            )
        specs.append(_model_spec(view, esm_index, esm, overrides))
        layout.append(view.model_id)
    # the page opens where the player stands (a dashboard may start at an
    # instant with data), paused
    start = float(player.time) if player.time is not None else 0.0
    specs.append(_model_spec(player, esm_index, esm, {"time": start, "playing": False}))
    layout.append(player.model_id)
    return {
        "esm": esm,
        "models": specs,
        "layout": layout,
        "autoplay": bool(autoplay),
        "runtime": bundle("export"),
        "note": export_note(scene, max_frames),
    }


def _rate(hertz: float) -> str:
    return f"{hertz:.3g} Hz" if hertz < 100 else f"{hertz:.0f} Hz"


def _duration(seconds: float) -> str:
    if seconds >= 3600:
        return f"{seconds / 3600:.3g} h"
    if seconds >= 60:
        return f"{seconds / 60:.3g} min"
    return f"{seconds:.3g} s"


def export_note(scene, max_frames: int | None) -> str:
    """What the page shows of the recording, in words (it is written on the page).

    Poses: at most ``max_frames`` samples per moving object, evenly spaced,
    so a pose every ``duration / max_frames`` seconds (the export rate) where
    the recording has more; paths: the points drawn and the largest distance
    of a sample from the line (see :func:`~rbm_nb.scene.decimate.simplify_path`).
    """
    parts = []
    tracks = list(scene.state.tracks.values())
    if tracks:
        recorded = []
        shown = []
        span = 0.0
        for track in tracks:
            duration = track_duration(track)
            span = max(span, duration)
            if duration <= 0:
                continue
            n = len(track)
            kept = n if max_frames is None else min(n, max_frames)
            recorded.append((n - 1) / duration)
            shown.append((kept - 1) / duration)
        if recorded:
            low, high = min(shown), max(shown)
            rate = (
                _rate(high) if high / low < 1.05 else f"{_rate(low)} to {_rate(high)}"
            )
            if max(r / s for r, s in zip(recorded, shown, strict=True)) <= 1.0001:
                parts.append(f"poses: every sample over {_duration(span)}")
            else:
                parts.append(
                    f"poses at {rate} over {_duration(span)} (recorded at up to "
                    f"{_rate(max(recorded))}; at most {max_frames:,} per moving object)"
                )
    for handle in scene.handles.values():
        if handle.kind == "path":
            stretches, error = handle.stretches()
            points = sum(len(s) for s in stretches)
            parts.append(
                f"{handle.name.replace('_', ' ')}: {points:,} of "
                f"{len(handle.samples):,} samples drawn, within {_length(error)}"
            )
    return "; ".join(parts)


def _length(metres: float) -> str:
    if metres >= 1:
        return f"{metres:.3g} m"
    if metres >= 0.01:
        return f"{metres * 100:.3g} cm"
    return f"{metres * 1000:.3g} mm"


# inside a <script> element, "</script", "<!--" and "<script" change how the
# HTML parser reads the rest of the page; JSON allows these escapes in strings
# (and the characters occur nowhere else in JSON). U+2028/2029 are escaped by
# json.dumps already (ensure_ascii).
_SCRIPT_SAFE = str.maketrans({"<": "\\u003c", ">": "\\u003e", "&": "\\u0026"})


def embeddable_json(value) -> str:
    """``value`` as JSON that can sit inside a ``<script>`` element of any page.

    Whatever the strings hold (frame ids from a rosbag, labels, units),
    nothing in the result can end the element or open a comment or script.
    """
    text = json.dumps(value, separators=(",", ":"), ensure_ascii=True)
    return text.translate(_SCRIPT_SAFE)


def render_html(document: dict, title: str) -> str:
    runtime = document.pop("runtime")
    note = document.pop("note", "")
    data = embeddable_json(document)
    return _TEMPLATE.format(
        title=html.escape(title), note=html.escape(note), data=data, runtime=runtime
    )


def write_atomic(path: Path, text: str, what: str = "to_html") -> None:
    """Write ``text`` to ``path`` so that a failure leaves an existing file untouched.

    Errors name ``what`` was writing and the path.
    """
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
    series=None,
    player=None,
    max_frames: int | None = 20000,
    title: str | None = None,
    autoplay: bool = False,
) -> Path:
    """Write ``scene`` (and ``series``) to ``path`` as a self-contained page (see :meth:`Scene.to_html`)."""
    if max_frames is not None and (
        isinstance(max_frames, bool)
        or not isinstance(max_frames, (int, np.integer))
        or max_frames < 2
    ):
        raise ValueError(
            f"to_html: max_frames must be an integer >= 2 or None, got {max_frames!r}"
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
    if series is None:
        series = []
    elif not isinstance(series, (list, tuple)):
        series = [series]
    document = build_document(
        scene,
        series=series,
        player=player,
        max_frames=None if max_frames is None else int(max_frames),
        autoplay=autoplay,
    )
    text = render_html(document, title or f"rbm_nb scene {scene.name}")
    write_atomic(path, text)
    return path
