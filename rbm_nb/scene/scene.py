"""A meshcat scene of reference frames, played back in time.

:class:`Scene` is the facade: ``add_frame``, ``add_path``, ``add_points``,
``add_vectors`` and ``add_mesh`` return handles; ``set_time`` / ``publish``
move everything that moves; ``player()`` returns a linked
:class:`~rbm_nb.widgets.Player`; ``show()`` displays the live viewer and
``to_html()`` writes a self-contained animation.

Poses are looked up once per object for the whole recording (see
:mod:`rbm_nb.scene.tracks`); a step only does one binary search and one
msgpack encoding per moving node.
"""

from __future__ import annotations

import itertools
import re
import threading
import uuid

import numpy as np

from ..widgets._time import (
    DATETIME,
    check_kinds,
    seconds_to_datetime64,
    time_as_seconds,
)
from . import commands
from .commands import TransformPacker
from .handles import (
    FrameHandle,
    MeshHandle,
    PathHandle,
    PointsHandle,
    SceneHandle,
    VectorsHandle,
    _points_array,
)
from .server import Message
from .tracks import Track

ROOT = "/rbm"
_counter = itertools.count(1)


def _resolve(frame, argument: str):
    from .. import frames

    return frames._resolve(frame, argument)


def _slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.\-]+", "_", str(text)).strip("_") or "object"


class _Node:
    """A group in the meshcat tree whose pose follows a track."""

    __slots__ = ("path", "track", "packer", "index", "shown")

    def __init__(self, path: str, track: Track):
        self.path = path
        self.track = track
        self.packer = TransformPacker(path)
        self.index: int | None = None
        self.shown = True

    def messages_at_time(self, t: float) -> list[Message]:
        return self.messages_at_index(self.track.index_at(t))

    def messages_at_index(self, index: int) -> list[Message]:
        out = []
        if index < 0:  # nothing recorded yet: hide instead of guessing
            if self.shown:
                self.shown = False
                out.append(commands.set_property(self.path, "visible", False))
            self.index = -1
            return out
        if not self.shown:
            self.shown = True
            out.append(commands.set_property(self.path, "visible", True))
        if index != self.index:
            self.index = index
            out.append(self.packer.message(self.track.matrix(index)))
        return out

    def current_messages(self) -> list[Message]:
        """What a freshly attached viewer needs to show this node as it is."""
        out = []
        index = self.index if self.index is not None else 0
        if index >= 0:
            out.append(self.packer.message(self.track.matrix(index)))
        if not self.shown:
            out.append(commands.set_property(self.path, "visible", False))
        return out


class Scene:
    """A 3-D scene of frames, paths, points, vectors and meshes (meshcat).

    Parameters
    ----------
    base : str or ReferenceFrame, default "world"
        The fixed frame of the scene: everything is drawn in its coordinates.
    name : str, optional
        Channel name on the viewer server (letters, digits, ``-``, ``_``).

    Examples
    --------
    >>> import rbm_nb as rbm
    >>> rbm.clear_registry()
    >>> rbm.register_frame("world")
    >>> scene = rbm.scene.Scene("world")
    >>> handle = scene.add_frame("world", scale=0.5)
    >>> handle.update(scale=1.0).style["scale"]
    1.0
    >>> scene.close()
    """

    def __init__(self, base="world", *, name: str | None = None):
        self.base = _resolve(base, "Scene: base")
        if name is None:
            name = f"scene-{next(_counter)}-{uuid.uuid4().hex[:6]}"
        if not re.fullmatch(r"[A-Za-z0-9_\-]+", name):
            raise ValueError(
                f"Scene: name must be letters, digits, '-' or '_', got {name!r}"
            )
        self.name = name
        self._lock = threading.RLock()
        self._server = None
        self._closed = False
        self._handles: dict[str, SceneHandle] = {}
        self._anchors: dict[str, list] = {}  # key -> [node or None, users, base frame]
        self._nodes: dict[str, _Node] = {}
        self._dynamic: list[_Node] = []
        self._objects: dict[str, Message] = {}
        self._properties: dict[tuple, Message] = {}
        self._static_transforms: dict[str, Message] = {}
        self._camera: Message | None = None
        self._camera_is_auto = True
        self._time: float | None = None
        self.timestamps_kind: str | None = None
        self._timestamps_cache = None
        self._highlight: tuple | None = None
        self._listeners: list = []

    # -- adding objects ---------------------------------------------------------
    def add_frame(
        self, frame, *, base=None, scale: float = 0.5, label: str | None = None
    ) -> FrameHandle:
        """Draw a frame as a triad (x red, y green, z blue) that follows it.

        Parameters
        ----------
        frame : str or ReferenceFrame
        base : str or ReferenceFrame, optional
            Frame the pose is looked up in; the scene's base by default.
        scale : float, default 0.5
            Length of the axes in metres.
        label : str, optional
            Name of the object in the scene (``"frame <name>"`` by default).
        """
        frame = _resolve(frame, "add_frame: frame")
        base = self._resolve_base(base, "add_frame")
        handle = FrameHandle(
            self,
            self._new_name(label or f"frame {frame.name}"),
            frame,
            base,
            {"scale": scale},
        )
        handle._validate_style(handle._style)
        self._install(handle, Track.lookup(frame, base))
        return handle

    def add_path(
        self,
        frame,
        *,
        base=None,
        color="#ffffff",
        max_points: int = 1000,
        label: str | None = None,
    ) -> PathHandle:
        """Draw the trajectory of a moving frame in ``base`` as a line.

        Parameters
        ----------
        frame : str or ReferenceFrame
            A moving frame (or one that moves wrt ``base``).
        base : str or ReferenceFrame, optional
            The frame the path is expressed in; the scene's base by default.
        color : str or int, default "#ffffff"
        max_points : int, default 1000
            The path is subsampled to at most this many points.
        """
        frame = _resolve(frame, "add_path: frame")
        base = self._resolve_base(base, "add_path")
        track = Track.lookup(frame, base)
        if track.static:
            raise ValueError(
                f"add_path: frame {frame.name!r} does not move wrt {base.name!r}, it has no path"
            )
        style = {"color": color, "max_points": max_points}
        handle = PathHandle(
            self,
            self._new_name(label or f"path {frame.name}"),
            frame,
            base,
            style,
            track.positions(),
        )
        handle._validate_style(handle._style)
        identity = Track(np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0]), name="path")
        self._install(handle, identity)
        return handle

    def add_points(
        self,
        points,
        *,
        frame=None,
        timestamps=None,
        color="#ffff00",
        size: float = 0.05,
        label: str | None = None,
    ) -> PointsHandle:
        """Draw points given in ``frame`` (the scene's base by default).

        Parameters
        ----------
        points : array_like, shape (3,) or (n, 3)
            A static point cloud; with ``timestamps``, the positions of one
            point over time (drawn as a sphere of radius ``size``).
        frame : str or ReferenceFrame, optional
        timestamps : array_like, shape (n,), optional
        color : str or int, default "#ffff00"
        size : float, default 0.05
            Point size (cloud) or sphere radius (moving point), in metres.
        """
        frame = _resolve(frame if frame is not None else self.base, "add_points: frame")
        pts = _points_array(points, "points", "add_points")
        inner = None
        if timestamps is not None:
            identity = np.zeros((len(pts), 4))
            identity[:, 0] = 1.0
            inner = Track(pts, identity, timestamps, name="add_points: points")
        style = {"color": color, "size": size}
        name = self._new_name(label or f"points {frame.name}")
        handle = PointsHandle(
            self, name, frame, self.base, style, pts, moving=inner is not None
        )
        handle._validate_style(handle._style)
        self._install(handle, Track.lookup(frame, self.base), inner)
        return handle

    def add_vectors(
        self,
        frame,
        vectors=(1.0, 0.0, 0.0),
        *,
        origins=None,
        timestamps=None,
        base=None,
        color="#ffff00",
        length: float = 1.0,
        label: str | None = None,
    ) -> VectorsHandle:
        """Draw vectors given in ``frame`` and moving with it (e.g. gaze rays).

        Parameters
        ----------
        frame : str or ReferenceFrame
            The frame the vectors are expressed in.
        vectors : array_like, shape (3,) or (n, 3), default (1, 0, 0)
            Fixed vectors; with ``timestamps``, one vector over time.
        origins : array_like, shape (3,) or (n, 3), optional
            Start points in ``frame`` (its origin by default; one origin with
            ``timestamps``).
        timestamps : array_like, shape (n,), optional
        base : str or ReferenceFrame, optional
            Frame the pose of ``frame`` is looked up in; the scene's base by default.
        color : str or int, default "#ffff00"
        length : float, default 1.0
            Factor applied to the vectors (metres per unit).
        """
        frame = _resolve(frame, "add_vectors: frame")
        base = self._resolve_base(base, "add_vectors")
        vecs = _points_array(vectors, "vectors", "add_vectors")
        inner = None
        if timestamps is not None:
            origin = _points_array(
                origins if origins is not None else np.zeros(3),
                "origins",
                "add_vectors",
            )
            if len(origin) != 1:
                raise ValueError(
                    "add_vectors: with timestamps, give one origin of shape (3,)"
                )
            norms = np.linalg.norm(vecs, axis=1)
            rotation = _rotations_from_x(vecs, norms)
            inner = Track(
                np.repeat(origin, len(vecs), axis=0),
                rotation,
                timestamps,
                scale=np.maximum(norms, 1e-12),
                name="add_vectors: vectors",
            )
            origins_arr = origin
        else:
            origins_arr = _points_array(
                origins if origins is not None else np.zeros(3),
                "origins",
                "add_vectors",
            )
            if len(origins_arr) == 1:
                origins_arr = np.repeat(origins_arr, len(vecs), axis=0)
            if origins_arr.shape != vecs.shape:
                raise ValueError(
                    f"add_vectors: origins must have shape (3,) or {vecs.shape}, got {origins_arr.shape}"
                )
        style = {"color": color, "length": length}
        name = self._new_name(label or f"vectors {frame.name}")
        handle = VectorsHandle(
            self, name, frame, base, style, vecs, origins_arr, moving=inner is not None
        )
        handle._validate_style(handle._style)
        self._install(handle, Track.lookup(frame, base), inner)
        return handle

    def add_mesh(
        self,
        frame,
        mesh="box",
        *,
        base=None,
        size=0.1,
        scale: float = 1.0,
        color="#cccccc",
        opacity: float = 1.0,
        offset=None,
        rotation=None,
        label: str | None = None,
    ) -> MeshHandle:
        """Attach a mesh to ``frame``.

        Parameters
        ----------
        frame : str or ReferenceFrame
        mesh : str, path or meshcat Geometry, default "box"
            ``"box"``, ``"sphere"``, ``"cylinder"``, ``"ellipsoid"``, a
            ``.obj`` / ``.stl`` / ``.dae`` file or a meshcat geometry.
        size : float or tuple
            Box edge lengths (x, y, z), sphere radius, cylinder (height,
            radius) or ellipsoid radii, in metres.
        scale : float, default 1.0
        color : str or int, default "#cccccc"
        opacity : float, default 1.0
        offset : array_like, shape (3,), optional
            Position of the mesh in ``frame``.
        rotation : array_like, shape (4,), optional
            Orientation of the mesh in ``frame`` (w, x, y, z).
        """
        frame = _resolve(frame, "add_mesh: frame")
        base = self._resolve_base(base, "add_mesh")
        offset_t = _points_array(
            offset if offset is not None else np.zeros(3), "offset", "add_mesh"
        )[0]
        offset_r = np.asarray(
            rotation if rotation is not None else (1.0, 0.0, 0.0, 0.0), dtype=float
        )
        if (
            offset_r.shape != (4,)
            or not np.isfinite(offset_r).all()
            or np.linalg.norm(offset_r) == 0
        ):
            raise ValueError(
                f"add_mesh: rotation must be a non-zero quaternion (4,), got {rotation!r}"
            )
        style = {"color": color, "opacity": opacity, "scale": scale}
        name = self._new_name(label or f"mesh {frame.name}")
        handle = MeshHandle(
            self,
            name,
            frame,
            base,
            style,
            mesh,
            np.atleast_1d(np.asarray(size, dtype=float)),
        )
        handle._validate_style(handle._style)
        self._install(
            handle,
            Track.lookup(frame, base),
            offset=commands.pose_matrix(offset_t, offset_r),
        )
        return handle

    @property
    def handles(self) -> dict:
        """The scene's objects by name."""
        return dict(self._handles)

    def __getitem__(self, name: str) -> SceneHandle:
        try:
            return self._handles[name]
        except KeyError:
            raise KeyError(
                f"no object {name!r} in this scene; objects: {sorted(self._handles)}"
            ) from None

    def __len__(self) -> int:
        return len(self._handles)

    # -- time -------------------------------------------------------------------
    def set_time(self, t) -> None:
        """Move every moving object to its latest sample at or before ``t``.

        Objects whose data starts after ``t`` are hidden until it starts.

        Parameters
        ----------
        t : float or datetime64
            Float seconds (since the epoch for datetime recordings) or a
            datetime64.
        """
        self._check_open()
        seconds = time_as_seconds(t, self.timestamps_kind)
        with self._lock:
            self._time = seconds
            messages = []
            for node in self._dynamic:
                messages.extend(node.messages_at_time(seconds))
            self._emit(messages)

    def publish(self, idx: int | None = None) -> None:
        """Show sample ``idx`` of :attr:`timestamps` (the first by default)."""
        self._check_open()
        seconds = self._timeline()
        if seconds is None:
            return
        idx = 0 if idx is None else int(idx)
        if not -len(seconds) <= idx < len(seconds):
            raise IndexError(
                f"Scene.publish: idx {idx} outside [0, {len(seconds) - 1}]"
            )
        self.set_time(float(seconds[idx]))

    @property
    def time(self) -> float | None:
        """The time last shown (float seconds), None before the first step."""
        return self._time

    @property
    def timestamps(self):
        """Time axis for playback: None for a scene where nothing moves.

        When all moving objects share their timestamps these are returned
        as they are; otherwise a regular grid spanning all of them at the
        finest mean sampling interval.
        """
        seconds = self._timeline()
        if seconds is None:
            return None
        original = self._timestamps_cache[1]
        if original is not None:
            return original
        if self.timestamps_kind == DATETIME:
            return seconds_to_datetime64(seconds)
        return seconds

    def _timeline(self) -> np.ndarray | None:
        with self._lock:
            if self._timestamps_cache is not None:
                return self._timestamps_cache[0]
            tracks = [node.track for node in self._dynamic]
            if not tracks:
                return None
            first = tracks[0].seconds
            original = None
            if all(
                t.seconds is first or np.array_equal(t.seconds, first) for t in tracks
            ):
                seconds = first
                original = tracks[0].original_timestamps
            else:
                start = min(t.start for t in tracks)
                end = max(t.end for t in tracks)
                steps = [
                    (t.end - t.start) / (len(t) - 1)
                    for t in tracks
                    if len(t) > 1 and t.end > t.start
                ]
                if not steps or end <= start:
                    seconds = np.unique(np.concatenate([t.seconds for t in tracks]))
                else:
                    n = int(np.ceil((end - start) / min(steps) - 1e-9)) + 1
                    seconds = np.linspace(start, end, n)
            self._timestamps_cache = (seconds, original)
            return seconds

    def player(
        self, step: int = 1, speed: float = 1.0, skip: int | None = None, **kwargs
    ):
        """A :class:`~rbm_nb.widgets.Player` over :attr:`timestamps`, linked to this scene."""
        self._check_open()
        if self._timeline() is None:
            raise ValueError(
                f"Scene {self.name!r} has no moving objects, there is nothing to play; "
                "add a moving frame first"
            )
        from ..widgets.player import Player

        player = Player(self, step=step, speed=speed, skip=skip, **kwargs)
        player.link(self)
        return player

    # -- viewer -----------------------------------------------------------------
    @property
    def server(self):
        """The viewer server this scene is shown on (started on first use)."""
        self._check_open()
        with self._lock:
            if self._server is None or self._server.closed:
                from .server import get_server

                server = get_server()
                server.add_channel(self.name)
                self._server = server
                if self._camera is None:
                    self._camera = commands.camera(*self._fitted_camera())
                    self._camera_is_auto = True
                server.send(self.name, self._snapshot())
            return self._server

    @property
    def url(self) -> str:
        """Direct URL of the live viewer page (loopback)."""
        return self.server.channel_url(self.name)

    def proxy_path(self, base_url: str = "/") -> str:
        """Path of the viewer page through jupyter-server-proxy under ``base_url``."""
        return f"{base_url.rstrip('/')}/proxy/{self.server.port}/{self.name}/"

    def show(self, *, height: int = 480, proxy: bool | None = None) -> None:
        """Display the live viewer in the notebook.

        Parameters
        ----------
        height : int, default 480
            Height of the view in pixels.
        proxy : bool, optional
            Load the viewer through jupyter-server-proxy (``<base_url>proxy/<port>/``).
            By default it is used unless the notebook itself is opened on the
            loopback over http (``$RBM_NB_VIEWER_PROXY`` = ``always`` / ``never``
            overrides that).
        """
        from IPython.display import HTML, display

        display(HTML(self._viewer_html(height=height, proxy=proxy)))

    def _repr_html_(self) -> str:
        return self._viewer_html()

    def _viewer_html(self, height: int = 480, proxy: bool | None = None) -> str:
        from .display import viewer_html

        if self._camera is None:
            self.fit_camera()
        server = self.server
        return viewer_html(
            server.port, self.name, server.channel_url(self.name), height, proxy
        )

    def fit_camera(self) -> None:
        """Point the camera at everything in the scene."""
        self._set_camera(*self._fitted_camera(), auto=True)

    def _fitted_camera(self) -> tuple[np.ndarray, np.ndarray]:
        points = self._extent_points()
        if len(points) == 0:
            points = np.zeros((1, 3))
        low, high = points.min(axis=0), points.max(axis=0)
        target = (low + high) / 2
        radius = max(float(np.linalg.norm(high - low)) / 2, 1.0)
        direction = np.array([1.0, -1.4, 1.0])
        position = target + direction / np.linalg.norm(direction) * radius * 1.7
        return position, target

    def set_camera(self, position, target) -> None:
        """Place the camera at ``position`` looking at ``target`` (scene base coordinates)."""
        p = _points_array(position, "position", "set_camera")[0]
        t = _points_array(target, "target", "set_camera")[0]
        self._set_camera(p, t, auto=False)

    def _set_camera(self, position, target, auto: bool) -> None:
        self._check_open()
        with self._lock:
            self._camera = commands.camera(position, target)
            self._camera_is_auto = auto
            self._emit([self._camera])

    def highlight(self, frame=None) -> None:
        """Emphasise ``frame`` (enlarged triad); None removes the emphasis."""
        self._check_open()
        with self._lock:
            if self._highlight is not None:
                kind, handle = self._highlight
                self._highlight = None
                if kind == "scaled" and not handle.removed:
                    self._emit(
                        [
                            commands.set_property(
                                handle.geom_path, "scale", [1.0, 1.0, 1.0]
                            )
                        ]
                    )
                elif kind == "added":
                    handle.remove()
            if frame is None:
                return
            frame = _resolve(frame, "highlight: frame")
            for handle in self._handles.values():
                if isinstance(handle, FrameHandle) and handle.frame is frame:
                    message = commands.set_property(
                        handle.geom_path, "scale", [2.0, 2.0, 2.0]
                    )
                    self._emit([message])
                    self._highlight = ("scaled", handle)
                    return
            handle = self.add_frame(frame, scale=1.0, label=f"highlight {frame.name}")
            self._highlight = ("added", handle)

    # -- export -----------------------------------------------------------------
    def to_html(
        self,
        path,
        *,
        max_frames: int = 5000,
        title: str | None = None,
        autoplay: bool = True,
    ):
        """Write one self-contained HTML file that plays the scene offline.

        meshcat's viewer bundle and the animation data are inlined: the file
        needs no server and no network. Each moving object keeps at most
        ``max_frames`` samples (evenly subsampled), which bounds the size.

        Parameters
        ----------
        path : str or os.PathLike
            Output file; written atomically (a temporary file, then renamed).
        max_frames : int, default 5000
        title : str, optional
        autoplay : bool, default True

        Returns
        -------
        pathlib.Path
            The file written.

        Raises
        ------
        ValueError
            If the scene is empty or ``max_frames`` < 2.
        OSError
            If the file cannot be written (the message names the path).
        """
        from .export import write_html

        self._check_open()
        return write_html(
            self, path, max_frames=max_frames, title=title, autoplay=autoplay
        )

    # -- life cycle -------------------------------------------------------------
    @property
    def closed(self) -> bool:
        return self._closed

    def close(self) -> None:
        """Remove the scene from the viewer server; idempotent.

        The kernel's server keeps running for other scenes (see
        :func:`rbm_nb.scene.shutdown_server`).
        """
        if self._closed:
            return
        with self._lock:
            self._closed = True
            server, self._server = self._server, None
            for handle in self._handles.values():
                handle.removed = True
            self._handles.clear()
        if server is not None and not server.closed:
            server.remove_channel(self.name)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __repr__(self) -> str:
        state = "closed" if self._closed else f"{len(self._handles)} objects"
        return f"<Scene {self.name!r} base={self.base.name!r} ({state})>"

    # -- internals --------------------------------------------------------------
    def _check_open(self) -> None:
        if self._closed:
            raise RuntimeError(f"scene {self.name!r} is closed; create a new Scene")

    def _resolve_base(self, base, owner: str):
        self._check_open()
        return self.base if base is None else _resolve(base, f"{owner}: base")

    def _new_name(self, label: str) -> str:
        self._check_open()
        name = _slug(label)
        if name in self._handles:
            for i in itertools.count(2):
                if f"{name}_{i}" not in self._handles:
                    name = f"{name}_{i}"
                    break
        return name

    def _anchor_path(self, base) -> str:
        if base is self.base:
            return f"{ROOT}/root"
        return f"{ROOT}/anchor_{_slug(base.name)}"

    def _acquire_anchor(self, base) -> tuple[str, list[Message]]:
        path = self._anchor_path(base)
        entry = self._anchors.get(path)
        messages: list[Message] = []
        if entry is None:
            node = None
            if base is not self.base:
                track = Track.lookup(base, self.base)
                node, messages = self._add_node(path, track)
            entry = [node, 0, base]
            self._anchors[path] = entry
        entry[1] += 1
        return path, messages

    def _release_anchor(self, path: str) -> list[Message]:
        entry = self._anchors.get(path)
        if entry is None:
            return []
        entry[1] -= 1
        if entry[1] > 0 or entry[0] is None:
            if entry[1] <= 0:
                del self._anchors[path]
            return []
        del self._anchors[path]
        self._drop_prefix(path)
        return [commands.delete(path)]

    def _add_node(self, path: str, track: Track) -> tuple[_Node | None, list[Message]]:
        if track.static:
            message = TransformPacker(path).message(track.matrix())
            self._static_transforms[path] = message
            return None, [message]
        check_kinds(self.timestamps_kind, track.kind, f"scene {self.name!r}")
        self.timestamps_kind = track.kind
        node = _Node(path, track)
        self._nodes[path] = node
        self._dynamic.append(node)
        self._timestamps_cache = None
        if self._time is not None:
            return node, node.messages_at_time(self._time)
        return node, node.messages_at_index(0)

    def _install(
        self,
        handle: SceneHandle,
        carrier: Track,
        inner: Track | None = None,
        offset=None,
    ) -> None:
        with self._lock:
            kinds = [t.kind for t in (carrier, inner) if t is not None and not t.static]
            for kind in kinds:
                check_kinds(self.timestamps_kind, kind, f"scene {self.name!r}")
            anchor, messages = self._acquire_anchor(handle.base)
            handle.root_path = f"{anchor}/{handle.name}"
            handle.pose_path = f"{handle.root_path}/pose"
            leaf = handle.pose_path
            _, more = self._add_node(handle.pose_path, carrier)
            messages += more
            if inner is not None:
                leaf = f"{handle.pose_path}/data"
                _, more = self._add_node(leaf, inner)
                messages += more
            handle.geom_path = f"{leaf}/geom"
            if offset is not None:
                message = TransformPacker(handle.geom_path).message(offset)
                self._static_transforms[handle.geom_path] = message
                messages.append(message)
            messages += self._object_messages(handle)
            self._handles[handle.name] = handle
            self._emit(messages)
            if self._camera is not None and self._camera_is_auto:
                self._camera = None  # refit when next shown
                if self._server is not None and not self._server.closed:
                    self.fit_camera()

    def _object_messages(self, handle: SceneHandle) -> list[Message]:
        messages = []
        for rel, obj in handle._objects():
            path = handle.geom_path + (f"/{rel}" if rel else "")
            message = commands.set_object(path, obj)
            self._objects[path] = message
            messages.append(message)
        return messages

    def _redraw(self, handle: SceneHandle) -> None:
        with self._lock:
            self._emit(self._object_messages(handle))

    def _set_visible(self, handle: SceneHandle, visible: bool) -> None:
        with self._lock:
            message = commands.set_property(handle.root_path, "visible", visible)
            self._properties[(handle.root_path, "visible")] = message
            self._emit([message])

    def _remove_handle(self, handle: SceneHandle) -> None:
        self._check_open()
        with self._lock:
            if self._highlight is not None and self._highlight[1] is handle:
                self._highlight = None
            self._handles.pop(handle.name, None)
            handle.removed = True
            self._drop_prefix(handle.root_path)
            messages = [commands.delete(handle.root_path)]
            messages += self._release_anchor(self._anchor_path(handle.base))
            self._emit(messages)

    def _drop_prefix(self, path: str) -> None:
        prefix = path + "/"

        def gone(p: str) -> bool:
            return p == path or p.startswith(prefix)

        for table in (self._objects, self._static_transforms, self._nodes):
            for key in [k for k in table if gone(k)]:
                del table[key]
        for key in [k for k in self._properties if gone(k[0])]:
            del self._properties[key]
        self._dynamic = [n for n in self._dynamic if not gone(n.path)]
        self._timestamps_cache = None
        if not self._dynamic:
            self.timestamps_kind = None

    def _emit(self, messages: list[Message]) -> None:
        if messages and self._server is not None and not self._server.closed:
            self._server.send(self.name, messages)

    def _snapshot(self) -> list[Message]:
        """Everything a viewer needs to show the scene as it is now."""
        messages = [commands.delete(ROOT)]
        messages += list(self._objects.values())
        messages += list(self._static_transforms.values())
        for node in self._nodes.values():
            messages += node.current_messages()
        messages += list(self._properties.values())
        if self._highlight is not None and self._highlight[0] == "scaled":
            handle = self._highlight[1]
            messages.append(
                commands.set_property(handle.geom_path, "scale", [2.0, 2.0, 2.0])
            )
        if self._camera is not None:
            messages.append(self._camera)
        return messages

    def _extent_points(self) -> np.ndarray:
        """Points (scene base coordinates, roughly) that the camera should see."""
        chunks = []
        for handle in self._handles.values():
            node = self._nodes.get(handle.pose_path)
            origins = (
                node.track.positions()
                if node is not None
                else self._static_offset(handle.pose_path)
            )
            local = np.asarray(handle._extent(), dtype=float).reshape(-1, 3)
            if isinstance(handle, PathHandle) or (
                isinstance(handle, PointsHandle) and not handle.moving
            ):
                points = local + origins.mean(axis=0)  # the geometry is the data
            else:
                points = np.vstack([origins, local + origins.mean(axis=0)])
            anchor = self._anchors.get(self._anchor_path(handle.base))
            if anchor is not None and anchor[0] is not None:
                points = anchor[0].track.positions() + points.mean(axis=0)
            chunks.append(points)
        if not chunks:
            return np.zeros((0, 3))
        return np.vstack(chunks)

    def _static_offset(self, path: str) -> np.ndarray:
        message = self._static_transforms.get(path)
        if message is None:
            return np.zeros((1, 3))
        import umsgpack

        matrix = np.asarray(umsgpack.unpackb(message.data)["matrix"]).reshape(4, 4).T
        return matrix[:3, 3].reshape(1, 3)

    # publishers drive single handles by sample index
    def _show_handle_index(self, handle: SceneHandle, index: int) -> float | None:
        """Move ``handle``'s pose to sample ``index`` of its own track."""
        self._check_open()
        with self._lock:
            node = self._nodes.get(handle.pose_path)
            if node is None:
                return None
            self._emit(node.messages_at_index(index))
            return float(node.track.seconds[index])

    def _sync_anchor(self, frame, seconds: float) -> None:
        """Move anchors based on ``frame`` (objects expressed in it) to ``seconds``."""
        with self._lock:
            entry = self._anchors.get(self._anchor_path(frame))
            if entry is not None and entry[0] is not None:
                self._emit(entry[0].messages_at_time(seconds))


def _rotations_from_x(vectors: np.ndarray, norms: np.ndarray) -> np.ndarray:
    """Quaternions (w, x, y, z) turning the x axis onto each vector."""
    unit = vectors / np.maximum(norms, 1e-12)[:, np.newaxis]
    x = np.array([1.0, 0.0, 0.0])
    w = 1.0 + unit @ x
    axis = np.cross(np.broadcast_to(x, unit.shape), unit)
    q = np.column_stack([w, axis])
    opposite = w < 1e-9
    q[opposite] = (0.0, 0.0, 0.0, 1.0)  # half turn about z
    q /= np.linalg.norm(q, axis=1)[:, np.newaxis]
    return q


_default: Scene | None = None


def default_scene(base=None) -> Scene:
    """The scene that publishers draw into when none is given.

    Created on first use with the root of ``base``'s tree as its base (or
    ``"world"``). A new one replaces it when it was closed or when ``base``
    belongs to another tree (frames registered anew, e.g. by re-running a
    notebook).
    """
    global _default
    root = _resolve(base if base is not None else "world", "default_scene: base").root
    if _default is not None and not _default.closed and _default.base.root is not root:
        _default.close()
    if _default is None or _default.closed:
        _default = Scene(root)
    return _default
