"""The pose of a frame in a base, looked up per window of samples, never kept whole.

A scene that drew an hour of a recording used to keep every pose of every
moving object (float64, ~0.65x the loaded data at 3 h). A
:class:`LookedUpTrack` keeps the frames' values (immutable, and held by the
frames anyway) and the few rows a frame's ``max_gap`` hides; the samples of
any run of rows are looked up from the frames when asked for (a chunk around
the playhead, the coarse copy, one pose). At the frames' own timestamps the
engine hands the stored samples back (slices, no interpolation), so a window
is bit for bit the rows of a whole-recording lookup.

Whole-recording passes (bounds, the coarse copy, the path's positions) of
a chain with one moving frame (the explorer's: head -> tracker -> world,
eye -> scene camera -> head) compose that frame's stored rows in one kernel
pass (:mod:`rbm_nb.scene.one_mover`, the engine's bits); other chains are
looked up by the engine in blocks of :data:`BLOCK_ROWS`. Chunks around the
playhead are the engine's windows either way.
"""

from __future__ import annotations

import functools
from collections.abc import Iterator
from typing import Literal

import numpy as np

from .._door import coverage as _coverage
from .._engine import chain as _chain
from .._engine.time import TimeBase, check_compatible
from . import one_mover as _one_mover
from .commands import pose_matrix
from .timekeys import at_or_before

#: rows looked up at once by a whole-recording pass (~0.25 MB of float64 poses)
BLOCK_ROWS = 1 << 12
#: rows of a whole-recording pass of a chain with one moving frame, composed
#: by one kernel call (:mod:`rbm_nb.scene.one_mover`; ~3.7 MB of poses): a
#: few dozen calls per hour of recording instead of hundreds
MOVER_BLOCK_ROWS = 1 << 16
#: picked rows this close (or closer) are looked up in one window: one call of
#: the engine costs about as much as looking up a few thousand rows
JOIN_ROWS = 2048
#: samples per track in the coarse copy sent with a streamed scene's content
#: (``stream.COARSE_SAMPLES``): gathered by the blockwise pass at build and kept
COARSE_SAMPLES = 2000


class LookedUpTrack:
    """The transform of ``frame`` into ``base`` over the chain's timestamps.

    Rows are the samples of the lookup, plus one hidden (NaN) row ``gap``
    seconds after each sample followed by a longer gap (``gap``: the
    smallest ``max_gap`` on the chain), as :class:`~rbm_nb.scene.tracks.PoseTrack`
    has them. Made by :meth:`PoseTrack.lookup` for a frame that moves.
    """

    scale = None  # looked-up poses have no per-sample scale
    static = False

    def __init__(self, frame, base, gap: float | None, name: str):
        self.name = name
        # frames that share no time are refused here, as every lookup's door
        # refuses them (the engine's match takes that as given)
        _coverage.chain_samples(frame.data, base.data)
        self._steps = _chain.chain(frame.data, base.data)
        target = _chain.match([f for f, _ in self._steps])
        # the chain's timestamps: a Track of views of a frame's own times
        self._times = target.track
        self._source = target.source
        # one moving frame looked up at its own samples: whole-recording
        # passes (bounds, coarse copy, a path's blocks) compose its stored
        # rows in one kernel pass, the same bits as the engine's windows
        self._mover = _one_mover.plan(self._steps, self._times)
        self.kind = self._times.kind
        self._ns = self._times.is_datetime
        # the coarse copy's rows and samples (gathered by the bounds' pass)
        self._coarse: tuple[np.ndarray, tuple] | None = None
        self._hidden_after, self._hidden_keys = self._hidden_rows(gap)
        # row position of each hidden row (a_k + 1 + k)
        self._hidden_rows_at = (
            self._hidden_after + 1 + np.arange(len(self._hidden_after))
        )

    # -- time axis ----------------------------------------------------------
    def _hidden_rows(self, gap: float | None) -> tuple[np.ndarray, np.ndarray]:
        """Original indices followed by a gap longer than ``gap``, and the
        sort key of the hidden row after each."""
        none = np.zeros(0, dtype=np.int64)
        if gap is None or len(self._times) < 2:
            return none, self._times.key[:0].copy()
        after = np.zeros(0, dtype=np.int64)
        key = self._times.key
        # blockwise: seconds from the first sample, as PoseTrack's rule has them
        values = self._times.values
        base = TimeBase.of(values[:1]) if self._ns else None
        found = []
        # (element by element: the block's length changes no row found)
        for lo in range(0, len(key) - 1, MOVER_BLOCK_ROWS):
            hi = min(lo + MOVER_BLOCK_ROWS + 1, len(key))
            chunk = values[lo:hi]
            seconds = (
                base.seconds(chunk) if base is not None else chunk.astype(np.float64)
            )
            found.append(np.flatnonzero(np.diff(seconds) > gap) + lo)
        after = np.concatenate(found) if found else after
        if self._ns:
            step = int(round(gap * 1e9))
            keys = key[after] + step
        else:
            keys = key[after] + gap
        return after.astype(np.int64), keys

    def __len__(self) -> int:
        return len(self._times) + len(self._hidden_after)

    @property
    def start(self) -> int | float:
        """Key of the first row."""
        return self._times.key[0].item()

    @property
    def end(self) -> int | float:
        """Key of the last row (a hidden one after the last sample, if any)."""
        last = self._times.key[-1].item()
        if len(self._hidden_keys):
            last = max(last, self._hidden_keys[-1].item())
        return last

    def search(self, key: int | float, side: Literal["left", "right"] = "left") -> int:
        """Rows before time ``key`` (as ``np.searchsorted`` on the rows' keys)."""
        hidden = int(np.searchsorted(self._hidden_keys, key, side=side))
        return int(np.searchsorted(self._times.key, key, side=side)) + hidden

    def index_at(self, key: int | float) -> int:
        """Row of the latest sample at or before time ``key``; -1 before the start."""
        return self.search(at_or_before(key, self.kind), side="right") - 1

    def _split(self, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """For each row: whether it is hidden, and its sample (or hidden row) index."""
        k = np.searchsorted(self._hidden_rows_at, rows, side="left")
        at = self._hidden_rows_at
        hidden = np.zeros(len(rows), dtype=bool)
        inside = k < len(at)
        hidden[inside] = at[k[inside]] == rows[inside]
        return hidden, np.where(hidden, k, rows - k)

    def keys_of(self, rows) -> np.ndarray:
        """Exact keys of ``rows`` (indices), shape (k,)."""
        rows = np.atleast_1d(np.asarray(rows, dtype=np.int64))
        rows = np.where(rows < 0, rows + len(self), rows)
        hidden, index = self._split(rows)
        out = np.empty(len(rows), dtype=self._times.key.dtype)
        out[~hidden] = self._times.key[index[~hidden]]
        out[hidden] = self._hidden_keys[index[hidden]]
        return out

    def sample_keys(self) -> np.ndarray:
        """Exact keys of every row, shape (n,): a whole-recording array,
        made on request (the player's axis, publishers), not kept."""
        if not len(self._hidden_after):
            keys = (
                self._times.key.view()
            )  # a view of the frame's keys: not theirs to change
            keys.flags.writeable = False
            return keys
        return self.keys_of(np.arange(len(self)))

    @property
    def original_timestamps(self) -> np.ndarray:
        """Every row's timestamp as given (made on request, not kept)."""
        values = self._times.values
        if not len(self._hidden_after):
            return values.copy()
        if self._ns:
            step = self._hidden_keys - self._times.key[self._hidden_after]
            extra = values[self._hidden_after] + step.astype("timedelta64[ns]")
        else:
            extra = self._hidden_keys.astype(values.dtype)
        return np.insert(values, self._hidden_after + 1, extra)

    # -- poses ----------------------------------------------------------------
    def _samples(self, lo: int, hi: int) -> tuple[np.ndarray, np.ndarray]:
        """Translation and rotation of samples ``lo:hi`` (fresh float64 arrays,
        NaN across a row where either is missing)."""
        target = _chain.Target(self._times.slice(lo, hi), self._source)
        t, r = _chain.evaluate(self._steps, target)
        n = hi - lo
        t = np.array(np.broadcast_to(t.reshape(-1, 3), (n, 3)), dtype=np.float64)
        r = np.array(np.broadcast_to(r.reshape(-1, 4), (n, 4)), dtype=np.float64)
        missing = _any_nan(t) | _any_nan(r)
        t[missing] = np.nan
        r[missing] = np.nan
        return t, r

    def _mover_translations(self, lo: int, hi: int) -> tuple[np.ndarray, None]:
        """:meth:`_samples`' translations, composed by the one-mover kernel
        (same bits), and no rotations."""
        assert self._mover is not None
        return self._mover.translations(lo, hi), None

    def window(self, lo: int, hi: int):
        """Keys, translation, rotation and scale (None) of rows ``lo:hi``."""
        return self._window(lo, hi, self._samples)

    def _window(self, lo: int, hi: int, look_up):
        """:meth:`window`, the samples looked up by ``look_up(first, last)``."""
        lo, hi = max(lo, 0), min(hi, len(self))
        hi = max(hi, lo)
        first_hidden = int(np.searchsorted(self._hidden_rows_at, lo, side="left"))
        last_hidden = int(np.searchsorted(self._hidden_rows_at, hi, side="left"))
        if first_hidden == last_hidden and hi > lo:
            # no hidden row inside: the samples themselves, one lookup
            first = lo - first_hidden
            t, r = look_up(first, first + hi - lo)
            return self._times.key[first : first + hi - lo], t, r, None
        rows = np.arange(lo, hi)
        hidden, index = self._split(rows)
        samples = index[~hidden]
        keys = np.empty(hi - lo, dtype=self._times.key.dtype)
        t = np.full((hi - lo, 3), np.nan)
        r = np.full((hi - lo, 4), np.nan)
        if len(samples):
            first, last = int(samples[0]), int(samples[-1]) + 1
            st, sr = look_up(first, last)
            t[~hidden] = st
            if sr is not None:  # (a path's blocks: translations alone)
                r[~hidden] = sr
            keys[~hidden] = self._times.key[first:last]
        keys[hidden] = self._hidden_keys[index[hidden]]
        return keys, t, r, None

    def take(self, index):
        """Keys, translation, rotation and scale of rows ``index``: None
        (all), a slice, or increasing indices (looked up in windows of
        nearby rows, at the samples' own times, so that they are the stored
        ones)."""
        if index is None:
            return self.window(0, len(self))
        if isinstance(index, slice):
            lo, hi, _ = index.indices(len(self))
            return self.window(lo, hi)
        rows = np.asarray(index, dtype=np.int64)
        rows = np.where(rows < 0, rows + len(self), rows)
        if self._coarse is not None and np.array_equal(self._coarse[0], rows):
            return self._coarse[1]
        return self._gather(rows)

    def _gather(self, rows: np.ndarray):
        if self._mover is not None:
            return self._gather_composed(rows)
        keys = np.empty(len(rows), dtype=self._times.key.dtype)
        t = np.empty((len(rows), 3))
        r = np.empty((len(rows), 4))
        i = 0
        while i < len(rows):
            j = i + 1
            while (
                j < len(rows)
                and rows[j] - rows[j - 1] <= JOIN_ROWS
                and rows[j] - rows[i] < BLOCK_ROWS
            ):
                j += 1
            lo = int(rows[i])
            ws, wt, wr, _ = self.window(lo, int(rows[j - 1]) + 1)
            at = rows[i:j] - lo
            keys[i:j], t[i:j], r[i:j] = ws[at], wt[at], wr[at]
            i = j
        return keys, t, r, None

    def _gather_composed(self, rows: np.ndarray):
        """:meth:`_gather` by the one-mover kernel: one call at the rows' own
        samples (the engine's values to the bit, hidden rows NaN)."""
        assert self._mover is not None
        hidden, index = self._split(rows)
        t = np.full((len(rows), 3), np.nan)
        r = np.full((len(rows), 4), np.nan)
        shown = ~hidden
        if shown.any():
            t[shown], r[shown] = self._mover.poses(index[shown])
        return self.keys_of(rows), t, r, None

    def matrix(self, index: int = 0) -> np.ndarray:
        _, t, r, _ = self.take([index])
        return pose_matrix(t[0], r[0])

    def missing(self, index: int) -> bool:
        _, t, _, _ = self.take([index])
        return bool(np.isnan(t[0]).any())

    def blocks(self) -> Iterator[np.ndarray]:
        """The translations of every row, in consecutive blocks (of
        :data:`BLOCK_ROWS`, or :data:`MOVER_BLOCK_ROWS` composed by the
        one-mover kernel)."""
        if self._mover is not None:
            for lo in range(0, len(self), MOVER_BLOCK_ROWS):
                yield self._window(lo, lo + MOVER_BLOCK_ROWS, self._mover_translations)[
                    1
                ]
            return
        for lo in range(0, len(self), BLOCK_ROWS):
            yield self.window(lo, lo + BLOCK_ROWS)[1]

    def _windows(self) -> Iterator[tuple[int, tuple]]:
        for lo in range(0, len(self), BLOCK_ROWS):
            yield lo, self.window(lo, lo + BLOCK_ROWS)

    def positions_with_gaps(self) -> np.ndarray:
        """Every row's translation, shape (n, 3), NaN where missing: a
        whole-recording array made on request (a path's line), not kept."""
        out = np.empty((len(self), 3))
        lo = 0
        for block in self.blocks():
            out[lo : lo + len(block)] = block
            lo += len(block)
        return out

    def positions(self) -> np.ndarray:
        """The translations of the rows that are not missing, as (n, 3)."""
        points = self.positions_with_gaps()
        return points[~np.isnan(points[:, 0])]

    @functools.cached_property
    def bounds(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, int] | None:
        """As :attr:`PoseTrack.bounds`, exact (the mean too, bit for bit: the
        camera's target), and the coarse copy (:data:`COARSE_SAMPLES` rows,
        evenly spaced), kept for the snapshot.

        A chain with one moving frame: one kernel pass over its stored rows
        (:mod:`rbm_nb.scene.one_mover`) and one call at the coarse rows.
        Otherwise one blockwise pass of the engine's lookups, gathering the
        coarse rows on the way."""
        if self._mover is not None:
            picks = even_rows(len(self), COARSE_SAMPLES)
            self._coarse = (picks, self._gather_composed(picks))
            low, high, total, count = self._mover.summary()
            if count == 0:
                return None
            # (a sum in row order from 0.0, as the blockwise pass adds them)
            return low, high, total / count, count
        low = np.full(3, np.nan)
        high = np.full(3, np.nan)
        total = np.zeros((1, 3))
        count = 0
        picks = even_rows(len(self), COARSE_SAMPLES)
        coarse = (
            np.empty(len(picks), dtype=self._times.key.dtype),
            np.empty((len(picks), 3)),
            np.empty((len(picks), 4)),
        )
        for lo, (keys, points, rotations, _) in self._windows():
            first, last = np.searchsorted(picks, [lo, lo + len(points)])
            at = picks[first:last] - lo
            for out, values in zip(coarse, (keys, points, rotations), strict=True):
                out[first:last] = values[at]
            present = ~np.isnan(points[:, 0])
            n = int(present.sum())
            if n == 0:
                continue
            count += n
            # the running total as the first row: numpy adds the rows of an
            # axis-0 reduction in order, so the mean is bit for bit the one
            # of the whole array at once (the camera's target is made of it)
            # (missing rows add 0.0, which changes no sum; ``where=`` is 2x slower)
            kept = np.where(present[:, np.newaxis], points, 0.0)
            total = np.add.reduce(np.vstack([total, kept]), axis=0)
            # contiguous columns: numpy's fast loop (axis 0 of (n, 3) is 60x slower)
            columns = np.ascontiguousarray(points.T)
            low = np.fmin(low, np.fmin.reduce(columns, axis=1))
            high = np.fmax(high, np.fmax.reduce(columns, axis=1))
        self._coarse = (picks, (*coarse, None))
        if count == 0:
            return None
        return low, high, total.reshape(3) / count, count

    def check_kind(self, kind: str | None, what: str) -> None:
        check_compatible([kind, self.kind], what)


def even_rows(n: int, max_samples: int) -> np.ndarray:
    """At most ``max_samples`` (>= 2) evenly spaced rows of ``n``, the last one kept."""
    return np.unique(np.linspace(0, n - 1, max_samples).round().astype(np.int64))


def _any_nan(values: np.ndarray) -> np.ndarray:
    """Rows of ``values`` (n, k) with a NaN (column by column: ``any(axis=1)``
    over k = 3 or 4 is ~4x slower)."""
    out = np.isnan(values[:, 0])
    for k in range(1, values.shape[1]):
        out |= np.isnan(values[:, k])
    return out
