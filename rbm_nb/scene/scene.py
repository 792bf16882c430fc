"""A 3-D scene of reference frames, played back in time, as a notebook widget.

:class:`Scene` is the facade: ``add_frame``, ``add_path``, ``add_points``,
``add_vectors`` and ``add_mesh`` return handles; ``set_time`` / ``publish``
choose the time shown; ``player()`` returns a linked
:class:`~rbm_nb.widgets.Player`; ``show()`` displays the view, ``scene.widget``
is the ``DOMWidget`` to put in layouts; ``to_html()`` writes a self-contained
page.

The facade holds parts with one job each and no state of its own: what the
scene contains (:class:`~rbm_nb.scene.state.SceneState`, plain data, in the
:class:`~rbm_nb.scene.context.SceneContext` every part shares), the objects
by name (:mod:`~rbm_nb.scene.objects`), what each ``add_*`` draws
(:mod:`~rbm_nb.scene.placements`), the frames objects hang from and every
pose lookup (:mod:`~rbm_nb.scene.anchors`), the grid, the camera, the
legend, the selection, the time shown (:mod:`~rbm_nb.scene.player_link`)
and the live view (:mod:`~rbm_nb.scene.view`). Poses are looked up once per
object for the whole recording and sent once as float buffers: the browser
moves the objects while the player plays, the kernel does nothing per frame.
"""

from __future__ import annotations

from ..core import frames
from .anchors import Anchors
from .assembly import Assembly
from .camera import Camera
from .context import SceneContext
from .export import write_html
from .grid import Grid, format_length, nice_step  # noqa: F401 (documented here before)
from .handles import (
    FrameHandle,
    MeshHandle,
    PathHandle,
    PointsHandle,
    SceneHandle,
    VectorsHandle,
)
from .objects import SceneObjects
from .placements import Placements
from .player_link import PlayerLink
from .selection import Selection
from .traits import ALL_TRAITS, ViewTraits
from .view import ViewLink


def _resolve(frame, argument: str):
    return frames.resolve_frame(frame, argument)


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
        context = SceneContext.checked(base, name, max_samples)
        self._context = context
        self._objects = objects = SceneObjects()
        self._anchors = anchors = Anchors(context)
        self._placements = Placements(self, context, anchors, objects)
        self._grid = Grid(grid)
        self._camera_part = Camera()
        self._selection = Selection()
        self._view = ViewLink(context)
        self._link = PlayerLink(context, self._view)
        self._traits = ViewTraits(
            context, self._view, objects, self._grid, self._camera_part, self._link
        )
        self._assembly = Assembly(
            context,
            objects,
            anchors,
            self._view,
            self._traits,
            self._grid,
            self._camera_part,
            self._selection,
        )
        # meshcat's own grid and axes are 1 m wide at the origin: ours fits the data
        self.state.set_property("/Grid", "visible", False)
        self.state.set_property("/Axes", "visible", False)

    # -- identity (the context's) -----------------------------------------------
    @property
    def base(self):
        """The scene's base frame (everything is drawn in its coordinates)."""
        return self._context.base

    @property
    def name(self) -> str:
        return self._context.name

    @property
    def max_samples(self) -> int | None:
        return self._context.max_samples

    @property
    def state(self):
        """What the scene contains (:class:`~rbm_nb.scene.state.SceneState`)."""
        return self._context.state

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
        return self._assembly.install(self._placements.frame(frame, base, scale, label))

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
        style = {"color": color, "max_points": max_points, "tolerance": tolerance}
        return self._assembly.install(self._placements.path(frame, base, style, label))

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
        style = {"color": color, "size": size}
        placement = self._placements.points(points, frame, timestamps, style, label)
        return self._assembly.install(placement)

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
        style = {"color": color, "length": length}
        placement = self._placements.vectors(
            frame, vectors, origins, timestamps, base, style, label
        )
        return self._assembly.install(placement)

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
        style = {"color": color, "opacity": opacity, "scale": scale}
        placement = self._placements.mesh(
            frame, mesh, base, size, offset, rotation, style, label
        )
        return self._assembly.install(placement)

    @property
    def handles(self) -> dict:
        """The scene's objects by name."""
        return dict(self._objects.by_name)

    def __getitem__(self, name: str) -> SceneHandle:
        return self._objects[name]

    def __len__(self) -> int:
        return len(self._objects)

    # -- time -------------------------------------------------------------------
    @property
    def timestamps_kind(self) -> str | None:
        """``"datetime64"``, ``"timedelta64"`` or ``"numeric"`` for the moving
        objects' timestamps (the core's kinds of time); None if static."""
        return self.state.kind

    def set_time(self, t) -> None:
        """Show every object as it is at ``t``.

        ``t`` is float seconds (epoch seconds for datetime data: the latest
        sample whose epoch float is at or before ``t``) or a datetime64
        value (exact to the ns: samples 1 ns apart are told apart). With a linked player this moves the player (and so
        every view following it). Without one, ``t`` is kept between one
        span before the first sample (all moving objects hidden) and the last
        sample (every object as it was last).
        """
        self._link.set_time(t)

    def publish(self, idx: int | None = None) -> None:
        """Show sample ``idx`` of :attr:`timestamps` (the first by default)."""
        self._link.publish(idx)

    @property
    def time(self) -> float | None:
        """The time shown (float seconds), None before any was set.

        With a linked player, the player's time as the kernel last learned it.
        """
        return self._link.time

    @property
    def timestamps(self):
        """Time axis for playback: None for a scene where nothing moves.

        When all moving objects share their timestamps these are returned
        as they are; otherwise a regular grid spanning all of them at the
        finest mean sampling interval.
        """
        return self._link.timestamps()

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
        return self._link.new_player(self, step, speed, skip, loop)

    def _attach_player(self, player) -> None:
        """Follow ``player`` (called by ``Player.link``)."""
        self._link.attach(player)

    def _detach_player(self, player) -> None:
        self._link.detach(player)

    # -- the view -----------------------------------------------------------------
    @property
    def widget(self):
        """The scene's ``DOMWidget`` (created on first use): put it in any layout."""
        self._context.check_open()
        with self._context.lock:
            if self._view.widget is None:
                if self._camera_part.value is None:
                    self._camera_part.fit(self._assembly.bounds())
                widget = self._view.open(
                    self._link.time_key,
                    self._objects.checked_frame_name,
                    lambda: self.handles,
                )
                self._traits.push(*ALL_TRAITS)
                self._link.show_in(widget)
                widget.observe(self._on_selected, "selected")
            return self._view.widget

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

    # -- selection, camera --------------------------------------------------------
    @property
    def selected(self) -> str | None:
        """Name of the selected frame (clicked in 3D, or set here or by a FrameTree)."""
        widget = self._view.widget
        return None if widget is None else widget.selected

    @selected.setter
    def selected(self, name) -> None:
        if name is not None:
            name = _resolve(name, "Scene.selected").name
        self.widget.selected = name

    def _on_selected(self, change) -> None:
        # a drawn frame's triad is enlarged; other frames are selected without
        # adding anything to the scene
        name = change["new"]
        if not self._context.closed:
            drawn = name is not None and name in self._objects.frame_paths()
            self.highlight(name if drawn else None)

    def follow(self, frame=None) -> None:
        """Keep the camera on ``frame`` (drawn with ``add_frame``) as it moves; None stops."""
        if frame is not None:
            frame = _resolve(frame, "Scene.follow: frame").name
            self._objects.drawn(frame, "Scene.follow")
        self.widget.follow = frame

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
        t = self._link.time_key()
        if t is None:
            span = self.state.span()
            t = 0.0 if span is None else span[0]
        self._context.check_open()
        with self._context.lock:
            self._camera_part.focus(name, self._objects, self.state, t, distance)
            self._traits.push("_camera")

    def fit_camera(self) -> None:
        """Point the camera at everything in the scene."""
        self._context.check_open()
        with self._context.lock:
            self._camera_part.fit(self._assembly.bounds())
            self._traits.push("_camera")

    def set_camera(self, position, target) -> None:
        """Place the camera at ``position`` looking at ``target`` (scene base coordinates)."""
        self._context.check_open()
        with self._context.lock:
            self._camera_part.set(position, target)
            self._traits.push("_camera")

    def highlight(self, frame=None) -> None:
        """Emphasise ``frame`` (enlarged triad); None removes the emphasis."""
        self._context.check_open()
        with self._context.lock:
            self._view.emit(self._selection.clear(self.state))
            if frame is not None:
                frame = _resolve(frame, "highlight: frame")
                self._view.emit(
                    self._selection.emphasise(
                        frame, self._objects, self.state, self._highlight_triad
                    )
                )

    def _highlight_triad(self, frame) -> SceneHandle:
        return self.add_frame(frame, scale=1.0, label=f"highlight {frame.name}")

    def legend(self) -> list[dict]:
        """The colour legend: ``{"text", "color"}`` rows (colour a hex string or a list)."""
        return self._traits.legend()

    # -- export -------------------------------------------------------------------
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
        self._context.check_open()
        return write_html(
            self,
            path,
            series=series,
            player=player if player is not None else self._link.player,
            max_frames=max_frames,
            title=title,
            autoplay=autoplay,
        )

    def _snapshot_message(self, max_samples: int | None = None) -> tuple[dict, list]:
        """The content message that builds this scene in a fresh view."""
        return self._view.snapshot_message(max_samples)

    # -- life cycle ---------------------------------------------------------------
    @property
    def closed(self) -> bool:
        return self._context.closed

    def close(self) -> None:
        """Close the scene and its widget; idempotent."""
        if self._context.closed:
            return
        with self._context.lock:
            self._context.closed = True
            self._objects.clear()
        self._view.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __repr__(self) -> str:
        state = "closed" if self.closed else f"{len(self)} objects"
        return f"<Scene {self.name!r} base={self.base.name!r} ({state})>"

    # -- what handles and publishers call ------------------------------------------
    def _check_open(self) -> None:
        self._context.check_open()

    def _redraw(self, handle: SceneHandle) -> None:
        self._assembly.redraw(handle)

    def _set_visible(self, handle: SceneHandle, visible: bool) -> None:
        self._assembly.set_visible(handle, visible)

    def _remove_handle(self, handle: SceneHandle) -> None:
        self._assembly.remove(handle)

    def _track(self, path: str):
        return self.state.tracks.get(path)

    def _show_handle_index(self, handle: SceneHandle, index: int) -> int | float | None:
        """Show ``handle``'s pose at sample ``index`` of its own track (publishers)."""
        return self._link.pin_sample(handle.pose_path, index)

    def _sync_anchor(self, frame, key: int | float) -> None:
        """Move anchors based on ``frame`` (objects expressed in it) to time ``key``."""
        path = self._anchors.moving_path(frame)
        if path is not None:
            self._link.pin(path, key)

    # read by tests and benchmarks written before the split
    @property
    def _camera(self) -> dict | None:
        return self._camera_part.value

    @property
    def _highlight(self):
        return self._selection.current

    @property
    def _stream(self) -> dict | None:
        return self._view.stream


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
