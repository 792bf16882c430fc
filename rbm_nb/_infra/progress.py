"""Progress bars that render as widgets in Jupyter and as text in a terminal.

tqdm is an optional dependency (extras ``data`` and ``ros``): without it
long operations simply run without a bar, unless a bar was asked for
explicitly, which then raises an ImportError naming the extra.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any


class _NoBar:
    """Stands in for a tqdm bar when none is shown."""

    def update(self, n: int = 1) -> None:
        pass

    def set_postfix_str(self, text: str) -> None:
        pass

    def close(self) -> None:
        pass


def wants_bar(progress: bool | None, size: int, threshold: int) -> bool:
    """Show a bar if asked to (True), or by default (None) if ``size >= threshold``."""
    if progress is None:
        return size >= threshold
    return bool(progress)


def _tqdm(required: bool):
    try:
        from tqdm.auto import tqdm
    except ImportError:
        if required:
            raise ImportError(
                "progress=True needs tqdm: pip install 'rbm_nb[data]' (or tqdm)"
            ) from None
        return None
    return tqdm


def make_bar(
    total: int | None, desc: str, *, progress: bool | None, threshold: int = 0
) -> Any:
    """A tqdm.auto bar (notebook widget or text), or a silent stand-in.

    Parameters
    ----------
    total : int or None
        Number of steps, None if unknown.
    desc : str
        Label in front of the bar.
    progress : bool or None
        True always shows a bar, False never, None only when ``total`` is at
        least ``threshold``.
    """
    if not wants_bar(progress, total or 0, threshold):
        return _NoBar()
    tqdm = _tqdm(required=progress is True)
    if tqdm is None:
        return _NoBar()
    return tqdm(total=total, desc=desc, leave=False)


def download_bar(desc: str) -> Any:
    """A byte-counting bar for pooch's downloaders, or False without tqdm."""
    tqdm = _tqdm(required=False)
    if tqdm is None:
        return False
    # pooch sets the real total and tests the bar for truth first, which a
    # tqdm without a total refuses; delay: a download that fails at once
    # leaves no empty bar behind
    return tqdm(
        total=1, desc=desc, unit="B", unit_scale=True, unit_divisor=1024, delay=0.5
    )


@contextmanager
def progress_bar(
    total: int | None, desc: str, *, progress: bool | None, threshold: int = 0
) -> Iterator:
    """:func:`make_bar` as a context manager that always closes the bar."""
    bar = make_bar(total, desc, progress=progress, threshold=threshold)
    try:
        yield bar
    finally:
        bar.close()
