"""What the browser may change in a widget, and nothing more.

A widget's synced traits come back from the frontend in ``update`` messages,
which anyone with the page (or a script in it) can send. Some traits are the
browser's to set (the player's time, the plot's zoom); the rest are the
kernel's (a player's duration and origin, a plot's data, every ``_esm``):
an update of those from the frontend is refused and the kernel's value sent
back, so every view shows the kernel's state again. An update of a trait the
frontend may set goes through the same ``@validate`` as a Python assignment;
a value that fails is refused the same way, and the others of the message
still apply.
"""

from __future__ import annotations

import logging
from typing import Any, ClassVar

import traitlets

logger = logging.getLogger("rbm_nb.widgets")

# traits of every ipywidget (layout, model names, ...): the base classes own them
_BASE_TRAITS = frozenset(
    (
        "_dom_classes",
        "_model_module",
        "_model_module_version",
        "_model_name",
        "_view_count",
        "_view_module",
        "_view_module_version",
        "_view_name",
        "layout",
        "tabbable",
        "tooltip",
    )
)


class FrontendGuard:
    """Mixin for an anywidget (first in the bases): guards updates from the browser.

    Subclasses list in ``_frontend_settable`` the synced traits the browser
    may set; every other synced trait they declare is the kernel's.

    Attributes
    ----------
    refused : list of tuple
        ``(trait, value sent, reason)`` of each update refused, latest last.
    """

    _frontend_settable: ClassVar[frozenset[str]] = frozenset()

    def kernel_owned(self) -> frozenset[str]:
        """The synced traits the browser may not set."""
        keys = set(getattr(self, "keys", ()))
        return frozenset(keys - _BASE_TRAITS - self._frontend_settable)

    def set_state(self, sync_data: dict[str, Any]) -> None:
        """Apply an update from the frontend: the settable traits that validate."""
        if not hasattr(self, "refused"):
            self.refused: list[tuple[str, Any, str]] = []
        owned = self.kernel_owned()
        restore = []
        for name, value in sync_data.items():
            if name in owned:
                self._refuse(name, value, "the kernel owns it")
                restore.append(name)
                continue
            try:
                # one trait at a time: a bad value does not block the others
                super().set_state({name: value})  # type: ignore[misc]
            except (traitlets.TraitError, TypeError, ValueError) as err:
                self._refuse(name, value, str(err))
                restore.append(name)
        if restore:
            # the browser already shows what it sent: give it the kernel's value
            self.send_state(restore)  # type: ignore[attr-defined]

    def _refuse(self, name: str, value: Any, reason: str) -> None:
        self.refused.append((name, value, reason))
        del self.refused[:-20]
        logger.warning(
            "%s: refused %s=%r from the browser: %s",
            type(self).__name__,
            name,
            value,
            reason,
        )
