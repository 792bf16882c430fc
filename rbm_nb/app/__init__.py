"""The application layer: the head/eye explorer, the demo server, the command line.

``explorer`` builds the dashboard out of the notebook layer's widgets,
``server`` writes the demo notebook and serves it with Voilà (127.0.0.1 and
a token only), ``cli`` is the ``rbm-nb`` command. The names of ``server``
are also available here, where they were before the module moved.
"""

from __future__ import annotations

from .._infra.lazy import lazy_attributes

_EXPORTS = {
    name: "server"
    for name in (
        "app_notebook",
        "explorer_dashboard",
        "run_child",
        "serve",
        "voila_command",
        "voila_environment",
        "write_app_notebook",
    )
}

__getattr__, __dir__ = lazy_attributes(
    __name__, _EXPORTS, ("cli", "explorer", "server")
)
