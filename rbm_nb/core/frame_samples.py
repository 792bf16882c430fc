"""A frame's samples, checked once and prepared for the engine (:class:`Samples`).

What :class:`rbm_nb.core.frames.ReferenceFrame` does with the arrays it is
given: the timestamps become a Track, the translations and rotations are
checked (each error naming the frame, the argument and the row), rows given
as ``missing`` are kept as a mask, and frozen arrays are kept as they are
with one sign code per sample instead of copies. Split out of
``core/frames.py`` (issue 32: no module over 700 lines); the frame class
calls :func:`_samples`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._door.unpack import float_array, kernel_array
from .._door.validation import (
    check_coordinates,
    check_finite,
    check_missing_rows,
    is_scalar,
    moving_samples,
    normalize_quaternions,
)
from .._door.xarray import is_dataarray
from .._engine import time as _time
from .._engine.frame_data import Samples
from .._infra.config import UNIT_QUATERNION_TOLERANCE
from .._infra.frozen import is_frozen, kernel_alias
from .._kernels import masked_rows as _masked_rows
from .._kernels import quaternion as kq
from .._kernels import rows as _rows


def _check_discrete(name: str | None, samples: Samples, discrete: Any) -> None:
    if discrete and samples.track is None:
        raise ValueError(
            f"frame {name!r}: discrete=True needs timestamps (the times of the events)"
        )


def _checked_max_gap(name: str | None, max_gap: Any) -> float | None:
    if max_gap is None:
        return None
    if not is_scalar(max_gap) or not max_gap > 0 or not np.isfinite(max_gap):
        raise ValueError(
            f"frame {name!r}: max_gap must be a positive number of seconds "
            f"or None, got {max_gap!r}"
        )
    return float(max_gap)


def _samples(name, translation, rotation, timestamps, inverse, missing=None) -> Samples:
    """A moving or static frame's arrays, checked once and prepared for the engine."""
    label = f"frame {name!r}: " if name is not None else ""
    track: _time.Track | None = None
    if timestamps is not None:
        track = _time.as_track(
            timestamps,
            f"{label}timestamps",
            copy=not is_frozen(getattr(timestamps, "values", timestamps)),
        )
    elif missing is not None:
        raise ValueError(f"{label}missing given without timestamps (a static frame)")
    if missing is not None:
        assert track is not None
        mask = _missing_mask(missing, len(track), label)
        if mask is not None:
            return _masked_samples(label, track, translation, rotation, inverse, mask)
    return _prepared(label, track, translation, rotation, inverse)


def _missing_mask(missing: Any, n: int, label: str) -> np.ndarray | None:
    """``missing`` as a private frozen bool array of n rows, or None if no row is set."""
    values = getattr(missing, "values", missing)
    mask = np.asarray(values)
    if mask.dtype != np.bool_ or mask.shape != (n,):
        raise ValueError(
            f"{label}missing must be a bool array of shape ({n},) (one per "
            f"timestamp), got {mask.dtype} of shape {mask.shape}"
        )
    if not mask.any():
        return None
    if not is_frozen(mask):
        mask = mask.copy()  # the caller may change theirs later
        mask.setflags(write=False)
    return mask


def _masked_samples(label, track, translation, rotation, inverse, mask) -> Samples:
    """A moving frame's samples with the rows in ``mask`` missing (as if NaN).

    Every number the engine computes is that of copies with those rows NaN,
    as a caller masking its arrays would make them. Where the caller's
    arrays are frozen the frame keeps them and ``mask`` (the engine applies
    the mask whenever it reads them, :class:`Samples`), and one kernel pass
    checks them and makes the sign codes as if masked
    (``_kernels.masked_rows``): no masked copies at all. Anything else, or a
    row that fails a check, goes through the masked copies, so the error
    names the row as before.
    """
    n = len(track)
    t = _frozen_rows(translation, 3) if translation is not None else None
    q = _frozen_rows(rotation, 4) if rotation is not None else None
    if t is not None and q is not None and not inverse and n >= 2:
        if t.shape[0] == n and q.shape[0] == n:
            signs = np.empty(n, dtype=np.int8)
            t_k, q_k = kernel_alias(t), kernel_alias(q)
            bad, missing = _masked_rows.masked_signs(
                t_k, q_k, kernel_alias(mask), UNIT_QUATERNION_TOLERANCE, signs
            )
            if not bad:
                return Samples(track, t_k, None, q_k, bool(missing), mask, signs)
    masked = _masked_copies(label, n, translation, rotation, mask)
    # the masked copies, kept as any frame's (or a bad row named)
    return _prepared(label, track, masked[0], masked[1], inverse)


def _masked_copies(label, n, translation, rotation, mask) -> list[np.ndarray]:
    """Frozen copies of the translations and rotations with ``mask``'s rows NaN."""
    t_in = (
        np.zeros((n, 3))
        if translation is None
        else float_array(translation, f"{label}translation")
    )
    q_in = None if rotation is None else float_array(rotation, f"{label}rotation")
    if q_in is None:
        q_in = np.zeros((n, 4))
        q_in[:, 0] = 1.0
    for arr, what, cols in ((t_in, "translation", 3), (q_in, "rotation", 4)):
        if arr.shape != (n, cols):
            raise ValueError(_shape_message(label, what, arr.shape, (n, cols)))
    masked = []
    for arr in (t_in, q_in):
        copy = np.ascontiguousarray(
            np.where(mask[:, None], np.nan, arr), dtype=np.float64
        )
        copy.setflags(write=False)  # frozen: _prepared keeps it, no second copy
        masked.append(copy)
    return masked


def _prepared(label, track, translation, rotation, inverse) -> Samples:
    """:func:`_samples` once the times are a Track (or None: static)."""
    if track is not None:
        if not inverse:
            shared = _shared_samples(track, translation, rotation)
            if shared is not None:
                return shared
        n = len(track)
        t_shape: tuple[int, ...] = (n, 3)
        r_shape: tuple[int, ...] = (n, 4)
    else:
        t_shape, r_shape = (3,), (4,)

    t: np.ndarray | None = None
    if translation is not None:
        t = float_array(translation, f"{label}translation")
        if t.shape != t_shape:
            raise ValueError(_shape_message(label, "translation", t.shape, t_shape))
        if track is None:
            check_finite(t, f"{label}translation")
            check_coordinates(t, f"{label}translation")
    stored: np.ndarray | None = None
    if rotation is not None:
        stored = float_array(rotation, f"{label}rotation")
        if stored.shape != r_shape:
            raise ValueError(_shape_message(label, "rotation", stored.shape, r_shape))
    moving = track is not None and r_shape[0] > 1
    if moving and stored is not None and not inverse:
        # the usual recording: every check and copy in one pass
        fused = moving_samples(np.zeros(t_shape) if t is None else t, stored)
        if fused is not None:
            t_fused, public, unit, missing = fused
            return Samples(track, t_fused, unit, public, missing)
    # one check at a time, each naming the row it finds
    missing = False
    if t is None:
        t = np.zeros(t_shape)
    elif track is not None:  # NaN rows: missing samples; else mistakes
        check_missing_rows(t, f"{label}translation")
    if stored is None:
        r: np.ndarray = np.zeros(r_shape)
        r[..., 0] = 1.0
        stored = r
    else:
        if track is not None:
            missing = check_missing_rows(stored, f"{label}rotation")
        r = normalize_quaternions(
            stored, f"{label}rotation", allow_nan=track is not None
        )
    # private copies: the caller's arrays may change later (a moving
    # frame's rotations are copied by unflip below, which makes a new array)
    t = np.array(t.reshape(-1, 3), dtype=np.float64, order="C")
    r = kernel_array(r.reshape(-1, 4)) if moving else np.array(r.reshape(-1, 4))
    if inverse:
        r = kq.qconj(r)  # unit quaternions: the conjugate is the inverse
        t = -kq.rotate_vectors(r, t)
        stored = r
    # the user's values as given (recordings store ~4 digits, so |q| - 1
    # reaches 1e-4): returned by the rotation property and by lookups at
    # the frame's own timestamps; the math uses unit quaternions, which
    # interpolation needs on the same hemisphere
    public = np.array(stored.reshape(-1, 4), dtype=np.float64, order="C")
    return Samples(track, t, kq.unflip(r) if moving else r, public, missing)


def _frozen_rows(value: Any, columns: int) -> np.ndarray | None:
    """``value``'s (n, columns) float64 C-contiguous array if it is frozen, else None."""
    arr = value.data if is_dataarray(value) else value
    if (
        type(arr) is np.ndarray
        and arr.dtype == np.float64
        and arr.ndim == 2
        and arr.shape[1] == columns
        and arr.flags.c_contiguous
        and is_frozen(arr)
    ):
        return arr
    return None


def _shared_samples(track, translation, rotation) -> Samples | None:
    """A moving frame's samples that keep the caller's frozen arrays, or None.

    Translations (n, 3) and rotations (n, 4) that nobody can change any more
    (:func:`rbm_nb._infra.frozen.is_frozen`: read-only down to their memory)
    are kept as they are, with one sign code per sample from which the
    kernels make the unit, sign-continuous rotations interpolation needs
    (``_kernels.signed_rows``; the checks and arithmetic of a copied frame's,
    so every value is the same bit for bit). At 3 h of the explorer's
    recording a frame keeps 1 byte per sample beside the caller's 56 (it
    kept 11 floats, then 4). None (copy as before) for anything else, or if
    a row fails a check (the caller's checks then name it).
    """
    n = len(track)
    t = _frozen_rows(translation, 3)
    q = _frozen_rows(rotation, 4)
    if n < 2 or t is None or q is None or t.shape[0] != n or q.shape[0] != n:
        return None
    signs = np.empty(n, dtype=np.int8)
    bad, missing = _rows.moving_signs(
        kernel_alias(t), kernel_alias(q), UNIT_QUATERNION_TOLERANCE, signs
    )
    if bad:
        return None
    return Samples(
        track, kernel_alias(t), None, kernel_alias(q), bool(missing), None, signs
    )


def _shape_message(label, name, got, expected) -> str:
    hint = ""
    if len(expected) == 2 and len(got) >= 1 and got[-1] == expected[1]:
        hint = f" (one row per timestamp: {expected[0]} timestamps given)"
    elif len(expected) == 1 and len(got) == 2:
        hint = " (a moving frame needs timestamps)"
    return f"{label}{name} must have shape {expected}, got {got}{hint}"
