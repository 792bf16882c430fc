"""What the FrameTree's details panel says, as plain data.

The panel is rendered from these frozen dataclasses (:func:`details_html`,
:func:`details_text`); tests and callers read the fields instead of parsing
HTML. Nothing here imports ipywidgets.

Attitudes are shown twice: as the unit quaternion ``(w, x, y, z)`` (with
``w >= 0``; ``q`` and ``-q`` are the same rotation) and as Euler angles of
the intrinsic z-y'-x'' sequence (``EULER_ORDER``): the rotation is
``Rz(yaw) @ Ry(pitch) @ Rx(roll)``, pitch in [-90°, 90°]. At gimbal lock
(pitch ±90°) only yaw ∓ roll is defined; roll is then 0 and yaw carries the
rotation, as :func:`rbm_nb.conversions.euler_from_quaternion` documents.
"""

from __future__ import annotations

import html
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..core.conversions import euler_from_quaternion

#: Euler sequence of the details: intrinsic z-y'-x'' (yaw, pitch, roll).
EULER_ORDER = "zyx"
EULER_NAMES = ("yaw", "pitch", "roll")
ARROW = " \u2192 "


@dataclass(frozen=True)
class Attitude:
    """A rotation as a quaternion and as yaw, pitch, roll.

    Attributes
    ----------
    quaternion : tuple of 4 float
        Unit quaternion ``(w, x, y, z)`` with ``w >= 0``.
    euler : tuple of 3 float
        Yaw, pitch, roll in degrees (``EULER_ORDER``, intrinsic).
    """

    quaternion: tuple[float, float, float, float]
    euler: tuple[float, float, float]

    @classmethod
    def of(cls, q) -> Attitude:
        """The attitude of quaternion ``q`` (w, x, y, z), normalised.

        Raises
        ------
        ValueError
            If ``q`` is not a finite 4-vector of nonzero norm.
        """
        q = np.asarray(q, dtype=float)
        norm = float(np.linalg.norm(q)) if q.shape == (4,) else 0.0
        if q.shape != (4,) or not np.isfinite(q).all() or norm == 0.0:
            raise ValueError(
                f"Attitude.of: need a finite nonzero quaternion (w, x, y, z), got {q!r}"
            )
        q = q / norm
        if q[0] < 0:
            q = -q
        euler = euler_from_quaternion(q, EULER_ORDER, degrees=True)
        return cls(
            tuple(float(v) + 0.0 for v in q),  # type: ignore[arg-type]
            tuple(float(v) + 0.0 for v in euler),  # type: ignore[arg-type]
        )

    def euler_text(self) -> str:
        """``yaw 90.00°, pitch 90.00°, roll 0.00°``."""
        return ", ".join(
            f"{name} {_angle(v):.2f}\u00b0"
            for name, v in zip(EULER_NAMES, self.euler, strict=True)
        )

    def quaternion_text(self) -> str:
        """``(w, x, y, z) = (0.5, -0.5, 0.5, 0.5)``."""
        return "(w, x, y, z) = " + _vector(self.quaternion)


@dataclass(frozen=True)
class Pose:
    """A pose shown in the details, or why none is shown.

    Attributes
    ----------
    what : str
        ``"wrt parent"`` or ``"of a in b"``.
    translation : tuple of 3 float or None
        Metres; None when the pose is not defined at the shown time.
    attitude : Attitude or None
    when : str
        ``"static"``, the time of the sample shown (the shared readout),
        ``"not defined before <time>"``, or, where a sample the pose needs
        is missing (a NaN row: a blink, a lost pupil), ``"no sample of
        <frame> at <time> (missing: <why>)"``.
    """

    what: str
    translation: tuple[float, float, float] | None
    attitude: Attitude | None
    when: str

    @classmethod
    def sample(cls, what: str, translation, rotation, when: str) -> Pose:
        return cls(
            what,
            tuple(float(v) for v in translation),  # type: ignore[arg-type]
            Attitude.of(rotation),
            when,
        )


@dataclass(frozen=True)
class FrameDetails:
    """One selected frame."""

    name: str
    summary: str
    parent: str | None
    children: tuple[str, ...]
    path: tuple[str, ...]
    pose: Pose | None


@dataclass(frozen=True)
class PairDetails:
    """Two selected frames: the chain a lookup passes and the transform."""

    outof: str
    into: str
    chain: tuple[str, ...]
    pose: Pose


Details = FrameDetails | PairDetails | None


# -- building -------------------------------------------------------------------
def pose_at(
    what: str,
    translation,
    rotation,
    seconds: np.ndarray | None,
    time: float | None,
    fmt: Callable[[float], str],
    missing: Callable[[float], str] | None = None,
) -> Pose:
    """The pose at the latest sample at or before ``time``.

    Parameters
    ----------
    translation : array_like, shape (3,) or (n, 3)
    rotation : array_like, shape (4,) or (n, 4)
    seconds : ndarray, shape (n,), or None
        Sample times (data seconds); None for a static pose.
    time : float or None
        Data seconds to show; None shows the first sample.
    fmt : callable
        Data seconds -> the shared time readout.
    missing : callable, optional
        Data seconds of a sample with no value (NaN) -> what to say instead
        of the pose, e.g. ``"no sample of pupil/left_eye at 72.969 s
        (missing: ...)"``. Default: ``"no sample at <time> (missing)"``.
    """
    if seconds is None:
        return Pose.sample(what, translation, rotation, "static")
    index = 0 if time is None else int(np.searchsorted(seconds, time, side="right")) - 1
    if index < 0:
        return Pose(what, None, None, f"not defined before {fmt(float(seconds[0]))}")
    t, r = np.asarray(translation)[index], np.asarray(rotation)[index]
    if not (np.isfinite(t).all() and np.isfinite(r).all()):
        at = float(seconds[index])
        text = (
            missing(at) if missing is not None else f"no sample at {fmt(at)} (missing)"
        )
        return Pose(what, None, None, text)
    return Pose.sample(what, t, r, f"at {fmt(float(seconds[index]))}")


# -- rendering ------------------------------------------------------------------
def _angle(v: float) -> float:
    # no "-0.00°" and no "-180.00°" for the same angle as 180
    v = round(float(v), 2) + 0.0
    return 180.0 if v == -180.0 else v


def _vector(values) -> str:
    return "(" + ", ".join(f"{float(v) + 0.0:.4g}" for v in values) + ")"


def _pose_lines(pose: Pose) -> list[str]:
    if pose.translation is None or pose.attitude is None:
        return [f"pose {pose.what}: {pose.when}"]
    return [
        f"pose {pose.what} ({pose.when}):",
        f"  translation {_vector(pose.translation)} m",
        f"  rotation {pose.attitude.euler_text()} (intrinsic z-y'-x'')",
        f"  quaternion {pose.attitude.quaternion_text()}",
    ]


def details_lines(details: Details) -> list[str]:
    """The details as lines of plain text."""
    if details is None:
        return ["select a frame for details, two for the transform between them"]
    if isinstance(details, PairDetails):
        lines = [
            f"{details.outof}{ARROW}{details.into}",
            "chain: " + ARROW.join(details.chain),
        ]
    else:
        lines = [
            f"{details.name} \u2014 {details.summary}",
            f"parent: {details.parent or 'none (root)'}",
            f"children: {', '.join(details.children) or 'none'}",
            f"path to root: {ARROW.join(details.path)}",
        ]
    if details.pose is not None:
        lines += _pose_lines(details.pose)
    return lines


def details_text(details: Details) -> str:
    """The details as plain text, one fact per line."""
    return "\n".join(details_lines(details))


def details_html(details: Details) -> str:
    """The details as HTML for the panel (the first line in bold)."""
    lines = [html.escape(line) for line in details_lines(details)]
    lines = [line.replace("  ", "&nbsp;&nbsp;", 1) for line in lines]
    if details is None:
        return f"<i>{lines[0]}</i>"
    lines[0] = f"<b>{lines[0]}</b>"
    return "<br>".join(lines)
