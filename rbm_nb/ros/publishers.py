"""The ROS publisher names of the reference API, drawing into a meshcat scene.

Without ROS there is no ``/tf`` topic and no RViz: these adapters keep the
constructor signatures and methods of the reference package's classes and
show what they would broadcast in a :class:`~rbm_nb.scene.Scene` (the shared
:func:`~rbm_nb.scene.default_scene` unless ``scene=`` is given), so the
visualisation cells of the ROS guide run unchanged. Display the scene with
``broadcaster.scene.show()``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..scene import scene as scene_module
from ..scene.publishers import FramePublisher, PathPublisher

if TYPE_CHECKING:
    from ..core.frames import FrameLike
    from ..scene.scene import Scene


class ReferenceFrameTransformBroadcaster(FramePublisher):
    """Publishes the transform of ``frame`` wrt ``base`` (default: its parent).

    Parameters
    ----------
    frame : str or ReferenceFrame
    base : str or ReferenceFrame, optional
    publish_pose : bool, default False
        Also draw the pose as an arrow along the frame's x axis.
    publish_twist : bool, default False
        Also compute the twist of the frame wrt ``base`` (represented in the
        frame), stored in ``linear`` and ``angular``.
    subscribe : bool or str, default False
        Publish the sample nearest in time whenever the base frame (or the
        frame named by the string) is published.
    twist_cutoff, twist_outlier_thresh : float, optional
        Passed to the twist lookup.
    scene : Scene, optional
        Where to draw (keyword only; not in the reference API).
    """

    def __init__(
        self,
        frame: FrameLike,
        base: FrameLike | None = None,
        publish_pose: bool = False,
        publish_twist: bool = False,
        subscribe: bool | str = False,
        twist_cutoff: float | None = None,
        twist_outlier_thresh: float | None = None,
        *,
        scene: Scene | None = None,
    ) -> None:
        super().__init__(
            frame, base, scene=scene, pose_arrow=publish_pose, subscribe=subscribe
        )
        self.linear = self.angular = None
        if publish_twist:
            self.linear, self.angular = self.frame.lookup_twist(
                reference=self.base,
                represent_in=self.frame,
                cutoff=twist_cutoff,
                outlier_thresh=twist_outlier_thresh,
            )


class ReferenceFrameMarkerPublisher(PathPublisher):
    """Publishes the translation of ``frame`` wrt ``base`` as a line marker.

    Parameters
    ----------
    frame : str or ReferenceFrame
    base : str or ReferenceFrame, optional
    topic : str, optional
        Kept for reference compatibility (default ``"/<frame>/path"``).
    max_points : int, default 1000
    publish_interval : float, default 0.0
    scale : float, default 0.1
        Kept for compatibility; line width is fixed in WebGL.
    color : str, default "#ffffff"
    verbose : bool, default False
    scene : Scene, optional
    """

    def __init__(
        self,
        frame: FrameLike,
        base: FrameLike | None = None,
        topic: str | None = None,
        max_points: int = 1000,
        publish_interval: float = 0.0,
        scale: float = 0.1,
        color: str = "#ffffff",
        verbose: bool = False,
        *,
        scene: Scene | None = None,
    ) -> None:
        super().__init__(
            frame,
            base,
            scene=scene,
            max_points=max_points,
            color=color,
            publish_interval=publish_interval,
        )
        self.topic = topic or f"/{self.frame.name}/path"
        self.scale = scale
        if verbose:
            print(f"created marker publisher on {self.topic}")


class NodeHandle:
    """What :func:`init_node` returns: a node name and a ``shutdown()`` that
    ends the publishers' threads of the default scene (there is no ROS master
    to stop)."""

    def __init__(self, name: str):
        self.name = name

    def shutdown(self) -> None:
        """Close the shared default scene, if any (idempotent)."""
        if scene_module._default is not None:
            scene_module._default.close()

    def __repr__(self) -> str:
        return f"<NodeHandle {self.name!r} (no ROS master needed)>"


def init_node(name: str, start_master: bool = False) -> NodeHandle:
    """Register a client node; kept so that the ROS guide's cells run.

    Nothing is started: the publishers of :mod:`rbm_nb.ros` draw into a meshcat
    scene in this process instead of talking to a ROS master.

    Parameters
    ----------
    name : str
        Name of the node.
    start_master : bool, default False
        Accepted for compatibility; there is no master to start.

    Returns
    -------
    NodeHandle
        Its ``shutdown()`` closes the default scene, like stopping the master
        ends what it served.
    """
    if not isinstance(name, str) or not name:
        raise ValueError(f"init_node: name must be a non-empty string, got {name!r}")
    return NodeHandle(name)
