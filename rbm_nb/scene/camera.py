"""Where the scene's camera stands and what it looks at.

The camera is fitted to the content until the user places it
(:meth:`Scene.set_camera`, :meth:`Scene.focus`); a fitted camera is refitted
when the content changes, a placed one stays. Following a frame as it moves
happens in the browser (the widget's ``follow``); the kernel only checks
that the frame is drawn.
"""

from __future__ import annotations

import math

import numpy as np

from .bounds import MAX_COORDINATE, Bounds
from .handles import _points_array
from .objects import SceneObjects
from .state import SceneState
from .timekeys import seconds_from

#: the direction the camera looks from (towards -x, +y, -z: the usual 3/4 view)
VIEW_DIRECTION = np.array([1.0, -1.4, 1.0]) / np.linalg.norm([1.0, -1.4, 1.0])


def camera_distance(value) -> float:
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


def _reach(point: np.ndarray) -> float:
    return float(np.max(np.abs(point)))


class Camera:
    """The camera of one scene: ``value`` (the widget's ``_camera``) and
    whether it follows the content (``auto``)."""

    def __init__(self):
        self.value: dict | None = None
        self.auto = True

    def place(self, position, target, *, auto: bool) -> None:
        self.value = {
            "position": [float(v) for v in position],
            "target": [float(v) for v in target],
        }
        self.auto = auto

    def fit(self, bounds: Bounds | None) -> None:
        """Look at the whole box ``bounds`` (the origin's surroundings if None)."""
        low = np.zeros(3) if bounds is None else bounds.low
        high = np.zeros(3) if bounds is None else bounds.high
        target = (low + high) / 2
        radius = max(float(np.linalg.norm(high - low)) / 2, 1.0)
        self.place(target + VIEW_DIRECTION * radius * 1.7, target, auto=True)

    def set(self, position, target) -> None:
        """Place the camera where the user says (checked)."""
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
        self.place(p, t, auto=False)

    def focus(self, name: str, objects: SceneObjects, state: SceneState, key, distance):
        """Look at the frame ``name`` (drawn in ``objects``) as it is at time
        ``key`` (the scene's exact key), from ``distance`` metres (ten times
        its triad's size by default)."""
        objects.drawn(name, "Scene.focus")
        paths = objects.frame_paths()
        if distance is None:
            distance = 10.0 * objects.triad_at(paths[name]).style["scale"]
        distance = camera_distance(distance)
        pose = state.world_pose(paths[name], key)
        if pose is None:  # not started yet or missing now: where it is last
            pose = state.world_pose(paths[name], math.inf)
        if pose is None:
            seconds = float(seconds_from(state.base, np.array([key]))[0])
            raise ValueError(
                f"Scene.focus: frame {name!r} has no pose at the time shown "
                f"({seconds:g} s from the first sample) "
                "nor at its last sample: its samples there are missing"
            )
        target = pose[:3, 3]
        self.place(target + VIEW_DIRECTION * distance, target, auto=False)
