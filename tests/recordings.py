"""The head/eye recording tests run on: the real one when present, else synthetic.

The real files are ``../shared/data/rbm-data/{head,left_eye,right_eye}.nc``
(CI has them); without them the synthetic stand-in of the same schema is used,
so every test that takes a recording runs on both sources somewhere.
"""

from __future__ import annotations

import functools
import os
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
REAL_DIR = (
    Path(os.environ.get("RBM_NB_SHARED", REPO.parent / "shared")) / "data" / "rbm-data"
)
NAMES = ("head", "left_eye", "right_eye")


def real_available() -> bool:
    return all((REAL_DIR / f"{n}.nc").is_file() for n in NAMES)


@functools.lru_cache(maxsize=2)
def real_recording():
    """The real datasets, loaded into memory (None if the files are absent)."""
    if not real_available():
        return None
    import xarray as xr

    out = []
    for n in NAMES:
        with xr.open_dataset(REAL_DIR / f"{n}.nc") as ds:
            out.append(ds.load())
    return tuple(out)


@functools.lru_cache(maxsize=2)
def synthetic_recording(duration: float = 60.0):
    from rbm_nb.data.synthetic import synthetic_head_eye

    return tuple(synthetic_head_eye(duration=duration, seed=0))


def recording():
    """(head, left_eye, right_eye, source) with source 'real' or 'synthetic'."""
    real = real_recording()
    if real is not None:
        return (*real, "real")
    return (*synthetic_recording(), "synthetic")
