"""matplotlib plots of frames, points, orientations, vectors and trajectories.

``reference_frame``, ``points``, ``quaternions`` and ``vectors`` keep the
signatures and return values of the reference package's ``plot`` module (3-D
axes, equal scaling); ``trajectory`` plots a frame's position and orientation
over time.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt
from matplotlib.patches import FancyArrowPatch
from mpl_toolkits.mplot3d import Axes3D, proj3d

from .._door import shapes as _shapes
from .._door.lookups import reference_or_parent
from .._infra.config import UNIT_QUATERNION_TOLERANCE
from .._kernels import conversions as _kc
from .frames import resolve_frame
from .lookups import lookup_pose, lookup_transform

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from .frames import FrameLike

__all__ = [
    "Arrow3D",
    "reference_frame",
    "points",
    "quaternions",
    "vectors",
    "trajectory",
]


class Arrow3D(FancyArrowPatch):
    """An arrow between two 3-D points, projected when the axes are drawn.

    Parameters
    ----------
    xs, ys, zs : sequence of two floats
        Coordinates of the tail and the head.
    """

    def __init__(
        self,
        xs: npt.ArrayLike,
        ys: npt.ArrayLike,
        zs: npt.ArrayLike,
        *args: Any,
        **kwargs: Any,
    ) -> None:
        super().__init__((0.0, 0.0), (0.0, 0.0), *args, **kwargs)
        self._verts3d = (
            np.asarray(xs, float),
            np.asarray(ys, float),
            np.asarray(zs, float),
        )

    @property
    def tail(self) -> np.ndarray:
        """Tail point, shape (3,)."""
        return np.array([v[0] for v in self._verts3d])

    @property
    def head(self) -> np.ndarray:
        """Head point, shape (3,)."""
        return np.array([v[1] for v in self._verts3d])

    def do_3d_projection(self, renderer: Any = None) -> float:
        axes = self.axes
        if not isinstance(axes, Axes3D):
            raise TypeError(f"an Arrow3D is drawn on 3-D axes, not on {axes!r}")
        xs, ys, zs = proj3d.proj_transform(*self._verts3d, axes.M)
        self.set_positions((xs[0], ys[0]), (xs[1], ys[1]))
        return float(np.min(zs))


def _axes_3d(ax, figsize):
    if ax is not None:
        if getattr(ax, "name", "") != "3d":
            raise ValueError(
                "ax must be a 3-D axes, e.g. fig.add_subplot(111, projection='3d')"
            )
        return ax
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=figsize)
    return fig.add_subplot(111, projection="3d")


def _grow_limits(ax, pts: np.ndarray) -> None:
    """Extend the axis limits so that ``pts`` (n, 3) are inside."""
    pts = pts[np.isfinite(pts).all(axis=1)]
    if len(pts) == 0:
        return
    # a fresh 3-D axes has limits (0, 1) that no data set; ignore them
    fresh = not getattr(ax, "_rbm_has_data", False) and not ax.has_data()
    for i, (get, set_) in enumerate(
        (
            (ax.get_xlim3d, ax.set_xlim3d),
            (ax.get_ylim3d, ax.set_ylim3d),
            (ax.get_zlim3d, ax.set_zlim3d),
        )
    ):
        low, high = pts[:, i].min(), pts[:, i].max()
        if not fresh:
            old = get()
            low, high = min(low, old[0]), max(high, old[1])
        set_((low, high))
    ax._rbm_has_data = True


def _set_axes_equal(ax) -> None:
    """Same scale on all three axes: a cube around the current limits."""
    limits = np.array([ax.get_xlim3d(), ax.get_ylim3d(), ax.get_zlim3d()])
    centers = limits.mean(axis=1)
    radius = 0.5 * np.max(limits[:, 1] - limits[:, 0])
    if radius == 0:
        radius = 0.5
    ax.set_xlim3d(centers[0] - radius, centers[0] + radius)
    ax.set_ylim3d(centers[1] - radius, centers[1] + radius)
    ax.set_zlim3d(centers[2] - radius, centers[2] + radius)


def _rotation_matrices(q: np.ndarray) -> np.ndarray:
    """(n, 3, 3) rotation matrices of (n, 4) finite, non-zero quaternions
    (w, x, y, z): a frame's, or checked by ``_door.shapes.triads``."""
    q = np.array(q, dtype=np.float64, order="C").reshape(-1, 4)
    # any non-zero norm is accepted here (the kernel normalises); its
    # validity count against the unit tolerance is not needed
    matrices, _ = _kc.matrix_from_quaternion(q, UNIT_QUATERNION_TOLERANCE)
    return matrices


def reference_frame(
    frame: FrameLike,
    world_frame: FrameLike | None = None,
    ax: Axes3D | None = None,
    figsize: tuple[float, float] = (6, 6),
    arrow_len: float = 1.0,
) -> list[Arrow3D]:
    """Plot a static reference frame as three arrows (x red, y green, z blue).

    Parameters
    ----------
    frame : str or ReferenceFrame
        The frame to plot, or the name of a registered frame.
    world_frame : str or ReferenceFrame, optional
        The frame whose origin is the origin of the plot. Without it the frame
        is drawn at the origin with its axes along the plot's.
    ax : mpl_toolkits.mplot3d.Axes3D, optional
        Axes to draw on; a new figure of ``figsize`` otherwise.
    figsize : tuple, default (6, 6)
    arrow_len : float, default 1.0
        Length of the arrows.

    Returns
    -------
    arrows : list of Arrow3D
        The x, y and z arrows.

    Raises
    ------
    ValueError
        If the frame (or its transform into ``world_frame``) moves.
    """
    frame = resolve_frame(frame, "reference_frame: frame")
    if frame.timestamps is not None:
        raise ValueError(
            f"plot.reference_frame: frame {frame.name!r} is moving; "
            "plot it over time with plot.trajectory"
        )
    if not (np.isfinite(arrow_len) and arrow_len > 0):
        raise ValueError(f"arrow_len must be a positive number, got {arrow_len!r}")
    ax = _axes_3d(ax, figsize)
    corners = np.array(
        [[0.0, 0.0, 0.0], [arrow_len, 0, 0], [0, arrow_len, 0], [0, 0, arrow_len]]
    )
    if world_frame is not None:
        world = resolve_frame(world_frame, "reference_frame: world_frame")
        t, r, ts = lookup_transform(outof=frame, into=world, return_timestamps=True)
        if ts is not None:
            raise ValueError(
                f"plot.reference_frame: the transform of {frame.name!r} into {world.name!r} moves; "
                "only static frames can be drawn here"
            )
        corners = corners @ _rotation_matrices(np.asarray(r).reshape(1, 4))[
            0
        ].T + np.asarray(t).reshape(3)
    origin = corners[0]
    style = dict(mutation_scale=20, arrowstyle="-|>", shrinkA=0, shrinkB=0)
    arrows = []
    for tip, color in zip(corners[1:], ("r", "g", "b"), strict=True):
        arrow = Arrow3D(
            [origin[0], tip[0]],
            [origin[1], tip[1]],
            [origin[2], tip[2]],
            color=color,
            **style,
        )
        ax.add_artist(arrow)
        arrows.append(arrow)
    _grow_limits(ax, corners)
    _set_axes_equal(ax)
    return arrows


def points(
    arr: npt.ArrayLike,
    ax: Axes3D | None = None,
    figsize: tuple[float, float] = (6, 6),
    fmt: str = "",
    **kwargs: Any,
) -> list[Any]:
    """Plot 3-D points.

    Parameters
    ----------
    arr : array_like, shape (3,) or (N, 3)
    ax : Axes3D, optional
    figsize : tuple, default (6, 6)
    fmt : str, optional
        A matplotlib format string, e.g. ``"yo-"``.
    **kwargs
        Passed to ``ax.plot``.

    Returns
    -------
    lines : list of Line3D
    """
    arr = _shapes.one_or_many(arr, "points: arr", 3)
    ax = _axes_3d(ax, figsize)
    lines = ax.plot(arr[:, 0], arr[:, 1], arr[:, 2], fmt, **kwargs)
    _grow_limits(ax, arr)
    _set_axes_equal(ax)
    return lines


def vectors(
    arr: npt.ArrayLike,
    base: npt.ArrayLike | None = None,
    ax: Axes3D | None = None,
    figsize: tuple[float, float] = (6, 6),
    **kwargs: Any,
) -> Any:
    """Plot 3-D vectors as arrows.

    Parameters
    ----------
    arr : array_like, shape (3,) or (N, 3)
    base : array_like, shape (3,) or (N, 3), optional
        Tails of the vectors (the origin by default).
    ax : Axes3D, optional
    figsize : tuple, default (6, 6)
    **kwargs
        Passed to ``ax.quiver``.

    Returns
    -------
    lines : Line3DCollection
    """
    arr, tails = _shapes.with_tails(arr, base, "vectors", 3)
    return _arrows(_axes_3d(ax, figsize), arr, tails, **kwargs)


def _arrows(ax: Axes3D, arr: np.ndarray, tails: np.ndarray, **kwargs: Any) -> Any:
    """Arrows ``arr`` (N, 3) from ``tails`` (N, 3), checked, on ``ax``."""
    lines = ax.quiver(
        tails[:, 0], tails[:, 1], tails[:, 2], arr[:, 0], arr[:, 1], arr[:, 2], **kwargs
    )
    length = float(kwargs.get("length", 1.0))
    _grow_limits(ax, np.vstack([tails, tails + arr * length]))
    _set_axes_equal(ax)
    return lines


def quaternions(
    arr: npt.ArrayLike,
    base: npt.ArrayLike | None = None,
    ax: Axes3D | None = None,
    figsize: tuple[float, float] = (6, 6),
    **kwargs: Any,
) -> list[Any]:
    """Plot orientations as small triads (x red, y green, z blue, length 0.5).

    Parameters
    ----------
    arr : array_like, shape (4,) or (N, 4)
        Quaternions (w, x, y, z).
    base : array_like, shape (3,) or (N, 3), optional
        Positions of the triads (the origin by default).
    ax : Axes3D, optional
    figsize : tuple, default (6, 6)
    **kwargs
        Passed to ``ax.quiver``.

    Returns
    -------
    lines : list of Line3DCollection
        The x, y and z arrows.
    """
    q, tails = _shapes.triads(arr, base, "quaternions")
    axes = _rotation_matrices(q)  # columns are the rotated unit axes
    kwargs.setdefault("length", 0.5)
    ax = _axes_3d(ax, figsize)
    return [
        _arrows(ax, np.ascontiguousarray(axes[:, :, i]), tails, color=color, **kwargs)
        for i, color in enumerate(("r", "g", "b"))
    ]


def _roll_pitch_yaw(q: np.ndarray) -> np.ndarray:
    """(n, 3) roll, pitch, yaw in degrees (z-y'-x'' sequence)."""
    q = q / np.linalg.norm(q, axis=1)[:, np.newaxis]
    w, x, y, z = q.T
    roll = np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = np.arcsin(np.clip(2 * (w * y - z * x), -1, 1))
    yaw = np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return np.degrees(np.unwrap(np.column_stack([roll, pitch, yaw]), axis=0))


def trajectory(
    frame: FrameLike,
    reference: FrameLike | None = None,
    axes: Sequence[Axes] | None = None,
    figsize: tuple[float, float] = (8, 6),
    **kwargs: Any,
) -> list[Axes]:
    """Plot the position and orientation of a frame over time.

    Parameters
    ----------
    frame : str or ReferenceFrame
    reference : str or ReferenceFrame, optional
        The frame the pose is expressed in; the parent by default.
    axes : sequence of two matplotlib Axes, optional
        Axes for position and orientation; a new figure otherwise.
    figsize : tuple, default (8, 6)
    **kwargs
        Passed to ``ax.plot``.

    Returns
    -------
    axes : list of two Axes
        Position (x, y, z in m) and orientation (roll, pitch, yaw in degrees,
        unwrapped) against time.
    """

    frame = resolve_frame(frame, "trajectory: frame")
    reference = resolve_frame(
        reference_or_parent(frame, reference, "trajectory: "), "trajectory: reference"
    )
    position, orientation, ts = lookup_pose(frame, reference, return_timestamps=True)
    if ts is None:
        raise ValueError(
            f"trajectory: frame {frame.name!r} does not move wrt {reference.name!r}; "
            "use plot.reference_frame for static frames"
        )
    position = np.asarray(position, dtype=float)
    angles = _roll_pitch_yaw(np.asarray(orientation, dtype=float))
    if axes is None:
        import matplotlib.pyplot as plt

        _, axes = plt.subplots(2, 1, sharex=True, figsize=figsize)
    if len(axes) != 2:
        raise ValueError(f"trajectory: axes must be two Axes, got {len(axes)}")
    ax_p, ax_o = axes
    for i, label in enumerate("xyz"):
        ax_p.plot(ts, position[:, i], label=label, **kwargs)
    for i, label in enumerate(("roll", "pitch", "yaw")):
        ax_o.plot(ts, angles[:, i], label=label, **kwargs)
    ax_p.set_ylabel("Position (m)")
    ax_p.set_title(f"{frame.name} wrt {reference.name}")
    ax_o.set_ylabel("Orientation (\u00b0)")
    ax_o.set_xlabel(
        "Time" if np.issubdtype(np.asarray(ts).dtype, np.datetime64) else "Time (s)"
    )
    for ax in axes:
        ax.legend(loc="upper left")
        ax.grid(True)
    return list(axes)
