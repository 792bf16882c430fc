"""Handles to objects in a :class:`~rbm_nb.scene.Scene`.

Every ``Scene.add_*`` call returns a handle. A handle can be restyled with
``update(**style)``, hidden with ``visible = False`` and deleted with
``remove()``. The geometry itself is built here from meshcat's geometry
classes; the scene owns placement and timing.

Each object lives at ``/rbm/<anchor>/<name>`` in the meshcat tree::

    <name>            user visibility
      pose            follows the frame in the handle's base (static or a track)
        [data]        follows the object's own samples (moving points/vectors)
          geom        the geometry, with its fixed offset
"""

from __future__ import annotations

import numpy as np

from . import path_source
from .commands import color_int
from .commands import meshcat_geometry as _geometry
from .meshes import mesh_geometry


class SceneHandle:
    """Base class of scene handles."""

    kind = "object"

    def __init__(self, scene, name: str, frame, base, style: dict):
        self._scene = scene
        self.name = name
        self.frame = frame
        self.base = base
        self._style = dict(style)
        self._visible = True
        self.root_path = ""
        self.pose_path = ""
        self.geom_path = ""
        self.removed = False

    # -- facade -----------------------------------------------------------------
    @property
    def scene(self):
        return self._scene

    @property
    def style(self) -> dict:
        """Current styling keywords."""
        return dict(self._style)

    @property
    def visible(self) -> bool:
        """Whether the object is shown (when its data covers the current time)."""
        return self._visible

    @visible.setter
    def visible(self, value: bool) -> None:
        self._check()
        self._visible = bool(value)
        self._scene._set_visible(self, self._visible)

    def update(self, **style) -> SceneHandle:
        """Change styling keywords (the same as those of ``add_*``) and redraw."""
        self._check()
        unknown = set(style) - set(self._style)
        if unknown:
            raise ValueError(
                f"{type(self).__name__}.update: unknown style {sorted(unknown)}; "
                f"known: {sorted(self._style)}"
            )
        new = dict(self._style)
        new.update(style)
        self._validate_style(new)
        self._style = new
        self._scene._redraw(self)
        return self

    def remove(self) -> None:
        """Delete the object from the scene (idempotent)."""
        if self.removed:
            return
        self._scene._remove_handle(self)

    def _check(self) -> None:
        if self.removed:
            raise RuntimeError(f"{self.kind} {self.name!r} was removed from its scene")
        self._scene._check_open()

    def __repr__(self) -> str:
        state = " (removed)" if self.removed else ""
        return f"<{type(self).__name__} {self.name!r}{state}>"

    # -- for the scene ----------------------------------------------------------
    def _validate_style(self, style: dict) -> None:
        pass

    def _objects(self) -> list:
        """``(relative path, meshcat Object)`` pairs below ``geom``."""
        raise NotImplementedError

    def _extent(self) -> np.ndarray:
        """Points (in the handle's frame) that the camera should see."""
        return np.zeros((1, 3))


def _positive(value, name: str, owner: str) -> float:
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise ValueError(
            f"{owner}: {name} must be a positive number, got {value!r}"
        ) from None
    if not (np.isfinite(value) and value > 0):
        raise ValueError(f"{owner}: {name} must be a positive number, got {value!r}")
    return value


def _points_array(arr, name: str, owner: str) -> np.ndarray:
    arr = np.asarray(arr, dtype=np.float64)
    if arr.ndim == 1:
        arr = arr[np.newaxis]
    if arr.ndim != 2 or arr.shape[1] != 3 or arr.shape[0] == 0:
        raise ValueError(
            f"{owner}: {name} must have shape (3,) or (n, 3), got {np.shape(arr)}"
        )
    if not np.isfinite(arr).all():
        raise ValueError(f"{owner}: {name} must be finite")
    return arr


class FrameHandle(SceneHandle):
    """A frame drawn as a red/green/blue triad (x, y, z)."""

    kind = "frame"

    def _validate_style(self, style):
        style["scale"] = _positive(style["scale"], "scale", "add_frame")

    def _objects(self):
        g = _geometry()
        return [("", g.triad(self._style["scale"]))]

    def _extent(self):
        return np.eye(3) * self._style["scale"]


def segment_points(stretches) -> np.ndarray:
    """Line-segment vertices (2k, 3) float32 of unbroken stretches of a path.

    Segments, not one polyline: a stretch ends where samples are missing. A
    stretch of one sample becomes a segment of zero length (a dot).
    """
    ends = []
    for piece in stretches:
        if len(piece) == 1:
            piece = np.vstack([piece, piece])
        ends.append(np.repeat(piece, 2, axis=0)[1:-1])
    return np.vstack(ends).astype(np.float32) if ends else np.zeros((0, 3), np.float32)


class PathHandle(SceneHandle):
    """The trajectory of a frame in its base, as a line.

    The line is simplified to what shows on screen (see
    :func:`~rbm_nb.scene.decimate.simplify_path`): at most ``max_points``
    points, none farther than the tolerance from the recording (by default
    1/2000 of the path's extent), broken where samples are missing.
    """

    kind = "path"

    def __init__(
        self,
        scene,
        name,
        frame,
        base,
        style,
        samples: path_source.Samples,
    ):
        super().__init__(scene, name, frame, base, style)
        # the positions, NaN rows where samples are missing: an array, or the
        # track that looks them up (a long recording's path is not kept
        # whole: simplified block by block, looked up whole only when the
        # view asks for it finer)
        self._samples = samples
        self._shown: tuple[tuple, list[np.ndarray], float] | None = None

    @property
    def samples(self) -> np.ndarray:
        """Every recorded position, shape (n, 3), NaN rows where missing."""
        return path_source.every_sample(self._samples)

    @property
    def positions(self) -> np.ndarray:
        """The recorded positions that are not missing, shape (n, 3)."""
        samples = self.samples
        return samples[~np.isnan(samples).any(axis=1)]

    def _validate_style(self, style):
        color_int(style["color"], "add_path: color")
        value = style["max_points"]
        if (
            isinstance(value, bool)
            or not isinstance(value, (int, float, np.integer, np.floating))
            or not np.isfinite(value)
            or int(value) != value
            or value < 2
        ):
            raise ValueError(
                f"add_path: max_points must be a whole number, at least 2, got {value!r}"
            )
        style["max_points"] = int(value)
        tolerance = style.get("tolerance")
        if tolerance is not None:
            style["tolerance"] = _positive(tolerance, "tolerance", "add_path")

    def stretches(self) -> tuple[list[np.ndarray], float]:
        """The unbroken pieces of the line drawn, and the largest error (m) left."""
        key = (self._style["max_points"], self._style.get("tolerance"))
        if self._shown is None or self._shown[0] != key:
            stretches, error = self._simplified()
            self._shown = (key, stretches, error)
        return self._shown[1], self._shown[2]

    def _simplified(self) -> tuple[list[np.ndarray], float]:
        style = self._style
        return path_source.simplified(
            self._samples, style.get("tolerance"), style["max_points"]
        )

    def extent(self) -> tuple[np.ndarray, np.ndarray] | None:
        """Lowest and highest recorded position (None when every sample is missing)."""
        return path_source.extent(self._samples)

    def refined(self, low, high, tolerance: float, max_points: int):
        """The line through the box ``[low, high]`` at ``tolerance``
        (:func:`~rbm_nb.scene.decimate.refine_region`)."""
        return path_source.refined(self._samples, low, high, tolerance, max_points)

    def shown_positions(self) -> np.ndarray:
        """The points drawn (every stretch, in order), shape (m, 3)."""
        stretches, _ = self.stretches()
        return np.vstack(stretches) if stretches else np.zeros((0, 3))

    def _objects(self):
        g = _geometry()
        stretches, _ = self.stretches()
        pts = segment_points(stretches)
        if len(pts) == 0:  # meshcat draws no line of no vertices: one empty segment
            pts = np.zeros((2, 3), np.float32)
        line = g.LineSegments(
            g.PointsGeometry(np.ascontiguousarray(pts.T)),
            g.LineBasicMaterial(color=color_int(self._style["color"])),
        )
        return [("", line)]

    def _extent(self):
        return self.shown_positions()


class PointsHandle(SceneHandle):
    """A static point cloud, or one point moving over time (a sphere)."""

    kind = "points"

    def __init__(
        self, scene, name, frame, base, style, points: np.ndarray, moving: bool
    ):
        super().__init__(scene, name, frame, base, style)
        self.points = points
        self.moving = moving

    def _validate_style(self, style):
        color_int(style["color"], "add_points: color")
        style["size"] = _positive(style["size"], "size", "add_points")

    def _objects(self):
        g = _geometry()
        color = color_int(self._style["color"])
        if self.moving:
            return [
                (
                    "",
                    g.Mesh(
                        g.Sphere(self._style["size"]),
                        g.MeshLambertMaterial(color=color),
                    ),
                )
            ]
        rgb = (
            np.array(
                [(color >> 16) & 255, (color >> 8) & 255, color & 255], dtype=np.float32
            )
            / 255
        )
        colors = np.repeat(rgb[:, np.newaxis], len(self.points), axis=1)
        cloud = g.Points(
            g.PointsGeometry(
                np.ascontiguousarray(self.points.T.astype(np.float32)), color=colors
            ),
            g.PointsMaterial(size=self._style["size"], color=color),
        )
        return [("", cloud)]

    def _extent(self):
        return self.points


class VectorsHandle(SceneHandle):
    """Vectors fixed in a frame (e.g. gaze rays), or one vector over time."""

    kind = "vectors"

    def __init__(self, scene, name, frame, base, style, vectors, origins, moving: bool):
        super().__init__(scene, name, frame, base, style)
        self.vectors = vectors
        self.origins = origins
        self.moving = moving

    def _validate_style(self, style):
        color_int(style["color"], "add_vectors: color")
        style["length"] = _positive(style["length"], "length", "add_vectors")

    def _objects(self):
        g = _geometry()
        if self.moving:
            # a segment along x; the data track turns it onto the vector and
            # scales it by the vector's norm
            segments = np.array([[0.0, 0.0, 0.0], [self._style["length"], 0.0, 0.0]])
        else:
            tips = self.origins + self.vectors * self._style["length"]
            segments = np.empty((2 * len(tips), 3))
            segments[0::2] = self.origins
            segments[1::2] = tips
        lines = g.LineSegments(
            g.PointsGeometry(np.ascontiguousarray(segments.T.astype(np.float32))),
            g.LineBasicMaterial(color=color_int(self._style["color"])),
        )
        return [("", lines)]

    def _extent(self):
        if self.moving:
            return np.zeros((1, 3))
        return np.vstack(
            [self.origins, self.origins + self.vectors * self._style["length"]]
        )


class MeshHandle(SceneHandle):
    """A mesh file or a primitive attached to a frame."""

    kind = "mesh"

    def __init__(self, scene, name, frame, base, style, mesh, size):
        super().__init__(scene, name, frame, base, style)
        self.mesh = mesh
        self.size = size
        self._geometry_object = mesh_geometry(mesh, size)

    def _validate_style(self, style):
        color_int(style["color"], "add_mesh: color")
        opacity = float(style["opacity"])
        if not 0 <= opacity <= 1:
            raise ValueError(
                f"add_mesh: opacity must be in [0, 1], got {style['opacity']}"
            )
        style["opacity"] = opacity
        style["scale"] = _positive(style["scale"], "scale", "add_mesh")

    def _objects(self):
        g = _geometry()
        material = g.MeshLambertMaterial(
            color=color_int(self._style["color"]), opacity=self._style["opacity"]
        )
        return [("", g.Mesh(self._geometry_object, material))]

    def _extent(self):
        # a cube around the mesh: primitives' sizes are at most this big
        half = float(np.max(self.size)) * self._style["scale"]
        return np.array([[-half, -half, -half], [half, half, half]])
