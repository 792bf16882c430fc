"""Publishers with ROS semantics that draw into a :class:`~rbm_nb.scene.Scene`.

They mirror the reference package's tf broadcaster and marker publisher (see
:mod:`rbm_nb.ros.publishers` for the ROS names): ``publish(idx)`` shows sample
``idx`` of the frame's transform, ``spin()`` keeps publishing in a thread,
``stop()`` ends it. Instead of ``/tf`` messages, they move objects of a scene
(the shared :func:`~rbm_nb.scene.default_scene` unless one is given).
"""

from __future__ import annotations

import threading
import weakref

import numpy as np

from .._engine.time import time_key
from .scene import Scene, _resolve, default_scene
from .timekeys import KEYS_PER_SECOND
from .tracks import PoseTrack

# frame name -> publishers listening for it (``subscribe=``), per scene
_listeners: dict[tuple[int, str], list] = {}
_listeners_lock = threading.Lock()


def _notify(scene: Scene, frame_name: str, key: int | float | None) -> None:
    """Tell the subscribers of ``frame_name`` that it shows time ``key`` now."""
    with _listeners_lock:
        refs = list(_listeners.get((id(scene), frame_name), ()))
    for ref in refs:
        publisher = ref()
        if publisher is not None and not publisher.scene.closed:
            publisher._on_published(key)


class FramePublisher:
    """Shows the pose of ``frame`` wrt ``base`` in a scene, one sample at a time.

    Parameters
    ----------
    frame : str or ReferenceFrame
    base : str or ReferenceFrame, optional
        Defaults to the frame's parent.
    scene : Scene, optional
        Defaults to :func:`~rbm_nb.scene.default_scene`.
    scale : float, default 0.5
        Axis length of the triad.
    pose_arrow : bool, default False
        Also draw an arrow along the frame's x axis (a ROS ``PoseStamped``).
    subscribe : bool or str, default False
        Publish whenever a publisher of the base frame (or of the frame named
        by the string) publishes, with the sample nearest in time.

    Attributes
    ----------
    translation : ndarray, shape (n, 3) or (3,)
    rotation : ndarray, shape (n, 4) or (4,)
    timestamps : ndarray, shape (n,), or None for a static transform
    idx : int
        Sample published by ``publish()`` without an index.
    """

    def __init__(
        self,
        frame,
        base=None,
        *,
        scene: Scene | None = None,
        scale: float = 0.5,
        pose_arrow: bool = False,
        subscribe=False,
    ):
        self.frame = _resolve(frame, "FramePublisher: frame")
        if base is None:
            if self.frame.parent is None:
                raise ValueError(
                    f"FramePublisher: frame {self.frame.name!r} is a root; give a base frame"
                )
            base = self.frame.parent
        self.base = _resolve(base, "FramePublisher: base")
        self.scene = scene if scene is not None else default_scene(self.base)
        self.handle = self.scene.add_frame(self.frame, base=self.base, scale=scale)
        self.pose_handle = None
        if pose_arrow:
            self.pose_handle = self.scene.add_vectors(
                self.frame,
                (1.0, 0.0, 0.0),
                base=self.base,
                length=scale * 2,
                color="#ffff00",
                label=f"pose {self.frame.name}",
            )
        self._track = self.scene._track(self.handle.pose_path)
        if self._track is None:
            track = PoseTrack.lookup(self.frame, self.base)
            # no track at the pose's node: nothing on the chain moves
            assert isinstance(track, PoseTrack)
            self.translation, self.rotation, self.timestamps = (
                track.translation,
                track.rotation,
                None,
            )
            self._keys: np.ndarray | None = None
        else:
            # the publisher's own arrays (its API exposes them): the scene's
            # track looks its samples up per window and keeps none
            self._keys, self.translation, self.rotation, _ = self._track.take(None)
            self.timestamps = self._track.original_timestamps
        self.timestamps_kind = None if self._track is None else self._track.kind
        self.idx = 0
        self.stopped = True
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        if subscribe:
            target = subscribe if isinstance(subscribe, str) else self.base.name
            self.subscribe_to = target
            with _listeners_lock:
                _listeners.setdefault((id(self.scene), target), []).append(
                    weakref.ref(self)
                )
        else:
            self.subscribe_to = None

    def publish(self, idx: int | None = None) -> None:
        """Show sample ``idx`` (``self.idx`` by default) of the transform."""
        idx = self.idx if idx is None else idx
        key = None
        if self._track is not None:
            n = len(self._track)
            if (
                isinstance(idx, bool)
                or not isinstance(idx, (int, np.integer))
                or not -n <= idx < n
            ):
                raise IndexError(
                    f"{type(self).__name__}.publish: idx must be an integer in [0, {n - 1}], got {idx!r}"
                )
            idx = int(idx) % n
            for handle in (self.handle, self.pose_handle):
                if handle is not None:
                    key = self.scene._show_handle_index(handle, idx)
        self._published(key)

    def set_time(self, t) -> None:
        """Show the latest sample at or before ``t`` (for Player links)."""
        if self._track is None:
            self.publish()
            return

        key = time_key(t, self.timestamps_kind, f"{type(self).__name__}.set_time: t")
        idx = self._track.index_at(key)
        if idx >= 0:
            self.publish(idx)

    def _published(self, key: int | float | None) -> None:
        if key is not None:
            self.scene._sync_anchor(self.frame, key)
        _notify(self.scene, self.frame.name, key)

    def _on_published(self, key: int | float | None) -> None:
        keys = self._keys
        # (one scene's tracks share one kind of time: add_track checks it)
        if keys is None or key is None:
            self.publish()
            return
        # the nearest sample, compared exactly (Python ints for ns keys)
        idx = int(np.searchsorted(keys, key))
        if idx > 0 and (
            idx == len(keys) or key - keys[idx - 1].item() <= keys[idx].item() - key
        ):
            idx -= 1
        self.publish(idx)

    def spin(self, block: bool = False):
        """Keep publishing successive samples at the recorded rate.

        A static transform is published once. With ``subscribe`` the publisher
        only reacts to its subscription (``block=True`` then waits for
        :meth:`stop`).

        Returns
        -------
        threading.Thread or None
            The thread running the loop (``block=False``).
        """
        if self._track is None:
            self.publish()
            return None
        self._stop = threading.Event()
        self.stopped = False
        keys = self._track.sample_keys()
        if block:
            self._loop(self._stop, keys)
            return None
        self._thread = threading.Thread(
            target=self._loop,
            args=(self._stop, keys),
            daemon=True,
            name=f"rbm_nb-{type(self).__name__}",
        )
        self._thread.start()
        return self._thread

    def _loop(self, stop: threading.Event, keys: np.ndarray) -> None:
        per_second = KEYS_PER_SECOND[self.timestamps_kind or "numeric"]
        try:
            if self.subscribe_to is not None:
                stop.wait()
                return
            while not stop.is_set():
                self.publish()
                nxt = (self.idx + 1) % len(keys)
                dt = (keys[nxt] - keys[self.idx]) / per_second if nxt > 0 else 0.0
                self.idx = nxt
                stop.wait(max(float(dt), 0.0))
        finally:
            self.stopped = True

    def stop(self) -> None:
        """Stop :meth:`spin` (and stop reacting to subscriptions)."""
        self._stop.set()
        thread = self._thread
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout=10)
        self.stopped = True


class PathPublisher:
    """Shows the path of ``frame`` in ``base`` as a line in a scene.

    The line appears on the first ``publish()`` (like a latched marker).

    Parameters
    ----------
    frame : str or ReferenceFrame
    base : str or ReferenceFrame, optional
        Defaults to the frame's parent.
    scene : Scene, optional
    max_points : int, default 1000
    color : str, default "#ffffff"
    publish_interval : float, default 0.0
        Seconds between publications in :meth:`spin`.
    """

    def __init__(
        self,
        frame,
        base=None,
        *,
        scene: Scene | None = None,
        max_points: int = 1000,
        color="#ffffff",
        publish_interval: float = 0.0,
    ):
        self.frame = _resolve(frame, "PathPublisher: frame")
        if base is None:
            if self.frame.parent is None:
                raise ValueError(
                    f"PathPublisher: frame {self.frame.name!r} is a root; give a base frame"
                )
            base = self.frame.parent
        self.base = _resolve(base, "PathPublisher: base")
        if not (np.isfinite(publish_interval) and publish_interval >= 0):
            raise ValueError(
                f"PathPublisher: publish_interval must be >= 0, got {publish_interval!r}"
            )
        self.publish_interval = float(publish_interval)
        self.scene = scene if scene is not None else default_scene(self.base)
        self.handle = self.scene.add_path(
            self.frame, base=self.base, color=color, max_points=max_points
        )
        self.handle.visible = False
        self.translation = self.handle.positions
        self.stopped = True
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    @property
    def points(self) -> np.ndarray:
        """The (subsampled) points of the line, shape (m, 3)."""
        return self.handle.shown_positions()

    def publish(self, idx: int | None = None) -> None:
        """Show the path (``idx`` is accepted for Player links and ignored)."""
        if not self.handle.visible:
            self.handle.visible = True

    def spin(self, block: bool = False):
        """Publish every ``publish_interval`` seconds until :meth:`stop`."""
        self._stop = threading.Event()
        self.stopped = False
        if block:
            self._loop(self._stop)
            return None
        self._thread = threading.Thread(
            target=self._loop,
            args=(self._stop,),
            daemon=True,
            name="rbm_nb-PathPublisher",
        )
        self._thread.start()
        return self._thread

    def _loop(self, stop: threading.Event) -> None:
        try:
            while not stop.is_set():
                self.publish()
                stop.wait(self.publish_interval or 0.1)
        finally:
            self.stopped = True

    def stop(self) -> None:
        """Stop :meth:`spin`."""
        self._stop.set()
        thread = self._thread
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout=10)
        self.stopped = True
