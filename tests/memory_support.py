"""What a call keeps in memory, for the tests that bound it."""

from __future__ import annotations

import tracemalloc
from collections.abc import Callable
from typing import TypeVar

T = TypeVar("T")


def kept_by(make: Callable[[], T]) -> tuple[T, int]:
    """``make()``'s result and the bytes still allocated once it returned
    (traced by tracemalloc: what the result and anything it left behind hold)."""
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        out = make()
        kept = tracemalloc.get_traced_memory()[0] - before
    finally:
        tracemalloc.stop()
    return out, kept
