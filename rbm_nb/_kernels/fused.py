"""Fused chain kernels: one pass over the output rows, nothing else allocated.

The kernels called from Python: :func:`lookup_chain`, :func:`transform_chain`
and their prange twins (each pair compiled from one body), over the block
evaluation of :mod:`.chain_block`; the table fill is in :mod:`.squad_table`,
the parallel calls' prefill in :mod:`.chain_prefill`.

A chain of frames between two frames is, once its static runs are composed,
``S0 M1 S1 M2 S2 ...``: static transforms ``S`` and up to :data:`SLOTS`
moving frames ``M`` (each possibly inverted). For every output row the
kernels here find each moving frame's segment by walking forward from the
previous row's segment (a merge walk over sorted target times; unsorted
times restart the walk, which then is a galloping binary search), evaluate
the frame there (squad for rotations and linear for translations of
continuous frames, the held event of discrete frames), compose the whole
chain in registers and write only the result: the transform itself
(:func:`lookup_chain`) or the point/vector/quaternion it carries
(:func:`transform_chain`).

The arithmetic is that of the unfused engine (``chain.resample_frame``,
``resample.chain_step``, ``quaternion.squad_evaluate``), so results agree
with it to rounding.

Inputs (unchecked, like every kernel)
-------------------------------------
plan : int64 (3 * steps,)
    Per step ``(kind, index, inverse)``: kind :data:`STATIC` (index into
    ``statics``), :data:`SQUAD` (continuous frame: linear translation,
    squad rotation), :data:`CONSTANT` (a continuous frame of one sample),
    :data:`HELD` (discrete frame); index is the slot (0..SLOTS-1) of a
    moving frame. ``inverse`` is 1 for a step traversed against its
    direction (static steps are composed forward beforehand: 0).
statics : float64 (s, 7)
    Static transforms as ``tx, ty, tz, w, x, y, z``.
offsets : float64 (SLOTS,)
    Added to the target times to put them on each slot's time origin.
own : int64 (SLOTS,)
    1 + i0 where the target times are the run of the slot's own sample
    times from sample i0 (then every row is a sample: its stored value),
    else 0 (a target time that happens to equal a sample time is evaluated
    like any other: the stored translation, squad's unit rotation; the
    stored sample where the segment after it misses its end). With a wrong
    i0 the results are the same, only slower (blocks are checked before
    they are copied).
gaps : float64 (SLOTS,)
    Each slot's ``max_gap`` (inf: none): target times strictly inside a
    longer gap between two samples get NaN.
slot_times, slot_t, slot_s, slot_p, slot_c : tuples of SLOTS arrays
    One tuple per quantity, indexed by slot (``chain_block.SLOT_TYPES``):
    a moving frame's sample times (n,), translations (n, 3), the int8 sign
    codes (n,) that make its rotations free of sign flips (``unflip``)
    from the rotations as stored (:mod:`.signed_rows`), rotations as stored
    (with their signs) (n, 4) and its squad table (n, 15) (:mod:`.squad_table`; any
    (1, 15) array for a frame that is not interpolated by squad). Unused
    slots get any arrays of these types. :func:`pack_slots` builds them
    from per-frame tuples.

Signs: squad runs on the sign-continuous rotations; an interpolated value
takes the sign of the stored sample its segment starts from, a sample time
or a held event returns the stored sample (as ``chain.stored_signs``).

Missing samples
---------------
NaN rows in a frame's translations or rotations are missing samples. A
result is NaN only where a sample it needs is missing: at a sample's own
time the sample itself (NaN if it is the missing one), between samples i
and i+1 of a continuous frame those two (linear translation; squad
rotation, whose control points take the end rule of a series where
sample i-1 or i+2 is missing: each run between missing samples is
interpolated as a series of its own), and a discrete frame's held event.
Nothing else produces NaN.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numba import prange

from .._infra.config import PARALLEL_KERNEL
from ._jit import F1, F2, F3, I1, B, I, compiled_as, kernel  # noqa: E741
from .chain_block import CONSTANT, HELD, SLOT_TYPES, SLOTS, SQUAD, STATIC, _chain_block
from .chain_prefill import CHUNKS, _chunk_bounds, prefill_chain
from .chain_rows import BLOCK, WORK, _apply_block, _store_lookup
from .squad_table import TABLE_COLUMNS, squad_table

__all__ = [
    "SLOTS",
    "STATIC",
    "SQUAD",
    "CONSTANT",
    "HELD",
    "TABLE_COLUMNS",
    "pack_slots",
    "squad_table",
    "lookup_chain",
    "transform_chain",
    "prefill_chain",
    "lookup_chain_parallel",
    "transform_chain_parallel",
]

# the arguments every chain kernel starts with: plan, statics, offsets,
# gaps, own, then the slot tuples
CHAIN = (I1, F2, F1, F1, I1, *SLOT_TYPES)


def pack_slots(
    frames: Sequence[tuple[np.ndarray, ...]],
) -> tuple[tuple[np.ndarray, ...], ...]:
    """The slot arguments from SLOTS per-frame tuples (times, t, s, p, c)."""
    return tuple(zip(*frames, strict=True))


# ---------------------------------------------------------------------------
# serial and prange twins, each pair from one body
# ---------------------------------------------------------------------------

# A body is made for a number of chunks: the output rows are split into
# contiguous chunks of whole blocks, each with its own scratch and its own
# segment cursors, in a ``prange`` loop. The serial kernel is the body with
# one chunk, compiled without ``parallel`` (where prange is range): one
# scratch, cursors walking forward over every row. The twin has CHUNKS
# chunks: a chunk starts its walk from -1, a binary search, and the segment
# of a time does not depend on where the walk started, so every row gets
# exactly the arithmetic of the serial kernel (bit for bit). The twins only
# read the squad tables: :func:`prefill_chain` fills what they will read.
# Each scratch is allocated in the loop, which numba hoists to once per
# thread (a (chunks, BLOCK, 7) array would be half of a transform_points
# output of the recording).


def _lookup_body(chunks: int) -> Callable[..., Any]:
    def body(
        plan, statics, offsets, gaps, own, slot_times, slot_t, slot_s, slot_p, slot_c,
        target, rotation_only,
    ):  # fmt: skip
        m = target.shape[0]
        t_out = np.empty((0 if rotation_only else m, 3))
        r_out = np.empty((m, 4))
        bounds = _chunk_bounds(m, chunks)
        nch = bounds.shape[0] - 1
        cur = np.full((nch, SLOTS), -1, dtype=np.int64)
        computed = 0
        for ch in prange(nch):
            work = np.zeros(WORK * BLOCK)  # zeros: see chain_rows._ACC
            cur_c = cur[ch]
            for j0 in range(bounds[ch], bounds[ch + 1], BLOCK):
                j1 = min(j0 + BLOCK, bounds[ch + 1])
                computed += _chain_block(
                    plan, statics, offsets, gaps, own,
                    slot_times, slot_t, slot_s, slot_p, slot_c,
                    target, j0, j1, work, cur_c, rotation_only,
                )  # fmt: skip
                _store_lookup(work, t_out, r_out, j0, j1, rotation_only)
        return t_out, r_out, computed

    return body


def _transform_body(chunks: int) -> Callable[..., Any]:
    def body(
        plan, statics, offsets, gaps, own, slot_times, slot_t, slot_s, slot_p, slot_c,
        target, data, mode,
    ):  # fmt: skip
        m = target.shape[0]
        out = np.empty((m, data.shape[1], data.shape[2]))
        rotation_only = mode != 0
        bounds = _chunk_bounds(m, chunks)
        nch = bounds.shape[0] - 1
        cur = np.full((nch, SLOTS), -1, dtype=np.int64)
        computed = 0
        for ch in prange(nch):
            work = np.zeros(WORK * BLOCK)  # zeros: see chain_rows._ACC
            cur_c = cur[ch]
            for j0 in range(bounds[ch], bounds[ch + 1], BLOCK):
                j1 = min(j0 + BLOCK, bounds[ch + 1])
                computed += _chain_block(
                    plan, statics, offsets, gaps, own,
                    slot_times, slot_t, slot_s, slot_p, slot_c,
                    target, j0, j1, work, cur_c, rotation_only,
                )  # fmt: skip
                _apply_block(work, data, out, j0, j1, mode)
        return out, computed

    return body


_LOOKUP_DOC = """The chain's transform at every target time, in one pass.

    Parameters
    ----------
    plan, statics, offsets, gaps, own, slot_times .. slot_c : see the module docstring
    target : ndarray, shape (m,)
        Target times (slot k reads ``target + offsets[k]``).
    rotation_only : bool
        Skip the translations (then ``t`` is returned with shape (0, 3)).

    Returns
    -------
    t : ndarray, shape (m, 3) or (0, 3)
    r : ndarray, shape (m, 4)
    computed : int
        Rows of the squad tables computed by this call.
    """

_TRANSFORM_DOC = """Carry data through the chain at every target time, in one pass.

    Parameters
    ----------
    plan, statics, offsets, gaps, own, slot_times .. slot_c : see the module docstring
    target : ndarray, shape (m,)
    data : ndarray, shape (m, k, c) or (1, k, c)
        Points or vectors (c == 3) or quaternions (c == 4); a first
        dimension of 1 is reused for every row.
    mode : int
        0 points (rotate and translate), 1 vectors (rotate; translations
        are never evaluated), 2 quaternions (left-multiplied by the
        rotation; translations never evaluated).

    Returns
    -------
    out : ndarray, shape (m, k, c)
    computed : int
        Rows of the squad tables computed by this call.
    """

_TWIN_DOC = """:func:`{0}` on all threads, with tables prefilled.

    Call :func:`prefill_chain` first (unless the tables are complete): rows
    are evaluated in parallel chunks that only read the tables. Returns
    what :func:`{0}` returns, bit for bit (``computed`` is 0 when the
    tables were prefilled).
    """

lookup_chain = kernel(*CHAIN, F1, B)(
    compiled_as("lookup_chain", _LOOKUP_DOC, _lookup_body(1))
)
transform_chain = kernel(*CHAIN, F1, F3, I)(
    compiled_as("transform_chain", _TRANSFORM_DOC, _transform_body(1))
)
lookup_chain_parallel = kernel(*CHAIN, F1, B, options=PARALLEL_KERNEL)(
    compiled_as(
        "lookup_chain_parallel",
        _TWIN_DOC.format("lookup_chain"),
        _lookup_body(CHUNKS),
    )
)
transform_chain_parallel = kernel(*CHAIN, F1, F3, I, options=PARALLEL_KERNEL)(
    compiled_as(
        "transform_chain_parallel",
        _TWIN_DOC.format("transform_chain"),
        _transform_body(CHUNKS),
    )
)
