"""A looked-up chain with one moving frame, composed in one pass at its samples.

The scene's moving objects hang from chains such as head -> tracker ->
world or eye -> scene camera -> head: one frame moves, the others are
static, and the scene looks the chain up at the mover's own timestamps.
The engine composes such rows with ``chain_step``, a product per static
step; a whole recording looked up that way in windows of a few thousand
rows spent most of its time in per-call overhead (at 3 h: ~5000 calls,
~1.3 s for the bounds alone). :class:`OneMover` hands the mover's stored
rows to :mod:`rbm_nb._kernels.one_mover`, which composes them with the same
operations in the same order, so every row is the engine's to the bit:

* :meth:`OneMover.summary`: the bounds of every composed translation, one
  pass, nothing held;
* :meth:`OneMover.poses`: the composed rows of chosen samples (the coarse
  copy), NaN across a missing row; :meth:`OneMover.translations` their
  translations alone (a path's blocks).

Chains with more than one moving frame, a discrete mover, or timestamps
that are not the mover's own are not planned (:func:`plan` gives None) and
are looked up by the engine in windows, as before.
"""

from __future__ import annotations

import numpy as np

from .._engine import chain as _chain
from .._infra.frozen import kernel_alias
from .._kernels._arrays import kernel_array
from .._kernels.one_mover import mover_poses, mover_summary, mover_translations

_NO_ROWS = np.zeros(0, dtype=bool)


class OneMover:
    """The static parts around a chain's moving frame, ready for the kernels.

    ``steps``: the engine's chain (``(FrameData, inverse)`` pairs), ``at``
    the index of its moving step.
    """

    def __init__(self, steps, at: int) -> None:
        mover, inverse = steps[at]
        self._samples = mover.samples
        self._raw = at == 0 and not inverse
        # as the engine composes them: the steps before the mover from the
        # identity (static: one row each), the mover's row, then each step after
        if at == 0:
            below_t, below_r = _chain._IDENTITY_T, _chain._IDENTITY_R
        else:
            below_t, below_r = _chain.compose(steps[:at], _chain.Target(None))
        self._below = (kernel_array(below_t), kernel_array(below_r))
        self._inverse = bool(inverse)
        above = steps[at + 1 :]
        self._above_t = kernel_array(
            np.array([f.t.reshape(3) for f, _ in above]).reshape(-1, 3)
        )
        self._above_r = kernel_array(
            np.array([f.rotation.reshape(4) for f, _ in above]).reshape(-1, 4)
        )
        self._above_inverse = np.array([bool(i) for _, i in above], dtype=bool)

    def _chain(self) -> tuple:
        return (
            self._below[0],
            self._below[1],
            self._raw,
            self._inverse,
            self._above_t,
            self._above_r,
            self._above_inverse,
        )

    def summary(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
        """Lowest, highest and sum of the composed translations that are not
        missing, and their count (NaN bounds and 0 when none)."""
        samples = self._samples
        low, high, total, count = mover_summary(
            kernel_array(samples.stored_t),
            kernel_array(samples.stored_rotation),
            _missing(samples.missing_rows, slice(None)),
            *self._chain(),
        )
        return low, high, total, int(count)

    def poses(self, index: slice | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Composed translations (k, 3) and rotations (k, 4) of the mover's
        samples ``index`` (a slice or increasing indices), NaN across a row
        where anything is missing."""
        samples = self._samples
        return mover_poses(
            kernel_array(samples.stored_t[index]),
            kernel_array(samples.stored_rotation[index]),
            _missing(samples.missing_rows, index),
            *self._chain(),
        )

    def translations(self, lo: int, hi: int) -> np.ndarray:
        """The translations of :meth:`poses` of samples ``lo:hi`` alone (k, 3)."""
        samples = self._samples
        index = slice(lo, hi)
        return mover_translations(
            kernel_array(samples.stored_t[index]),
            kernel_array(samples.stored_rotation[index]),
            _missing(samples.missing_rows, index),
            *self._chain(),
        )


def _missing(rows: np.ndarray | None, index) -> np.ndarray:
    if rows is None:
        return _NO_ROWS
    # a frame keeps the caller's mask frozen: the kernels read it through a
    # writeable-flagged alias (their one signature), never a copy
    return kernel_alias(np.ascontiguousarray(rows[index]))


def plan(steps, times) -> OneMover | None:
    """An :class:`OneMover` for a chain looked up at ``times`` (its matched
    timestamps), or None where the engine must look it up itself."""
    moving = [k for k, (frame, _) in enumerate(steps) if frame.track is not None]
    if len(moving) != 1:
        return None
    frame, _ = steps[moving[0]]
    # the mover's own samples, every one of them, in its own order: the
    # engine then reads its stored rows (slices), nothing is interpolated
    if frame.discrete or times is not frame.track:
        return None
    return OneMover(steps, moving[0])
