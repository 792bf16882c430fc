"""The explorer's frame tree: its names, constants and registration.

Part of :mod:`rbm_nb.app.explorer` (which re-exports every name here): the
frames of the example head/eye recording as guide 1.6 of rigid-body-motion
builds them (see that module's docstring for the tree), the names the
explorer draws and plots (:class:`HeadEyeFrames`), and
:func:`register_head_eye_frames`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..core import frames
from ..core.frames import ReferenceFrame

# rotation between the T265's VR axes and ROS axes (guide 1.6)
R_T265_ROS = np.array([[0.0, 0.0, -1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
# rotation between the Pupil Core's camera axes (x right, y down, z forward)
# and ROS axes (guide 1.6)
R_PUPIL_ROS = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]])
# pose of the Pupil Core scene camera on the T265, from the study's calibration.
# The calibration's quaternion is printed in (x, y, z, w) order, as scipy and
# ROS write them; guide 1.6 of rigid-body-motion passes the same four numbers
# as (w, x, y, z), which turns the camera 180 deg about its line of sight
# (about the T265's x axis instead of its y axis). Read that way, the eyes of
# the real recording move *with* the head at 40 ms (gain +0.6 to +0.7 against
# the head's yaw and pitch rates) and look away from every turn; read as
# (x, y, z, w) they counter-rotate as the vestibulo-ocular reflex does (gain
# -0.6 to -0.7), look into turns, and still converge (+2 deg): see
# tests/data/test_eye_frames.py, which measures all of this.
SCENE_CAM_TRANSLATION = (24.5e-3, -29e-3, 0.0)
SCENE_CAM_ROTATION_XYZW = (-0.00125, -1.0, 6.3463e-05, 3.977e-06)
SCENE_CAM_ROTATION = (
    SCENE_CAM_ROTATION_XYZW[3],
    *SCENE_CAM_ROTATION_XYZW[:3],
)
EYES = ("left_eye", "right_eye")


class HeadEyeFrames(NamedTuple):
    """The registered frames the explorer draws and plots, by name.

    ``head`` has robotics axes (x forward, y left, z up: yaw is about z,
    gaze yaw is positive to the left); each eye frame's z axis is its line
    of sight. Give your own names to :func:`dashboard` (``frames=``) to
    explore any tree registered with those conventions.
    """

    world: str = "world"
    head: str = "head"
    left_eye: str = "pupil/left_eye"
    right_eye: str = "pupil/right_eye"

    def eye(self, name: str) -> str:
        """The frame of ``"left_eye"`` or ``"right_eye"``."""
        return self.left_eye if name == "left_eye" else self.right_eye


#: the names :func:`register_head_eye_frames` registers
EXAMPLE_FRAMES = HeadEyeFrames()
# Pupil Core's usual threshold: below it the pupil detection is not trusted
MIN_CONFIDENCE = 0.6
# the eye tracker's gaps longer than this are not bridged by interpolation
# (the eye frames') nor drawn across (the plots': their series say so in
# attrs["max_gap"], instead of a NaN row inserted in each pause, which
# would make a new copy of every eye timestamp)
MAX_EYE_GAP = 0.1
# per eye, the same in the 3D view and the plots (legible on both)
GAZE_COLORS = {"left_eye": "#e69f00", "right_eye": "#0094d6"}
# samples per plotted panel and per moving object in exports: 10000 over the
# 5.5 minutes is 30 per second, with every stretch's extremes kept; the page
# stays under 5 MB
PLOT_MAX_POINTS = 10000


def _unconfident(eye, min_confidence: float | None):
    """The rows of ``eye`` below ``min_confidence`` (bool, one per sample), or None.

    The frame treats them as missing (NaN) and keeps the recording's own
    arrays beside this mask where nobody can write them (the loaders' are
    read-only): no masked copies of the eye's pose.
    """
    if min_confidence is None or "confidence" not in eye:
        return None
    low = (eye.confidence < min_confidence).values
    return low if low.any() else None


def register_head_eye_frames(
    head,
    left_eye,
    right_eye,
    *,
    world: str = "world",
    ros_eyes: bool = False,
    min_confidence: float | None = MIN_CONFIDENCE,
    max_gap: float | None = MAX_EYE_GAP,
):
    """Register the explorer's frame tree (see the module docstring).

    ``world`` is registered as a root if it is not already. Existing frames of
    the same names are replaced, so the cell can be run again. With
    ``ros_eyes`` each eye also gets a frame in ROS axes below it
    (``left_eye``, ``right_eye``: x along the line of sight), as in guide 1.6.

    The eye frames keep the recording's missing samples (blinks, lost
    pupils) as missing, and samples below ``min_confidence`` become missing
    too; with ``max_gap`` (seconds) nothing is interpolated across longer
    gaps. So a gaze ray is drawn only where the eye tracker saw the pupil.
    ``min_confidence=None`` keeps every sample that has data.
    """
    if world not in frames.registry:
        frames.register_frame(world)
    ReferenceFrame.from_rotation_matrix(
        R_T265_ROS, parent=world, name="t265/world"
    ).register(update=True)
    ReferenceFrame.from_dataset(
        head,
        "position",
        "orientation",
        "time",
        parent="t265/world",
        name="t265/tracker",
    ).register(update=True)
    ReferenceFrame.from_rotation_matrix(
        R_T265_ROS, parent="t265/tracker", name="head", inverse=True
    ).register(update=True)
    frames.register_frame(
        "pupil/scene_cam",
        parent="t265/tracker",
        translation=SCENE_CAM_TRANSLATION,
        rotation=SCENE_CAM_ROTATION,
        update=True,
    )
    for name, eye in zip(EYES, (left_eye, right_eye), strict=True):
        ReferenceFrame.from_dataset(
            eye,
            "position",
            "orientation",
            "time",
            parent="pupil/scene_cam",
            name=f"pupil/{name}",
            max_gap=max_gap,
            missing=_unconfident(eye, min_confidence),
        ).register(update=True)
        if ros_eyes:
            ReferenceFrame.from_rotation_matrix(
                R_PUPIL_ROS, parent=f"pupil/{name}", name=name
            ).register(update=True)
