"""The Player the browser dashboard test links its views to.

scene's anywidget Player (time in seconds from the start, t0_ns, clock in the
browser) when this tree has it; until then a stand-in with the same synced
traits that shows its time, so the views can be tested against the contract.
"""

from __future__ import annotations

import anywidget
import traitlets


class StandInPlayer(anywidget.AnyWidget):
    _esm = """
    function render({ model, el }) {
      const span = document.createElement("span");
      span.className = "standin-player";
      const show = () => { span.textContent = `player ${model.get("time").toFixed(3)}`; };
      model.on("change:time", show);
      show();
      el.appendChild(span);
    }
    export default { render };
    """
    time = traitlets.Float(0.0).tag(sync=True)
    t0_ns = traitlets.Int(None, allow_none=True).tag(sync=True)
    duration = traitlets.Float(0.0).tag(sync=True)


def make_player(timestamps):
    from rbm_nb.widgets import Player

    if Player.class_traits().get("t0_ns") is not None:
        return Player(timestamps)
    return StandInPlayer(duration=float(timestamps[-1] - timestamps[0]))
