"""A 3-D scene of reference frames, played back in time, as a notebook widget.

:class:`Scene` is the facade: ``add_frame``, ``add_path``, ``add_points``,
``add_vectors`` and ``add_mesh`` return handles; ``set_time`` / ``publish``
choose the time shown; ``player()`` returns a linked
:class:`~rbm_nb.widgets.Player`; ``show()`` displays the view, ``scene.widget``
is the ``DOMWidget`` to put in layouts; ``to_html()`` writes a self-contained
page.

What the scene contains lives in a :class:`~rbm_nb.scene.state.SceneState`
(plain data, tested without a browser); the widget
(:class:`~rbm_nb.scene.widget.SceneWidget`) is only its transport and view.
Poses are looked up once per object for the whole recording (see
:mod:`rbm_nb.scene.tracks`) and sent once as float buffers: the browser
moves the objects while the player plays, the kernel does nothing per frame.
"""

from __future__ import annotations

import itertools
import math
import re
import threading
import uuid
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from .._engine.time import check_compatible, epoch_seconds, from_epoch_seconds
from ..core import frames
from . import commands, stream
from .commands import Message, color_int
from .export import write_html
from .handles import (
    FrameHandle,
    MeshHandle,
    PathHandle,
    PointsHandle,
    SceneHandle,
    VectorsHandle,
    _points_array,
)
from .path_refine import PathRefiner
from .state import ROOT, SceneState
from .tracks import Track

if TYPE_CHECKING:  # the widget module needs the notebook extras at import
    from .widget import SceneWidget

_counter = itertools.count(1)
GRID_PATH = f"{ROOT}/grid"
GRID_COLOR = "#5a5a5a"
AXIS_COLORS = ["#ff0000", "#00ff00", "#0000ff"]


def _resolve(frame, argument: str):
    return frames.resolve_frame(frame, argument)


#: largest distance from the scene's origin (metres) an object may reach: far
#: beyond any tracked volume, far inside float32 (the browser's numbers) and
#: the grid's and camera's arithmetic
MAX_COORDINATE = 1e9


def _camera_distance(value) -> float:
    """A camera distance in metres: positive, finite, within the drawable space."""
    try:
        distance = float(value)
    except (TypeError, ValueError):
        raise ValueError(
            f"Scene.focus: distance must be a number of metres, got {value!r}"
        ) from None
    if not 0 < distance <= MAX_COORDINATE:
        raise ValueError(
            f"Scene.focus: distance must be positive and at most {MAX_COORDINATE:.0e} m, "
            f"got {value!r}"
        )
    return distance


def _reach(points) -> float:
    """Largest absolute coordinate of ``points`` (NaN rows, i.e. missing, aside)."""
    values = np.abs(np.asarray(points, dtype=float))
    values = values[~np.isnan(values)]
    return float(values.max()) if values.size else 0.0


def _slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.\-]+", "_", str(text)).strip("_") or "object"


def nice_step(span: float, lines: int = 10) -> float:
    """A 1, 2 or 5 times a power of ten close to ``span / lines`` (grid spacing)."""
    raw = max(float(span), 1e-9) / lines
    power = 10.0 ** math.floor(math.log10(raw))
    for factor in (1.0, 2.0, 5.0, 10.0):
        if raw <= factor * power * 1.0000001:
            return factor * power
    return 10.0 * power


def format_length(metres: float) -> str:
    """``0.5 m``, ``20 m``, ``2 km``, ``5 cm``."""
    if metres >= 1000:
        return f"{metres / 1000:g} km"
    if metres < 0.01:
        return f"{metres * 1000:g} mm"
    if metres < 1:
        return f"{metres * 100:g} cm"
    return f"{metres:g} m"


class Scene:
    """A 3-D scene of frames, paths, points, vectors and meshes (meshcat).

    Parameters
    ----------
    base : str or ReferenceFrame, default "world"
        The fixed frame of the scene: everything is drawn in its coordinates.
    name : str, optional
        Name of the scene (letters, digits, ``-``, ``_``).
    grid : bool, default True
        Draw a grid in the base's xy plane, sized to the scene; its spacing
        is in the legend.
    max_samples : int, optional
        Send at most this many samples per moving object to the browser
        (evenly spaced). All samples by default: they go once, as float
        buffers, when the view opens.

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

    def __init__(
        self,
        base="world",
        *,
        name: str | None = None,
        grid: bool = True,
        max_samples: int | None = None,
    ):
        self.base = _resolve(base, "Scene: base")
        if name is None:
            name = f"scene-{next(_counter)}-{uuid.uuid4().hex[:6]}"
        if not re.fullmatch(r"[A-Za-z0-9_\-]+", name):
            raise ValueError(
                f"Scene: name must be letters, digits, '-' or '_', got {name!r}"
            )
        if max_samples is not None and (
            isinstance(max_samples, bool)
            or not isinstance(max_samples, (int, np.integer))
            or max_samples < 2
        ):
            raise ValueError(
                f"Scene: max_samples must be an integer >= 2 or None, got {max_samples!r}"
            )
        self.max_samples = None if max_samples is None else int(max_samples)
        self.name = name
        self.state = SceneState()
        self._lock = threading.RLock()
        self._widget: SceneWidget | None = None
        self._player = None
        self._closed = False
        self._grid = bool(grid)
        self._grid_step: float | None = None
        self._handles: dict[str, SceneHandle] = {}
        self._anchors: dict[str, list] = {}  # path -> [moving?, users, base frame]
        self._camera: dict | None = None
        self._camera_is_auto = True
        self._time: float | None = None
        self._highlight: tuple | None = None
        # the chunking last sent to a live view (None: poses went whole)
        self._stream: dict | None = None
        self._stream_generation = 0
        # meshcat's own grid and axes are 1 m wide at the origin: ours fits the data
        self.state.set_property("/Grid", "visible", False)
        self.state.set_property("/Axes", "visible", False)

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
        tolerance: float | None = None,
        label: str | None = None,
    ) -> PathHandle:
        """Draw the trajectory of a moving frame in ``base`` as a line.

        The line is simplified to what shows on screen: points are kept,
        worst first, while a sample lies farther than ``tolerance`` from the
        line, up to ``max_points``; it is broken where samples are missing
        (see :mod:`rbm_nb.scene.decimate`). A path of hours sends as much as
        one of minutes.

        Parameters
        ----------
        frame : str or ReferenceFrame
            A moving frame (or one that moves wrt ``base``).
        base : str or ReferenceFrame, optional
            The frame the path is expressed in; the scene's base by default.
        color : str or int, default "#ffffff"
        max_points : int, default 1000
            At most this many points are drawn.
        tolerance : float, optional
            Metres a sample may lie from the line drawn; by default 1/2000 of
            the path's bounding-box diagonal (half a pixel when the whole path
            fills a view 1000 pixels wide).
        """
        frame = _resolve(frame, "add_path: frame")
        base = self._resolve_base(base, "add_path")
        track = self._looked_up(frame, base)
        if track.static:
            raise ValueError(
                f"add_path: frame {frame.name!r} does not move wrt {base.name!r}, it has no path"
            )
        style = {"color": color, "max_points": max_points, "tolerance": tolerance}
        handle = PathHandle(
            self,
            self._new_name(label or f"path {frame.name}"),
            frame,
            base,
            style,
            track.translation,
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

    # -- time ---------------------------------------------------------------------
    @property
    def timestamps_kind(self) -> str | None:
        """``"datetime"`` or ``"float"`` for the moving objects' timestamps; None if static."""
        return self.state.kind

    def set_time(self, t) -> None:
        """Show every object as it is at ``t``.

        ``t`` is float seconds (epoch seconds for datetime data) or a
        datetime64 value. With a linked player this moves the player (and so
        every view following it). Without one, ``t`` is kept between one
        span before the first sample (all moving objects hidden) and the last
        sample (every object as it was last).
        """
        self._check_open()
        seconds = epoch_seconds(t, self.state.kind, "Scene.set_time: t")
        if not math.isfinite(seconds):
            raise ValueError(f"Scene.set_time: t must be finite, got {t!r}")
        timeline = self.state.timeline()
        if timeline is not None and self._player is None:
            # after the last sample every object stays as it was then, and
            # before the first all moving ones are hidden: times beyond show
            # nothing new, so 1e300 s is kept to the span (and one span before)
            start, end = float(timeline[0][0]), float(timeline[0][-1])
            seconds = min(max(seconds, start - max(end - start, 1.0)), end)
        with self._lock:
            self._time = seconds
            if self.state.pins:
                self.state.pins.clear()
                self._sync_widget("_pins")
            if self._player is not None:
                self._player.seek_time(seconds)
            elif self._widget is not None:
                self._widget.time = seconds - self.state.origin

    def publish(self, idx: int | None = None) -> None:
        """Show sample ``idx`` of :attr:`timestamps` (the first by default)."""
        self._check_open()
        timeline = self.state.timeline()
        if timeline is None:
            return
        seconds = timeline[0]
        idx = 0 if idx is None else int(idx)
        if not -len(seconds) <= idx < len(seconds):
            raise IndexError(
                f"Scene.publish: idx {idx} outside [0, {len(seconds) - 1}]"
            )
        self.set_time(float(seconds[idx]))

    @property
    def time(self) -> float | None:
        """The time shown (float seconds), None before any was set.

        With a linked player, the player's time as the kernel last learned it.
        """
        if self._player is not None:
            return self._player.data_time
        return self._time

    @property
    def timestamps(self):
        """Time axis for playback: None for a scene where nothing moves.

        When all moving objects share their timestamps these are returned
        as they are; otherwise a regular grid spanning all of them at the
        finest mean sampling interval.
        """
        timeline = self.state.timeline()
        if timeline is None:
            return None
        seconds, original = timeline
        if original is not None:
            return original
        if self.state.kind is not None:
            return from_epoch_seconds(seconds, self.state.kind)
        return seconds

    def player(
        self,
        step: int = 1,
        speed: float = 1.0,
        skip: float | None = None,
        *,
        loop: bool = False,
    ):
        """A :class:`~rbm_nb.widgets.Player` over :attr:`timestamps`, driving this scene.

        The player's clock runs in the browser; the scene's view follows it
        there. One player can drive several scenes and plots
        (``player.link(other)``).
        """
        self._check_open()
        if self.state.timeline() is None:
            raise ValueError(
                f"Scene {self.name!r} has no moving objects, there is nothing to play; "
                "add a moving frame first"
            )
        # lazy (optional dependency): the Player needs anywidget
        from ..widgets.player import Player

        player = Player(self, step=step, speed=speed, skip=skip, loop=loop)
        if self._time is not None:
            player.seek_time(self._time)
        player.link(self)
        return player

    def _attach_player(self, player) -> None:
        """Follow ``player`` (called by ``Player.link``)."""
        self._check_open()
        check_compatible(
            [self.state.kind, player.timestamps_kind], f"link(Scene {self.name!r})"
        )
        self._player = player
        if self.state.pins:  # the player drives everything from now on
            self.state.pins.clear()
            self._sync_widget("_pins")
        if self._widget is not None:
            self._widget.player = player

    def _detach_player(self, player) -> None:
        if self._player is player:
            self._player = None
            if self._widget is not None:
                self._widget.player = None

    # -- the widget -----------------------------------------------------------------
    @property
    def widget(self):
        """The scene's ``DOMWidget`` (created on first use): put it in any layout."""
        self._check_open()
        with self._lock:
            if self._widget is None:
                # lazy (optional dependency): the widget needs anywidget
                from .widget import SceneWidget

                if self._camera is None:
                    self._camera = self._fitted_camera()
                    self._camera_is_auto = True
                widget = SceneWidget(
                    lambda cap=None: (
                        self._live_snapshot_message()
                        if cap is None
                        else self._snapshot_message(min(cap, self.max_samples or cap))
                    ),
                    chunk=self._chunk_message,
                    check_frame=self._checked_frame_name,
                )
                self._widget = widget
                # finer paths where the camera zooms in (path_refine.py)
                self._path_refiner = PathRefiner(widget, lambda: self.handles)
                for name in (
                    "_origin",
                    "_camera",
                    "_frames",
                    "_labels",
                    "_legend",
                    "_pins",
                ):
                    self._sync_widget(name)
                if self._player is not None:
                    widget.player = self._player
                elif self._time is not None:
                    widget.time = self._time - self.state.origin
                widget.observe(self._on_selected, "selected")
            return self._widget

    def show(self, *, height: int | None = None) -> None:
        """Display the view in the notebook.

        Parameters
        ----------
        height : int, optional
            Height of the view in pixels (480 by default).
        """
        from IPython.display import display

        widget = self.widget
        if height is not None:
            widget.height = height
        display(widget)

    def _repr_mimebundle_(self, **kwargs):
        return self.widget._repr_mimebundle_(**kwargs)

    @property
    def selected(self) -> str | None:
        """Name of the selected frame (clicked in 3D, or set here or by a FrameTree)."""
        return None if self._widget is None else self._widget.selected

    @selected.setter
    def selected(self, name) -> None:
        if name is not None:
            name = _resolve(name, "Scene.selected").name
        self.widget.selected = name

    def _on_selected(self, change) -> None:
        # a drawn frame's triad is enlarged; other frames are selected without
        # adding anything to the scene
        name = change["new"]
        if self._closed:
            return
        if name is None or name not in self._frame_paths():
            self.highlight(None)
        else:
            self.highlight(name)

    def _checked_frame_name(self, name: str, trait: str) -> str:
        """What ``selected`` (a registered frame) and ``follow`` (a drawn one) accept."""
        if not isinstance(name, str):
            raise ValueError(f"Scene.{trait} must be a frame name, got {name!r}")
        resolved = _resolve(name, f"Scene.{trait}").name
        if trait == "follow" and resolved not in self._frame_paths():
            raise ValueError(
                f"Scene.follow: frame {resolved!r} is not drawn in this scene; "
                f"add_frame({resolved!r}) first (drawn: {sorted(self._frame_paths())})"
            )
        return resolved

    def follow(self, frame=None) -> None:
        """Keep the camera on ``frame`` (drawn with ``add_frame``) as it moves; None stops."""
        name = None
        if frame is not None:
            name = _resolve(frame, "Scene.follow: frame").name
            if name not in self._frame_paths():
                raise ValueError(
                    f"Scene.follow: frame {name!r} is not drawn in this scene; "
                    f"add_frame({name!r}) first (drawn: {sorted(self._frame_paths())})"
                )
        self.widget.follow = name

    def focus(self, frame, *, distance: float | None = None) -> None:
        """Point the camera at ``frame`` as it is at the current time.

        Parameters
        ----------
        frame : str or ReferenceFrame
            A frame drawn with ``add_frame``.
        distance : float, optional
            Camera distance in metres (ten times the triad's size by default).
        """
        name = _resolve(frame, "Scene.focus: frame").name
        paths = self._frame_paths()
        if name not in paths:
            raise ValueError(
                f"Scene.focus: frame {name!r} is not drawn in this scene; add_frame({name!r}) first"
            )
        if distance is not None:
            distance = _camera_distance(distance)
        t = self.time if self.time is not None else self.state.origin
        pose = self.state.world_pose(paths[name], t)
        if pose is None:  # not started yet or missing now: where it is last
            pose = self.state.world_pose(paths[name], math.inf)
        if pose is None:
            raise ValueError(
                f"Scene.focus: frame {name!r} has no pose at the time shown ({t:g} s) "
                "nor at its last sample: its samples there are missing"
            )
        target = pose[:3, 3]
        if distance is None:
            handle = next(
                h
                for h in self._handles.values()
                if isinstance(h, FrameHandle) and h.pose_path == paths[name]
            )
            distance = 10.0 * handle.style["scale"]
        direction = np.array([1.0, -1.4, 1.0]) / np.linalg.norm([1.0, -1.4, 1.0])
        self._set_camera(target + direction * float(distance), target, auto=False)

    def fit_camera(self) -> None:
        """Point the camera at everything in the scene."""
        position, target = self._fitted_camera_parts()
        self._set_camera(position, target, auto=True)

    def _fitted_camera_parts(self) -> tuple[np.ndarray, np.ndarray]:
        points = self._extent_points()
        if len(points) == 0:
            points = np.zeros((1, 3))
        low, high = points.min(axis=0), points.max(axis=0)
        target = (low + high) / 2
        radius = max(float(np.linalg.norm(high - low)) / 2, 1.0)
        direction = np.array([1.0, -1.4, 1.0])
        position = target + direction / np.linalg.norm(direction) * radius * 1.7
        return position, target

    def _fitted_camera(self) -> dict:
        position, target = self._fitted_camera_parts()
        return _camera_dict(position, target)

    def set_camera(self, position, target) -> None:
        """Place the camera at ``position`` looking at ``target`` (scene base coordinates)."""
        p = _points_array(position, "position", "set_camera")[0]
        t = _points_array(target, "target", "set_camera")[0]
        if not np.linalg.norm(p - t) > 0:
            raise ValueError(
                f"set_camera: position and target are the same point {p.tolist()}; "
                "the camera needs a direction to look in"
            )
        if not max(_reach(p), _reach(t)) <= MAX_COORDINATE:
            raise ValueError(
                f"set_camera: position {p.tolist()} or target {t.tolist()} is beyond "
                f"{MAX_COORDINATE:.0e} m from the origin"
            )
        self._set_camera(p, t, auto=False)

    def _set_camera(self, position, target, auto: bool) -> None:
        self._check_open()
        with self._lock:
            self._camera = _camera_dict(position, target)
            self._camera_is_auto = auto
            self._sync_widget("_camera")

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
                            self.state.set_property(
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
                    message = self.state.set_property(
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
        series=None,
        player=None,
        max_frames: int | None = 20000,
        title: str | None = None,
        autoplay: bool = False,
    ):
        """Write the dashboard (3D view, plots, player) as one self-contained HTML file.

        The page needs no kernel, no server and no network: meshcat's viewer,
        the widgets' JavaScript and the data are inlined; the player's clock
        runs in the page as in the notebook.

        Parameters
        ----------
        path : str or os.PathLike
            Output file; written atomically (a temporary file, then renamed).
        series : widget or list of widgets, optional
            Other views to include below the 3D view (e.g. a time-series plot
            linked to the same player); any anywidget works.
        player : Player, optional
            The player to include (the scene's linked one, else a new one).
        max_frames : int or None, default 20000
            Keep at most this many samples per moving object (evenly spaced);
            None keeps all. The page says at which rate its poses are, and
            how many points of each path it draws (paths are simplified as
            in the notebook, see :meth:`add_path`): a page of hours stays
            a few MB.
        title : str, optional
        autoplay : bool, default False

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
        self._check_open()
        return write_html(
            self,
            path,
            series=series,
            player=player,
            max_frames=max_frames,
            title=title,
            autoplay=autoplay,
        )

    # -- life cycle -------------------------------------------------------------
    @property
    def closed(self) -> bool:
        return self._closed

    def close(self) -> None:
        """Close the scene and its widget; idempotent."""
        if self._closed:
            return
        with self._lock:
            self._closed = True
            widget, self._widget = self._widget, None
            for handle in self._handles.values():
                handle.removed = True
            self._handles.clear()
        if widget is not None:
            widget.close()

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

    def _looked_up(self, frame, base) -> Track:
        """The pose of ``frame`` in ``base``: the one an anchor holds already
        (objects drawn in ``frame``), else looked up. A second lookup of a
        long recording would cost its time and a copy of its poses."""
        if base is self.base:
            anchor = self.state.tracks.get(self._anchor_path(frame))
            if anchor is not None and frame is not self.base:
                return anchor
        return Track.lookup(frame, base)

    def _anchor_path(self, base) -> str:
        if base is self.base:
            return f"{ROOT}/root"
        return f"{ROOT}/anchor_{_slug(base.name)}"

    def _acquire_anchor(self, base) -> tuple[str, list[Message]]:
        path = self._anchor_path(base)
        entry = self._anchors.get(path)
        messages: list[Message] = []
        if entry is None:
            moving = False
            if base is not self.base:
                moving, messages = self._add_node(path, Track.lookup(base, self.base))
            entry = [moving, 0, base]
            self._anchors[path] = entry
        entry[1] += 1
        return path, messages

    def _release_anchor(self, path: str) -> list[Message]:
        entry = self._anchors.get(path)
        if entry is None:
            return []
        entry[1] -= 1
        if entry[1] > 0:
            return []
        del self._anchors[path]
        if path == f"{ROOT}/root":
            return []
        return [self.state.delete(path)]

    def _add_node(self, path: str, track: Track) -> tuple[bool, list[Message]]:
        """Place the node at ``path``: fixed, or following a track. Returns (moving, commands)."""
        if track.static:
            return False, [self.state.set_static(path, track.matrix())]
        self.state.add_track(path, track, f"scene {self.name!r}")
        return True, []

    def _install(
        self,
        handle: SceneHandle,
        carrier: Track,
        inner: Track | None = None,
        offset=None,
    ) -> None:
        # before anything changes: an object the view cannot draw is refused whole
        self._check_reach(handle, carrier, inner)
        with self._lock:
            kinds = [t.kind for t in (carrier, inner) if t is not None and not t.static]
            for kind in kinds:
                check_compatible([self.state.kind, kind], f"scene {self.name!r}")
            moving_before = set(self.state.tracks)
            anchor, messages = self._acquire_anchor(handle.base)
            handle.root_path = f"{anchor}/{handle.name}"
            handle.pose_path = f"{handle.root_path}/pose"
            leaf = handle.pose_path
            messages += self._add_node(handle.pose_path, carrier)[1]
            if inner is not None:
                leaf = f"{handle.pose_path}/data"
                messages += self._add_node(leaf, inner)[1]
            handle.geom_path = f"{leaf}/geom"
            if offset is not None:
                messages.append(self.state.set_static(handle.geom_path, offset))
            messages += self._object_messages(handle)
            self._handles[handle.name] = handle
            self._emit(messages)
            added = [p for p in self.state.tracks if p not in moving_before]
            if added:
                self._emit_tracks(added)
            self._content_changed()

    def _check_reach(
        self, handle: SceneHandle, carrier: Track, inner: Track | None
    ) -> None:
        """Refuse an object reaching beyond :data:`MAX_COORDINATE` from the origin."""
        reach = _reach(handle._extent()) + _reach(carrier.positions())
        if inner is not None:
            reach += _reach(inner.positions())
        if handle.base is not self.base:
            # the anchor's track when the base has one already: the same
            # lookup, not repeated for every object drawn on that base
            anchor = self.state.tracks.get(self._anchor_path(handle.base))
            base_track = (
                Track.lookup(handle.base, self.base) if anchor is None else anchor
            )
            reach += _reach(base_track.positions())
        if not reach <= MAX_COORDINATE:
            raise ValueError(
                f"add_{handle.kind}: {handle.name!r} reaches {reach:.3g} m from the "
                f"scene's origin; the 3D view draws within {MAX_COORDINATE:.0e} m "
                "(check the values and their units)"
            )

    def _object_messages(self, handle: SceneHandle) -> list[Message]:
        messages = []
        for rel, obj in handle._objects():
            path = handle.geom_path + (f"/{rel}" if rel else "")
            messages.append(self.state.set_object(path, obj))
        return messages

    def _redraw(self, handle: SceneHandle) -> None:
        with self._lock:
            self._emit(self._object_messages(handle))
            self._content_changed()

    def _set_visible(self, handle: SceneHandle, visible: bool) -> None:
        with self._lock:
            self._emit([self.state.set_property(handle.root_path, "visible", visible)])

    def _remove_handle(self, handle: SceneHandle) -> None:
        self._check_open()
        with self._lock:
            if self._highlight is not None and self._highlight[1] is handle:
                self._highlight = None
            self._handles.pop(handle.name, None)
            handle.removed = True
            before = set(self.state.tracks)
            messages = [self.state.delete(handle.root_path)]
            messages += self._release_anchor(self._anchor_path(handle.base))
            self._emit(messages)
            gone = [p for p in before if p not in self.state.tracks]
            if gone:
                self._emit_tracks([], removed=gone)
            self._content_changed()

    def _content_changed(self) -> None:
        """Refresh what depends on the whole content: grid, legend, labels, camera."""
        if self._grid:
            self._update_grid()
        for name in ("_origin", "_frames", "_labels", "_legend"):
            self._sync_widget(name)
        if self._camera is not None and self._camera_is_auto:
            self.fit_camera()

    def _update_grid(self) -> None:
        points = self._extent_points()
        if len(points) == 0:
            return
        low, high = points.min(axis=0)[:2], points.max(axis=0)[:2]
        span = float(max(np.max(high - low), 1.0))
        step = nice_step(span)
        lo = np.floor(low / step) * step - step
        hi = np.ceil(high / step) * step + step
        if self._grid_step == step and getattr(self, "_grid_box", None) == (
            tuple(lo),
            tuple(hi),
        ):
            return
        self._grid_step = step
        self._grid_box = (tuple(lo), tuple(hi))
        xs = np.arange(lo[0], hi[0] + step / 2, step)
        ys = np.arange(lo[1], hi[1] + step / 2, step)
        segments = []
        for x in xs:
            segments += [(x, lo[1], 0.0), (x, hi[1], 0.0)]
        for y in ys:
            segments += [(lo[0], y, 0.0), (hi[0], y, 0.0)]
        g = commands.meshcat_geometry()
        lines = g.LineSegments(
            g.PointsGeometry(
                np.ascontiguousarray(np.array(segments, dtype=np.float32).T)
            ),
            g.LineBasicMaterial(color=color_int(GRID_COLOR)),
        )
        self._emit([self.state.set_object(GRID_PATH, lines)])

    def _frame_paths(self) -> dict[str, str]:
        """Frame name -> pose path of its (first) triad."""
        out: dict[str, str] = {}
        for handle in self._handles.values():
            if isinstance(handle, FrameHandle) and handle.frame.name not in out:
                out[handle.frame.name] = handle.pose_path
        return out

    def legend(self) -> list[dict]:
        """The colour legend: ``{"text", "color"}`` rows (colour a hex string or a list)."""
        rows: list[dict] = []
        if any(isinstance(h, FrameHandle) for h in self._handles.values()):
            rows.append({"text": "frame axes x, y, z", "color": AXIS_COLORS})
        for handle in self._handles.values():
            if isinstance(handle, FrameHandle) or "color" not in handle.style:
                continue
            color = f"#{color_int(handle.style['color']):06x}"
            rows.append({"text": handle.name.replace("_", " "), "color": color})
        if self._grid and self._grid_step is not None:
            rows.append(
                {"text": f"grid {format_length(self._grid_step)}", "color": GRID_COLOR}
            )
        return rows

    def _widget_value(self, name: str):
        if name == "_origin":
            return self.state.origin
        if name == "_camera":
            return dict(self._camera or {})
        if name == "_frames":
            return self._frame_paths()
        if name == "_labels":
            return {path: frame for frame, path in self._frame_paths().items()}
        if name == "_legend":
            return self.legend()
        if name == "_pins":
            origin = self.state.origin
            return {path: t - origin for path, t in self.state.pins.items()}
        raise KeyError(name)

    def _sync_widget(self, name: str) -> None:
        if self._widget is not None:
            setattr(self._widget, name, self._widget_value(name))

    def _emit(self, messages: list[Message]) -> None:
        if messages and self._widget is not None:
            self._widget.push({"type": "commands"}, [m.data for m in messages])

    def _emit_tracks(self, paths: list[str], removed: Sequence[str] = ()) -> None:
        if self._widget is None or not self._widget.ready:
            return
        origin = self.state.origin
        if (
            self._widget._origin != origin  # the time base moved
            or self._stream is not None  # chunks of the old content are stale
            or stream.streams(self.state, self.max_samples)
        ):
            self._widget._origin = origin
            self._widget.send_content()
            return
        sub = SceneState()
        sub.tracks = {p: self.state.tracks[p] for p in paths}
        meta, buffers = sub.track_payload(max_samples=self.max_samples, origin=origin)
        self._widget.push(
            {"type": "tracks", "tracks": meta, "remove": list(removed)}, buffers
        )

    def _snapshot_message(self, max_samples: int | None = None) -> tuple[dict, list]:
        """The content message that builds this scene in a fresh view."""
        with self._lock:
            commands_ = [m.data for m in self.state.snapshot()]
            meta, buffers = self.state.track_payload(max_samples=max_samples)
            offset = len(commands_)
            for entry in meta:
                for key in ("times", "translation", "rotation", "scale"):
                    if entry[key] is not None:
                        entry[key] += offset
            content = {"type": "snapshot", "commands": offset, "tracks": meta}
            return content, commands_ + buffers

    def _live_snapshot_message(self) -> tuple[dict, list]:
        """The content message for a live view: poses whole, or a coarse copy
        and the chunking when they are long (see :mod:`rbm_nb.scene.stream`)."""
        with self._lock:
            if not stream.streams(self.state, self.max_samples):
                self._stream = None
                return self._snapshot_message(self.max_samples)
            content, buffers = self._snapshot_message(stream.COARSE_SAMPLES)
            seconds = self.time
            at = None if seconds is None else seconds - self.state.origin
            self._stream_generation += 1
            self._stream = stream.plan(self.state, at, self._stream_generation)
            content["stream"] = self._stream
            return content, buffers

    def _chunk_message(self, content: dict) -> list[tuple[dict, list]]:
        """Answers to a browser's request for chunks (one message per chunk).

        A request for content that changed since (an older generation) gets
        the chunks of the current content, which the page then keeps.
        """
        with self._lock:
            plan = self._stream
            if plan is None:
                return []
            answers = []
            for index in stream.requested_chunks(content, plan["count"]):
                meta, buffers = self.state.track_chunk(index, plan["chunk"])
                head = {
                    "type": "chunk",
                    "index": index,
                    "generation": plan["generation"],
                    "tracks": meta,
                }
                answers.append((head, buffers))
            return answers

    def _extent_points(self) -> np.ndarray:
        """Points (scene base coordinates, roughly) that the camera should see."""
        chunks = []
        for handle in self._handles.values():
            track = self.state.tracks.get(handle.pose_path)
            origins = (
                track.positions()
                if track is not None
                else self._static_offset(handle.pose_path)
            )
            local = np.asarray(handle._extent(), dtype=float).reshape(-1, 3)
            if isinstance(handle, PathHandle) or (
                isinstance(handle, PointsHandle) and not handle.moving
            ):
                points = local + origins.mean(axis=0)  # the geometry is the data
            else:
                points = np.vstack([origins, local + origins.mean(axis=0)])
            anchor = self.state.tracks.get(self._anchor_path(handle.base))
            if anchor is not None:
                points = anchor.positions() + points.mean(axis=0)
            chunks.append(points)
        if not chunks:
            return np.zeros((0, 3))
        return np.vstack(chunks)

    def _static_offset(self, path: str) -> np.ndarray:
        return self.state.static_pose(path)[:3, 3].reshape(1, 3)

    def _track(self, path: str) -> Track | None:
        return self.state.tracks.get(path)

    # publishers drive single handles by sample index
    def _show_handle_index(self, handle: SceneHandle, index: int) -> float | None:
        """Show ``handle``'s pose at sample ``index`` of its own track."""
        self._check_open()
        with self._lock:
            track = self.state.tracks.get(handle.pose_path)
            if track is None:
                return None
            seconds = float(track.sample_times()[index])
            self.state.pins[handle.pose_path] = seconds
            self._sync_widget("_pins")
            return seconds

    def _sync_anchor(self, frame, seconds: float) -> None:
        """Move anchors based on ``frame`` (objects expressed in it) to ``seconds``."""
        with self._lock:
            path = self._anchor_path(frame)
            if path in self.state.tracks:
                self.state.pins[path] = float(seconds)
                self._sync_widget("_pins")


def _camera_dict(position, target) -> dict:
    return {
        "position": [float(v) for v in position],
        "target": [float(v) for v in target],
    }


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
