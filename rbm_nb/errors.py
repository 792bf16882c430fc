"""The exceptions rbm_nb raises beyond the built-in ones.

Each subclasses the built-in exception code written for rigid-body-motion
already catches (``ValueError``), so catching that keeps working.
"""

from __future__ import annotations

__all__ = ["ExtrapolationError"]


class ExtrapolationError(ValueError):
    """A transform was requested at a time a moving frame has no data for."""
