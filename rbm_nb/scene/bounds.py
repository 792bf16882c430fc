"""How far a scene's objects reach: the box the grid and the camera fit.

An object's extent is its geometry (points in its frame) placed along its
pose track, then moved along its anchor's track. Tracks of hours have
millions of samples: each is summarised once (:attr:`PoseTrack.bounds`, cached
on the track) and only those summaries are combined here, so refitting the
grid after each ``add_*`` copies no track.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .handles import PathHandle, PointsHandle, SceneHandle
from .state import SceneState
from .tracks import SceneTrack

#: largest distance from the scene's origin (metres) an object may reach: far
#: beyond any tracked volume, far inside float32 (the browser's numbers) and
#: the grid's and camera's arithmetic
MAX_COORDINATE = 1e9


@dataclass(frozen=True)
class Bounds:
    """Lowest, highest and mean of ``count`` points, shape (3,) each."""

    low: np.ndarray
    high: np.ndarray
    mean: np.ndarray
    count: int

    @classmethod
    def of_points(cls, points) -> Bounds | None:
        """Of an array of shape (n, 3) (None when n is 0)."""
        points = np.asarray(points, dtype=float).reshape(-1, 3)
        if len(points) == 0:
            return None
        return cls(
            points.min(axis=0), points.max(axis=0), points.mean(axis=0), len(points)
        )

    @classmethod
    def of_track(cls, track: SceneTrack) -> Bounds | None:
        """The track's samples that are not missing (None when all are)."""
        summary = track.bounds
        return None if summary is None else cls(*summary)

    def shifted(self, offset: np.ndarray) -> Bounds:
        return Bounds(
            self.low + offset, self.high + offset, self.mean + offset, self.count
        )

    def union(self, other: Bounds) -> Bounds:
        count = self.count + other.count
        mean = (self.mean * self.count + other.mean * other.count) / count
        return Bounds(
            np.minimum(self.low, other.low),
            np.maximum(self.high, other.high),
            mean,
            count,
        )

    def reach(self) -> float:
        """Largest absolute coordinate."""
        return float(max(np.max(np.abs(self.low)), np.max(np.abs(self.high))))


def _reach(bounds: Bounds | None) -> float:
    return 0.0 if bounds is None else bounds.reach()


def _track_reach(track: SceneTrack | None) -> float:
    return _reach(None if track is None else Bounds.of_track(track))


def check_reach(
    handle: SceneHandle,
    carrier: SceneTrack,
    inner: SceneTrack | None,
    anchor: SceneTrack,
) -> None:
    """Refuse an object reaching beyond :data:`MAX_COORDINATE` from the origin.

    ``carrier`` places it in its base, ``inner`` moves it there (moving
    points and vectors), ``anchor`` places its base in the scene's.
    """
    reach = _reach(Bounds.of_points(handle._extent()))
    reach += _track_reach(carrier) + _track_reach(inner) + _track_reach(anchor)
    if not reach <= MAX_COORDINATE:
        raise ValueError(
            f"add_{handle.kind}: {handle.name!r} reaches {reach:.3g} m from the "
            f"scene's origin; the 3D view draws within {MAX_COORDINATE:.0e} m "
            "(check the values and their units)"
        )


def handle_bounds(
    handle: SceneHandle, state: SceneState, anchor: SceneTrack | None
) -> Bounds | None:
    """Where ``handle`` reaches in the scene's base, roughly: its geometry at
    the mean of its pose, and every position its pose and its anchor take."""
    track = state.tracks.get(handle.pose_path)
    if track is None:
        origins = Bounds.of_points(state.static_pose(handle.pose_path)[:3, 3])
    else:
        origins = Bounds.of_track(track)
    if origins is None:  # every sample missing: nothing is ever drawn
        return None
    geometry = Bounds.of_points(handle._extent())
    if geometry is not None:
        geometry = geometry.shifted(origins.mean)
    if isinstance(handle, PathHandle) or (
        isinstance(handle, PointsHandle) and not handle.moving
    ):
        points = geometry  # the geometry is the data
    else:
        points = origins if geometry is None else origins.union(geometry)
    if points is None or anchor is None:
        return points
    moves = Bounds.of_track(anchor)
    return None if moves is None else moves.shifted(points.mean)


def scene_bounds(handles, state: SceneState, anchor_of) -> Bounds | None:
    """The box of every handle (``anchor_of(handle)``: its anchor's track or
    None); None for an empty scene."""
    total: Bounds | None = None
    for handle in handles:
        bounds = handle_bounds(handle, state, anchor_of(handle))
        if bounds is not None:
            total = bounds if total is None else total.union(bounds)
    return total
