"""What each ``Scene.add_*`` draws and where: its arguments checked and turned
into a handle and the tracks that place it.

A :class:`Placement` is a handle (the geometry and its style), the
``carrier`` track (the pose of the handle's frame in its base), an optional
``inner`` track (moving points and vectors: their own samples) and an
optional fixed ``offset`` of the geometry (meshes). The facade installs it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Generic, TypeVar

import numpy as np

from ..core import frames
from . import commands
from .anchors import Anchors
from .context import SceneContext
from .handles import (
    FrameHandle,
    MeshHandle,
    PathHandle,
    PointsHandle,
    SceneHandle,
    VectorsHandle,
    _points_array,
)
from .objects import SceneObjects
from .tracks import PoseTrack, SceneTrack

IDENTITY = np.array([1.0, 0.0, 0.0, 0.0])
H = TypeVar("H", bound=SceneHandle)


@dataclass
class Placement(Generic[H]):
    handle: H
    carrier: SceneTrack
    inner: SceneTrack | None = None
    offset: np.ndarray | None = None


class Placements:
    """Builds the placements of one scene's ``add_*`` calls (``owner``: the
    scene its handles report to)."""

    def __init__(
        self, owner, context: SceneContext, anchors: Anchors, objects: SceneObjects
    ):
        self._owner = owner
        self._context = context
        self._anchors = anchors
        self._objects = objects

    def _frame_and_base(self, frame, base, owner: str):
        self._context.check_open()
        frame = frames.resolve_frame(frame, f"{owner}: frame")
        if base is None:
            return frame, self._context.base
        return frame, frames.resolve_frame(base, f"{owner}: base")

    def _styled(self, cls: type[H], label, *args) -> H:
        handle = cls(self._owner, self._objects.new_name(label), *args)
        handle._validate_style(handle._style)
        return handle

    def frame(self, frame, base, scale, label) -> Placement[FrameHandle]:
        frame, base = self._frame_and_base(frame, base, "add_frame")
        handle = self._styled(
            FrameHandle, label or f"frame {frame.name}", frame, base, {"scale": scale}
        )
        return Placement(handle, self._anchors.pose(frame, base))

    def path(self, frame, base, style: dict, label) -> Placement[PathHandle]:
        frame, base = self._frame_and_base(frame, base, "add_path")
        track = self._anchors.pose(frame, base)
        if track.static:
            raise ValueError(
                f"add_path: frame {frame.name!r} does not move wrt {base.name!r}, it has no path"
            )
        handle = self._styled(
            PathHandle,
            label or f"path {frame.name}",
            frame,
            base,
            style,
            track,
        )
        return Placement(handle, PoseTrack(np.zeros(3), IDENTITY, name="path"))

    def points(
        self, points, frame, timestamps, style: dict, label
    ) -> Placement[PointsHandle]:
        base = self._context.base
        frame, _ = self._frame_and_base(
            frame if frame is not None else base, None, "add_points"
        )
        pts = _points_array(points, "points", "add_points")
        inner = None
        if timestamps is not None:
            identity = np.zeros((len(pts), 4))
            identity[:, 0] = 1.0
            inner = PoseTrack(pts, identity, timestamps, name="add_points: points")
        handle = self._styled(
            PointsHandle,
            label or f"points {frame.name}",
            frame,
            base,
            style,
            pts,
            inner is not None,
        )
        return Placement(handle, self._anchors.pose(frame, base), inner)

    def vectors(
        self, frame, vectors, origins, timestamps, base, style: dict, label
    ) -> Placement[VectorsHandle]:
        frame, base = self._frame_and_base(frame, base, "add_vectors")
        vecs = _points_array(vectors, "vectors", "add_vectors")
        origins_arr = _points_array(
            origins if origins is not None else np.zeros(3), "origins", "add_vectors"
        )
        inner = None
        if timestamps is not None:
            if len(origins_arr) != 1:
                raise ValueError(
                    "add_vectors: with timestamps, give one origin of shape (3,)"
                )
            norms = np.linalg.norm(vecs, axis=1)
            inner = PoseTrack(
                np.repeat(origins_arr, len(vecs), axis=0),
                rotations_from_x(vecs, norms),
                timestamps,
                scale=np.maximum(norms, 1e-12),
                name="add_vectors: vectors",
            )
        else:
            if len(origins_arr) == 1:
                origins_arr = np.repeat(origins_arr, len(vecs), axis=0)
            if origins_arr.shape != vecs.shape:
                raise ValueError(
                    f"add_vectors: origins must have shape (3,) or {vecs.shape}, got {origins_arr.shape}"
                )
        handle = self._styled(
            VectorsHandle,
            label or f"vectors {frame.name}",
            frame,
            base,
            style,
            vecs,
            origins_arr,
            inner is not None,
        )
        return Placement(handle, self._anchors.pose(frame, base), inner)

    def mesh(
        self, frame, mesh, base, size, offset, rotation, style: dict, label
    ) -> Placement[MeshHandle]:
        frame, base = self._frame_and_base(frame, base, "add_mesh")
        offset_t = _points_array(
            offset if offset is not None else np.zeros(3), "offset", "add_mesh"
        )[0]
        offset_r = np.asarray(
            rotation if rotation is not None else IDENTITY, dtype=float
        )
        if (
            offset_r.shape != (4,)
            or not np.isfinite(offset_r).all()
            or np.linalg.norm(offset_r) == 0
        ):
            raise ValueError(
                f"add_mesh: rotation must be a non-zero quaternion (4,), got {rotation!r}"
            )
        handle = self._styled(
            MeshHandle,
            label or f"mesh {frame.name}",
            frame,
            base,
            style,
            mesh,
            np.atleast_1d(np.asarray(size, dtype=float)),
        )
        return Placement(
            handle,
            self._anchors.pose(frame, base),
            offset=commands.pose_matrix(offset_t, offset_r),
        )


def rotations_from_x(vectors: np.ndarray, norms: np.ndarray) -> np.ndarray:
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
