"""The browser half of :class:`~rbm_nb.widgets.FrameSliders` (``js/src/teaching.js``).

The sliders, the local printout and the turning of the frame's node in the
3D view all run in the browser, so a saved page without a kernel still
responds; the kernel hears ``values`` and answers with ``report``.
"""

from __future__ import annotations

import anywidget
import traitlets
from ipywidgets import widget_serialization

from ..scene.widget import SceneWidget
from .player import bundle

NAMES = ("yaw", "pitch", "roll", "x", "y", "z")


class SliderPanel(anywidget.AnyWidget):
    """Yaw/pitch/roll/translation sliders for one static frame."""

    _esm = traitlets.Unicode("").tag(sync=True)
    values = traitlets.Dict(help="yaw, pitch, roll (degrees) and x, y, z (metres)").tag(
        sync=True
    )
    shown = traitlets.List(traitlets.Unicode(), help="which sliders to draw").tag(
        sync=True
    )
    reach = traitlets.Float(5.0, help="translation sliders run over +-reach m").tag(
        sync=True
    )
    frame = traitlets.Unicode("", help="the frame the sliders pose").tag(sync=True)
    parent = traitlets.Unicode("", help="its parent").tag(sync=True)
    scene = traitlets.Instance(SceneWidget, allow_none=True).tag(
        sync=True, **widget_serialization
    )
    node = traitlets.Unicode(
        "", help="scene path of the frame's pose node ('' if not the sliders' pose)"
    ).tag(sync=True)
    point = traitlets.List(
        traitlets.Float(), allow_none=True, default_value=None, minlen=3, maxlen=3,
        help="a point of the parent the browser prints in the frame's axes",
    ).tag(sync=True)  # fmt: skip
    report = traitlets.Unicode("", help="what the kernel printed for this pose").tag(
        sync=True
    )

    def __init__(self, **kwargs):
        super().__init__(_esm=bundle("teaching"), **kwargs)

    @traitlets.validate("values")
    def _valid_values(self, proposal):
        values = proposal["value"]
        if set(values) != set(NAMES):
            raise traitlets.TraitError(
                f"values must have the keys {NAMES}, got {sorted(values)}"
            )
        out = {}
        for key in NAMES:
            value = values[key]
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise traitlets.TraitError(
                    f"values[{key!r}] must be a number, got {value!r}"
                )
            out[key] = float(value)
        return out
