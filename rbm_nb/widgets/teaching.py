"""Teaching aids for the notebooks: a self-check for exercises and frame sliders.

``check_answer`` compares a student's prediction with the value the notebook
computed and says right or wrong, and why. ``FrameSliders`` binds yaw, pitch,
roll and translation sliders to a *static* frame of the registry: every move
re-registers the frame, redraws it in a Scene and reprints whatever lookup the
notebook asked for, so "where is the point for the observer?" can be turned
and watched instead of recomputed by hand. The sliders run Python callbacks:
they need a live kernel (a saved page shows their last state).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ..core.frames import register_frame, registry
from ..core.quaternions import from_euler_angles

_NO_PREDICTION = (
    "No prediction yet: write yours in place of None in the cell above this one, "
    "then run both again."
)


def check_answer(
    prediction: Any,
    expected: Any,
    *,
    why: str,
    atol: float = 1e-6,
    rtol: float = 0.0,
) -> bool | None:
    """Print whether ``prediction`` matches ``expected``, and why.

    Parameters
    ----------
    prediction : object
        The student's answer; ``None`` means "not answered yet".
    expected : object
        The value the notebook computed. Numbers and arrays are compared
        with ``atol``/``rtol``, anything else with ``==``.
    why : str
        The explanation printed with the verdict.
    atol, rtol : float
        Tolerances for numeric answers.

    Returns
    -------
    bool or None
        True/False for right/wrong, None when there is no prediction.

    Examples
    --------
    >>> check_answer(4, 4.0, why="five samples make four steps")
    Right. five samples make four steps
    True
    """
    if not why or not isinstance(why, str):
        raise ValueError("check_answer: why must be a non-empty explanation")
    if prediction is None:
        print(_NO_PREDICTION)
        return None
    right = _matches(prediction, expected, atol, rtol)
    if right:
        print(f"Right. {why}")
    else:
        print(
            f"Not quite: you said {prediction!r}, the answer is {_show(expected)}. {why}"
        )
    return right


def _matches(prediction: Any, expected: Any, atol: float, rtol: float) -> bool:
    if isinstance(expected, str) or isinstance(prediction, str):
        return str(prediction).strip().lower() == str(expected).strip().lower()
    try:
        got = np.asarray(prediction, dtype=float)
        want = np.asarray(expected, dtype=float)
    except (TypeError, ValueError):
        return bool(prediction == expected)
    if got.shape != want.shape:
        return False
    return bool(np.allclose(got, want, atol=atol, rtol=rtol))


def _show(value: Any) -> str:
    if isinstance(value, np.ndarray):
        return np.array2string(np.round(value, 4), separator=", ")
    if isinstance(value, float):
        return f"{value:.4g}"
    return repr(value)


def quaternion_from_ypr_degrees(yaw: float, pitch: float, roll: float) -> np.ndarray:
    """``R = Rz(yaw) Ry(pitch) Rx(roll)`` as a (w, x, y, z) quaternion.

    The aerospace/ROS convention: turn by yaw about z, then pitch about the
    new y, then roll about the newest x.
    """
    return np.asarray(
        from_euler_angles(
            roll=np.deg2rad(roll),
            pitch=np.deg2rad(pitch),
            yaw=np.deg2rad(yaw),
            order="ypr",
        ),
        dtype=float,
    )


class FrameSliders:
    """Sliders for the pose of one static frame relative to its parent.

    The sliders are drawn by the browser (``js/src/teaching.js``): moving one
    turns the frame's triad in the scene and prints ``point`` in the frame's
    axes at once, with or without a kernel. With a kernel, every move also
    re-registers the frame, redraws it (and whatever ``draw`` adds) and prints
    what ``report`` returns.

    Parameters
    ----------
    name : str
        The frame to (re-)register; registered at once.
    parent : str
        Its parent in the registry.
    translation : sequence of 3 float, default (0, 0, 0)
        Starting translation in the parent's axes (metres).
    angles : sequence of 3 float, default (0, 0, 0)
        Starting yaw, pitch and roll in degrees (``R = Rz Ry Rx``).
    scene : rbm_nb.scene.Scene, optional
        Scene in which the frame is drawn as a triad and kept up to date.
    report : callable, optional
        Called after every change; what it returns is printed below the
        sliders (e.g. a lookup or a transformed point).
    draw : callable, optional
        ``draw(scene) -> list of handles`` for extra objects that depend on
        the frame (arrows, points); the handles are removed before the next
        redraw.
    point : sequence of 3 float, optional
        A point of the parent that the browser prints in the frame's axes.
    reach : float, default 5.0
        Translation sliders run from ``-reach`` to ``reach`` metres.
    sliders : sequence of str, optional
        Which sliders to show, among "yaw", "pitch", "roll", "x", "y", "z"
        (all six by default).
    scale : float, default 0.5
        Length of the triad's axes in the scene.
    """

    NAMES = ("yaw", "pitch", "roll", "x", "y", "z")

    def __init__(
        self,
        name: str,
        parent: str,
        *,
        translation: Sequence[float] = (0.0, 0.0, 0.0),
        angles: Sequence[float] = (0.0, 0.0, 0.0),
        scene=None,
        report: Callable[[], Any] | None = None,
        draw: Callable[[Any], list] | None = None,
        point: Sequence[float] | None = None,
        reach: float = 5.0,
        sliders: Sequence[str] | None = None,
        scale: float = 0.5,
    ) -> None:
        import ipywidgets as widgets

        # lazy (optional dependency): the panel needs anywidget; the plots do not
        from .slider_panel import SliderPanel

        if not isinstance(name, str) or not name:
            raise ValueError(f"FrameSliders: name must be a frame name, got {name!r}")
        if parent not in registry:
            raise ValueError(f"FrameSliders: parent {parent!r} is not registered")
        start = _three(translation, "translation") + _three(angles, "angles")
        wanted = tuple(self.NAMES if sliders is None else sliders)
        unknown = [s for s in wanted if s not in self.NAMES]
        if unknown or not wanted:
            raise ValueError(
                f"FrameSliders: sliders must be among {self.NAMES}, got {list(wanted)}"
            )
        if not reach > 0:
            raise ValueError(f"FrameSliders: reach must be positive, got {reach!r}")
        self.name, self.parent = name, parent
        self._scene, self._report, self._draw, self._scale = scene, report, draw, scale
        self._handles: list = []
        values = dict(zip(("x", "y", "z", "yaw", "pitch", "roll"), start, strict=True))
        self.panel = SliderPanel(
            values=values,
            shown=list(wanted),
            reach=float(reach),
            frame=name,
            parent=parent,
            point=None if point is None else list(_three(point, "point")),
            scene=None if scene is None else scene.widget,
        )
        parts: list = [self.panel]
        if scene is not None:
            parts.append(scene.widget)
        self.box = widgets.VBox(parts)
        self.apply()
        self.panel.observe(self._changed, "values")

    # -- the pose -------------------------------------------------------------
    @property
    def values(self) -> dict:
        """The sliders' values: yaw, pitch, roll in degrees, x, y, z in metres."""
        return dict(self.panel.values)

    @property
    def translation(self) -> np.ndarray:
        v = self.panel.values
        return np.array([v["x"], v["y"], v["z"]], dtype=float)

    @property
    def rotation(self) -> np.ndarray:
        v = self.panel.values
        return quaternion_from_ypr_degrees(v["yaw"], v["pitch"], v["roll"])

    def set(self, **values: float) -> None:
        """Move sliders from code, e.g. ``set(yaw=90, x=1)``; one redraw."""
        unknown = [k for k in values if k not in self.NAMES]
        if unknown:
            raise ValueError(f"FrameSliders.set: unknown sliders {unknown}")
        self.panel.values = {
            **self.panel.values,
            **{k: float(v) for k, v in values.items()},
        }

    def apply(self) -> None:
        """Register the frame at the sliders' pose, redraw and report."""
        register_frame(
            self.name,
            parent=self.parent,
            translation=self.translation,
            rotation=self.rotation,
            update=True,
        )
        if self._scene is not None:
            self._redraw()
        result = None if self._report is None else self._report()
        self.panel.report = "" if result is None else str(result)

    def _redraw(self) -> None:
        for handle in self._handles:
            handle.remove()
        # the same label each time: the triad keeps its scene path, which the
        # browser turns on its own while a slider moves
        triad = self._scene.add_frame(
            self.name, scale=self._scale, label=f"sliders {self.name}"
        )
        self._handles = [triad]
        if self.parent == self._scene.base.name:
            self.panel.node = triad.pose_path
        if self._draw is not None:
            self._handles += list(self._draw(self._scene))

    def _changed(self, change) -> None:
        self.apply()

    def _repr_mimebundle_(self, **kwargs):
        return self.box._repr_mimebundle_(**kwargs)


def _three(values: Sequence[float], argument: str) -> tuple[float, ...]:
    arr = np.asarray(values, dtype=float)
    if arr.shape != (3,) or not np.isfinite(arr).all():
        raise ValueError(
            f"FrameSliders: {argument} must be three finite numbers, got {values!r}"
        )
    return tuple(float(v) for v in arr)


def show_file(path, *, height: int = 480):
    """Show an HTML file the notebook wrote (e.g. ``Scene.to_html``) inline.

    The page is embedded in the output as an iframe's ``srcdoc``, so the saved
    notebook, its nbconvert HTML and the docs show it without a kernel and
    without the file beside them. (A ``src=`` link would break as soon as the
    output is viewed anywhere but next to the file.)

    Parameters
    ----------
    path : str or os.PathLike
        An HTML file.
    height : int, default 480
        Height of the frame in pixels.

    Returns
    -------
    IPython.display.HTML
    """
    import html
    import warnings
    from pathlib import Path

    from IPython.display import HTML

    file = Path(path)
    if file.suffix.lower() not in (".html", ".htm") or not file.is_file():
        raise ValueError(
            f"show_file: path must be an existing .html file, got {str(path)!r}"
        )
    if isinstance(height, bool) or not isinstance(height, int) or height < 50:
        raise ValueError(
            f"show_file: height must be an integer >= 50 pixels, got {height!r}"
        )
    page = html.escape(file.read_text(encoding="utf-8"), quote=True)
    with warnings.catch_warnings():
        # IPython suggests IFrame for any <iframe>; IFrame can only link (src=)
        warnings.filterwarnings("ignore", "Consider using IPython.display.IFrame")
        return HTML(
            f'<iframe srcdoc="{page}" style="width: 100%; height: {height}px; border: 0" '
            f'title="{html.escape(file.name)}"></iframe>'
        )
