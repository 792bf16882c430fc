"""Writing files so that a failure never damages what was there before.

Every writer in rbm_nb (rosbags, netCDF caches, HTML exports) goes through
:func:`atomic_path`: it writes into a hidden scratch folder beside the target
and renames into place only once everything has been written.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def atomic_path(target: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path that replaces ``target`` only if the block succeeds.

    The temporary path lives in a hidden folder beside ``target`` (same file
    system, so the final rename is atomic) and has the same name, so writers
    that look at the suffix behave as for ``target``. It may become a file or
    a directory (ROS2 bags are directories). If the block raises, ``target``
    is left exactly as it was and nothing is left behind.
    """
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    scratch = Path(
        tempfile.mkdtemp(dir=target.parent, prefix=f".{target.name}.", suffix=".tmp")
    )
    try:
        yield scratch / target.name
        _replace(scratch / target.name, target, scratch)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def _replace(new: Path, target: Path, scratch: Path) -> None:
    if not new.exists():
        raise FileNotFoundError(f"nothing was written to {target}")
    if target.is_dir() and not target.is_symlink():
        # a directory can only be renamed over an empty one: park the old one
        # in the scratch folder (deleted afterwards), put it back on failure
        old = scratch / ".previous"
        os.replace(target, old)
        try:
            os.replace(new, target)
        except BaseException:
            os.replace(old, target)
            raise
    else:
        os.replace(new, target)
