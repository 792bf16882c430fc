"""The exceptions rbm_nb raises beyond the built-in ones.

Each subclasses the built-in exception code written for rigid-body-motion
already catches (``ValueError``), so catching that keeps working.
"""

from __future__ import annotations

__all__ = ["ExtrapolationError", "UnsupportedError"]


class ExtrapolationError(ValueError):
    """A transform was requested at a time a moving frame has no data for."""


class UnsupportedError(NotImplementedError, ValueError):
    """A request the API does not support (yet), as opposed to a wrong value.

    Both a ``NotImplementedError`` (what rigid-body-motion raises in these
    places) and a ``ValueError`` (what rbm_nb raised before), so code
    catching either keeps working.
    """
