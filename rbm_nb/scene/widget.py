"""The 3D view as an anywidget: meshcat's own viewer, fed over the kernel comm.

The widget's JavaScript is meshcat's viewer bundle (shipped in the meshcat
package) followed by ``rbm_nb/widgets/static/scene.js``. Content goes as
custom comm messages whose buffers are meshcat's msgpack commands and the
float tracks of everything that moves (see :mod:`rbm_nb.scene.state`); the
browser asks for it with a ``ready`` message when a model is created, so
nothing is lost before the page listens and a reloaded page gets it again.
No port is opened: this works wherever Jupyter widgets work.
"""

from __future__ import annotations

import functools
import json
import math
import struct
import threading
import time
import uuid
from collections.abc import Callable

import anywidget
import traitlets
from ipywidgets import widget_serialization

from ..widgets._frontend import FrontendGuard
from ..widgets.player import Player, bundle
from .commands import meshcat_js_path


@functools.lru_cache(maxsize=1)
def scene_esm() -> str:
    """meshcat's viewer (defining ``globalThis.MeshCat`` once) + rbm_nb's scene module."""
    meshcat = meshcat_js_path().read_text(encoding="utf-8")
    # meshcat's bundle is UMD: with no module system in sight it sets
    # self.MeshCat. Hide any AMD/CommonJS globals a page may have.
    loader = (
        "if (!globalThis.MeshCat) {\n"
        "(function (define, exports, module) {\n"
        f"{meshcat}\n"
        "}).call(globalThis, undefined, undefined, undefined);\n"
        "}\n"
    )
    return loader + bundle("scene")


#: seconds between two snapshots sent in answer to pages' "ready" messages
READY_INTERVAL = 1.0

#: bounds of the view's height in pixels
HEIGHT = (50, 5000)


class SceneWidget(FrontendGuard, anywidget.AnyWidget):
    """The DOM widget of a :class:`~rbm_nb.scene.Scene` (``scene.widget``).

    It composes in ``HBox``/``VBox``/``GridBox`` like any ipywidget.

    Attributes
    ----------
    player : Player or None
        The player whose time the view shows (in the browser).
    time : float or None
        Seconds from the scene's origin shown when no player is linked.
    selected : str or None
        Name of the selected frame: set by clicking a frame in 3D, by Python,
        or by a FrameTree.
    follow : str or None
        Name of a frame the camera follows.
    labels : bool
        Show frame labels.
    height : int
        Height in pixels.
    """

    # a click selects a frame or follows it; the content, camera, time and
    # height are the kernel's
    _frontend_settable = frozenset({"selected", "follow"})

    _esm = traitlets.Unicode("").tag(sync=True)
    _uid = traitlets.Unicode("").tag(sync=True)
    player = traitlets.Instance(Player, allow_none=True).tag(
        sync=True, **widget_serialization
    )
    time = traitlets.Float(None, allow_none=True).tag(sync=True)
    selected = traitlets.Unicode(None, allow_none=True).tag(sync=True)
    follow = traitlets.Unicode(None, allow_none=True).tag(sync=True)
    labels = traitlets.Bool(True).tag(sync=True)
    height = traitlets.Int(480).tag(sync=True)
    _origin = traitlets.Float(0.0).tag(sync=True)
    # seconds from the scene's second 0 to its player's, counted exactly from
    # their int64 ns keys in the kernel (None: no player); the view shows
    # ``_player_shift + player.time`` (float epoch seconds subtracted in the
    # browser were ~0.24 µs coarse)
    _player_shift = traitlets.Float(None, allow_none=True).tag(sync=True)
    _camera = traitlets.Dict().tag(sync=True)
    _frames = traitlets.Dict().tag(sync=True)
    _labels = traitlets.Dict().tag(sync=True)
    _legend: traitlets.List[dict] = traitlets.List().tag(sync=True)
    _pins = traitlets.Dict().tag(sync=True)
    # The content as of the last change, packed (see pack_snapshot): saved with
    # the notebook's widget state, so a page with no kernel (nbconvert HTML,
    # the docs) draws the scene; a kernel's answer to "ready" replaces it.
    _saved = traitlets.Bytes(b"").tag(sync=True)
    SAVED_SAMPLES = 5000  # per moving object: keeps saved notebooks small
    SAVED_EVERY = 2.0  # seconds between refreshes while a browser is listening

    def __init__(
        self,
        snapshot: Callable[..., tuple[dict, list]],
        *,
        chunk: Callable[[dict], list[tuple[dict, list]]] | None = None,
        check_frame: Callable[[str, str], str] | None = None,
        **kwargs,
    ):
        # check_frame(name, trait) -> the name, or ValueError: what the scene
        # accepts as `selected` and `follow`, from Python and from the browser
        self._check_frame = check_frame
        super().__init__(_esm=scene_esm(), _uid=uuid.uuid4().hex, **kwargs)
        self._snapshot = snapshot
        # chunk(request) -> answers: the poses of a long recording, asked for
        # by the page around its playhead (see rbm_nb.scene.stream)
        self._chunk = chunk
        self.chunks_sent = 0
        self.ready = False
        self._ready_lock = threading.Lock()
        self._ready_timer: threading.Timer | None = None
        self._last_snapshot = -math.inf
        self.bytes_sent = 0
        self._saved_at = -float("inf")
        self._saved_timer: threading.Timer | None = None
        self.on_msg(self._on_message)
        self._save()

    @traitlets.validate("height")
    def _valid_height(self, proposal):
        value = int(proposal["value"])
        low, high = HEIGHT
        if not low <= value <= high:
            raise traitlets.TraitError(
                f"height must be in [{low}, {high}] pixels, got {value}"
            )
        return value

    @traitlets.validate("time")
    def _valid_time(self, proposal):
        value = proposal["value"]
        if value is not None and not math.isfinite(value):
            raise traitlets.TraitError(f"time must be finite or None, got {value}")
        return value

    @traitlets.validate("selected", "follow")
    def _valid_frame(self, proposal):
        name = proposal["value"]
        if name is None or self._check_frame is None:
            return name
        try:
            return self._check_frame(name, proposal["trait"].name)
        except ValueError as err:
            raise traitlets.TraitError(str(err)) from None

    def _on_message(self, _widget, content, _buffers) -> None:
        if not isinstance(content, dict):
            return
        if content.get("type") == "ready":
            self._on_ready()
        elif content.get("type") == "chunks" and self._chunk is not None:
            for head, buffers in self._chunk(content):
                self._send_chunk(head, buffers)

    def _on_ready(self) -> None:
        """Answer a page's ``ready`` with the whole scene, at most once per interval.

        Every page showing this model receives a snapshot sent for any of
        them, so readies arriving within :data:`READY_INTERVAL` of the last
        snapshot are answered together by one more snapshot when the interval
        ends: a page that asks always gets the scene, and a flood of readies
        costs two snapshots per interval, not one each.
        """
        with self._ready_lock:
            self.ready = True
            wait = self._last_snapshot + READY_INTERVAL - time.monotonic()
            if wait > 0:
                if self._ready_timer is None:
                    self._ready_timer = threading.Timer(wait, self._send_snapshot)
                    self._ready_timer.daemon = True
                    self._ready_timer.start()
                return
        self._send_snapshot()

    def _send_snapshot(self) -> None:
        with self._ready_lock:
            self._ready_timer = None
            self._last_snapshot = time.monotonic()
        self.send_content()

    def send_content(self) -> None:
        """Send the whole content; for a streamed scene, the chunks at the
        playhead right after it (no round trip before the first frame)."""
        content, buffers = self._snapshot()
        self.push(content, buffers)
        plan = content.get("stream")
        if plan and self._chunk is not None:
            request = {"type": "chunks", "indices": plan["first"]}
            for head, chunk_buffers in self._chunk(request):
                self._send_chunk(head, chunk_buffers)

    def _send_chunk(self, content: dict, buffers: list) -> None:
        """Send one chunk of poses: not content, so the saved state stays as it is."""
        if not self.ready or self.comm is None:
            return
        self.bytes_sent += sum(len(b) for b in buffers)
        self.chunks_sent += 1
        self.send(content, buffers=buffers)

    def push(self, content: dict, buffers: list) -> None:
        """Send one content message (only once a browser asked for the scene)."""
        self._refresh_saved()
        if not self.ready or self.comm is None:
            return
        self.bytes_sent += sum(len(b) for b in buffers)
        self.send(content, buffers=buffers)

    # -- the snapshot saved with the widget state --------------------------------
    def _save(self) -> None:
        self._saved_at = time.monotonic()
        self._saved = pack_snapshot(*self._snapshot(self.SAVED_SAMPLES))

    def _refresh_saved(self) -> None:
        """Keep ``_saved`` current; at most every SAVED_EVERY s while a browser listens.

        Without a browser (nbclient, a docs build) every change refreshes it at
        once, so the state saved after the last cell is complete. With one,
        each refresh re-sends the whole scene, so changes are gathered.
        """
        wait = self._saved_at + self.SAVED_EVERY - time.monotonic()
        if not self.ready or wait <= 0:
            self._save()
        elif self._saved_timer is None or not self._saved_timer.is_alive():
            self._saved_timer = threading.Timer(wait, self._save)
            self._saved_timer.daemon = True
            self._saved_timer.start()


def pack_snapshot(content: dict, buffers: list) -> bytes:
    """One snapshot message as bytes: u32 header length, JSON header, then
    each buffer as u32 length + bytes (little endian; read by scene.js)."""
    header = json.dumps(content, separators=(",", ":")).encode()
    parts = [struct.pack("<I", len(header)), header]
    for buffer in buffers:
        data = bytes(buffer)
        parts += [struct.pack("<I", len(data)), data]
    return b"".join(parts)
