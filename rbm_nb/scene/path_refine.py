"""A path drawn finer where the camera has zoomed in (asked for by the page).

A path goes to the browser once, simplified for the whole of it
(:mod:`rbm_nb.scene.decimate`, 1/2000 of its extent by default). Zoomed into
part of a long path, that line is visibly off the recording. When the camera
settles, the page works out the box (in the path's own coordinates) of what
it sees of the line and the size of half a pixel there, and asks the kernel
for the line through that box at that tolerance; it draws the answer in
place of the coarse line inside the box and drops it when the view zooms out
(``js/src/path_refine.js``).

The page owns nothing here: a request names a path the kernel drew, a box
and a tolerance, all checked. The tolerance is rounded down to a power of
two (its *level*), clamped to [:data:`FINEST_SHARE` of the path's extent, the
coarse line's own tolerance]; the box is snapped outward to a grid of
:data:`SNAP_CELLS` tolerances and clipped to the path's bounding box, so a
box of any size costs at most one pass over the path and nearby views share
one answer. An answer has at most :data:`MAX_POINTS` points (the reply says
the error it reached if the budget ran out) and is cached by (path, level,
box). Requests are answered off the kernel's message loop, and a newer one
from the same view cancels the older (:class:`LatestOnly`).

Positions go as float32 in the path's coordinates (within 0.06 mm at 1 km,
as the streamed poses).
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Callable

import numpy as np

from ..widgets._latest_only import LatestOnly
from .decimate import PATH_TOLERANCE
from .handles import PathHandle, segment_points

#: points in one answer, at most (240 kB of float32 segment ends)
MAX_POINTS = 10_000
#: the finest tolerance served, as a share of the path's bounding-box diagonal
FINEST_SHARE = 2.0**-20
#: a box's corners snap outward to multiples of this many tolerances
SNAP_CELLS = 256
#: answers kept, over all paths
CACHED_ANSWERS = 32


def _vector(value) -> np.ndarray | None:
    """Three finite floats, or None."""
    if not isinstance(value, (list, tuple)) or len(value) != 3:
        return None
    out = []
    for v in value:
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            return None
        out.append(float(v))
    arr = np.asarray(out)
    return arr if np.isfinite(arr).all() else None


class _Path:
    """What the kernel knows of one drawn path: samples, extent, coarse tolerance."""

    def __init__(self, handle: PathHandle):
        self.handle = handle
        extent = handle.extent()
        self.low: np.ndarray = np.zeros(3) if extent is None else extent[0]
        self.high: np.ndarray = np.zeros(3) if extent is None else extent[1]
        self.diagonal = float(np.linalg.norm(self.high - self.low))
        _, self.error = handle.stretches()
        tolerance = handle.style.get("tolerance")
        self.tolerance = (
            float(tolerance)
            if tolerance is not None
            else PATH_TOLERANCE * self.diagonal
        )

    def describe(self) -> dict:
        return {
            "id": self.handle.name,
            "node": self.handle.geom_path,
            "tolerance": self.tolerance,
            "error": self.error,
            "diagonal": self.diagonal,
        }


def checked_request(content: dict, path: _Path) -> dict | str:
    """The box and tolerance level to answer, or why the request is refused."""
    low, high = _vector(content.get("lo")), _vector(content.get("hi"))
    if low is None or high is None:
        return "lo and hi must be lists of three finite numbers"
    if (low > high).any():
        return "lo must not exceed hi"
    tolerance = content.get("tolerance")
    if (
        isinstance(tolerance, bool)
        or not isinstance(tolerance, (int, float))
        or not math.isfinite(tolerance)
        or tolerance <= 0
    ):
        return "tolerance must be a positive number of metres"
    if path.diagonal <= 0 or path.tolerance <= 0:
        return "the path has no extent to refine"
    finest = FINEST_SHARE * path.diagonal
    level = math.floor(math.log2(min(max(tolerance, finest), path.tolerance)))
    used = 2.0**level
    cell = SNAP_CELLS * used
    low = np.floor(np.maximum(low, path.low - cell) / cell) * cell
    high = np.ceil(np.minimum(high, path.high + cell) / cell) * cell
    return {"level": level, "tolerance": used, "lo": low, "hi": high}


class PathRefiner:
    """Answers a scene view's requests for its paths, finer where it is zoomed in.

    Parameters
    ----------
    widget : ipywidgets.Widget
        The scene's widget: its custom messages are heard and answered.
    handles : callable
        ``handles()`` -> the scene's objects by name (the paths among them
        are served).
    """

    def __init__(self, widget, handles: Callable[[], dict]):
        self._widget = widget
        self._handles = handles
        self._cache: OrderedDict[tuple, tuple[list[np.ndarray], float]] = OrderedDict()
        self._paths: dict[str, _Path] = {}
        self._worker = LatestOnly("rbm-scene-path-refine")
        #: requests answered (from the cache or computed) and refused
        self.answered = 0
        self.refused = 0
        widget.on_msg(self._on_message)

    # -- the paths drawn ----------------------------------------------------------
    def _current(self) -> dict[str, _Path]:
        """The paths drawn now (the record of one is kept while it is the same)."""
        paths = {}
        for name, handle in self._handles().items():
            if isinstance(handle, PathHandle):
                known = self._paths.get(name)
                paths[name] = (
                    known
                    if known is not None and known.handle is handle
                    else _Path(handle)
                )
        self._paths = paths
        return paths

    # -- messages -----------------------------------------------------------------
    def _on_message(self, _widget, content, _buffers) -> None:
        # any failure is the request's: answered with its reason, never raised
        # into the comm (which would stop answering the page)
        if not isinstance(content, dict):
            return
        kind = content.get("type")
        if kind == "paths":
            paths = [p.describe() for p in self._current().values()]
            self._send(
                {"type": "paths", "view": str(content.get("view", "")), "paths": paths}
            )
        elif kind == "path_refine":
            self._on_refine(content)

    def answer(self, content: dict) -> tuple[dict, list[bytes]]:
        """The reply to one ``path_refine`` request, computed here (no thread).

        Returns the message and its buffer (float32 segment ends, shape
        (m, 2, 3), in the path's coordinates), or a refusal naming why.
        """
        head = {
            "type": "path_refine",
            "view": str(content.get("view", "")),
            "id": content.get("id") if isinstance(content.get("id"), int) else None,
        }
        name = content.get("path")
        path = self._current().get(name) if isinstance(name, str) else None
        if path is None:
            return self._refused(head, f"no path {name!r} in this scene")
        request = checked_request(content, path)
        if isinstance(request, str):
            return self._refused(head, request)
        stretches, error = self._refined(path, request)
        pts = segment_points(stretches)
        head.update(
            path=path.handle.name,
            node=path.handle.geom_path,
            lo=request["lo"].tolist(),
            hi=request["hi"].tolist(),
            level=request["level"],
            tolerance=request["tolerance"],
            error=error,
            points=int(sum(len(p) for p in stretches)),
            stretches=len(stretches),
        )
        self.answered += 1
        return head, [np.ascontiguousarray(pts).tobytes()]

    def _refused(self, head: dict, why: str) -> tuple[dict, list[bytes]]:
        self.refused += 1
        return {**head, "refused": why}, []

    def _refined(self, path: _Path, request: dict):
        key = (
            path.handle.name,
            id(path.handle),
            request["level"],
            tuple(request["lo"].tolist()),
            tuple(request["hi"].tolist()),
        )
        hit = self._cache.get(key)
        if hit is None:
            hit = path.handle.refined(
                request["lo"],
                request["hi"],
                request["tolerance"],
                MAX_POINTS,
            )
            self._cache[key] = hit
            if len(self._cache) > CACHED_ANSWERS:
                self._cache.popitem(last=False)
        else:
            self._cache.move_to_end(key)
        return hit

    def _on_refine(self, content: dict) -> None:
        view = str(content.get("view", ""))

        def job(cancelled):
            return self.answer(content)

        def done(result):
            self._send(*result)

        self._last_request = self._worker.submit(view, job, done)

    def _send(self, content: dict, buffers: list | None = None) -> None:
        if self._widget.comm is not None:
            self._widget.send(content, buffers=buffers or [])

    def close(self) -> None:
        self._worker.close()
