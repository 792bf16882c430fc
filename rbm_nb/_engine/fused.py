"""Chains evaluated by the fused kernels (:mod:`rbm_nb._kernels.fused`).

A chain of steps (frame, inverse) becomes a *plan*: its runs of static
steps composed once into single transforms (by the ``compose`` function the
caller hands in, :func:`rbm_nb._engine.chain.compose`, which imports this
module), and its moving frames (at most :data:`~rbm_nb._kernels.fused.SLOTS`)
in slots. The fused kernels then
evaluate and compose the whole chain per output row, allocating nothing
but their result. Chains with more moving frames return None from
:func:`plan` and take the unfused path of :mod:`rbm_nb._engine.chain`.

Squad tables are per frame's samples (:class:`~rbm_nb._engine.frame_data.Samples`,
kept here in a weak mapping: a table goes with its samples), created empty (zeroed pages cost nothing until
touched) and filled by the kernels one segment at a time, as segments are
first used: registering a frame computes no coefficients, and a lookup
computes only those of the segments it needs. Calls that may fill a table
hold one lock, so that two threads never write the same row; calls that
read only rows known to be computed (a complete table, or intervals a
parallel call's prefill reported) run without it, as nothing writes those
rows again.

Long calls run the kernels' ``prange`` twins (``rbm_nb._infra.parallel.launch``
decides); the twins only read the tables, so a parallel call that may fill
first runs ``prefill_chain`` (under the lock, in the same launch).
"""

from __future__ import annotations

import threading
import weakref
from typing import Any

import numpy as np

from .._infra import memory as _memory
from .._infra import parallel as _parallel
from .._kernels import fused as kf
from .._kernels import velocity_chain as kv
from .frame_data import FrameData, Samples

__all__ = ["Plan", "plan", "lookup", "transform", "body_rates"]

_NS_PER_S = 1e9
_EMPTY_TIMES = np.zeros(1)
_EMPTY_T = np.zeros((1, 3))
_EMPTY_R = np.array([[1.0, 0.0, 0.0, 0.0]])
_EMPTY_SIGNS = np.ones(1, dtype=np.int8)
_EMPTY_TABLE = np.ones((1, kf.TABLE_COLUMNS))
_EMPTY_SLOT = (_EMPTY_TIMES, _EMPTY_T, _EMPTY_SIGNS, _EMPTY_R, _EMPTY_TABLE)
_TABLE_LOCK = threading.Lock()
# prefill_chain takes the chain kernels' arguments up to the target times
_PREFILL_ARGS = len(kf.CHAIN) + 1


class _Table:
    """A frame's squad table, and what is known to be computed in it.

    ``complete``: every row is computed. ``filled``: disjoint, sorted row intervals
    ``(start, stop)`` all computed (recorded by parallel calls, whose prefill
    reports them): a call that reads only rows inside them needs no lock.
    ``computed``: the number of computed rows, exact while ``counted`` and
    never more than the truth. A long call that could fill this table alone
    adds the kernel's count of new rows; the kernels report one sum for all
    tables, so after a call that may have filled several (a short call, or
    several tables unfilled) the count comes from a scan instead.
    """

    __slots__ = ("rows", "filled", "computed", "counted")

    def __init__(self, n: int) -> None:
        # (huge page aligned: a first lookup of the 66k-sample head recording
        # took 1,434 page faults in all, 608 once its table was aligned)
        self.rows = _memory.zeros((n, kf.TABLE_COLUMNS))
        self.filled: list[tuple[int, int]] = []
        self.computed = 0
        self.counted = True

    def clear(self) -> None:
        """Forget every computed row (as if the frame were just registered)."""
        self.rows[:] = 0.0
        self.filled = []
        self.computed = 0
        self.counted = True

    def update(self) -> None:
        """Count the computed rows (a pass over the state column)."""
        self.computed = int(np.count_nonzero(self.rows[:, kf.TABLE_COLUMNS - 1]))
        self.counted = True

    @property
    def complete(self) -> bool:
        # (an undercount never says complete wrongly)
        return self.computed == len(self.rows)

    def add_computed(self, rows: int) -> None:
        """Record that a call computed ``rows`` more rows of this table alone.

        Each row is computed once (under the table lock), so the count is
        exact while ``counted``; otherwise the table is scanned.
        """
        if not self.counted:
            self.update()
            return
        self.computed += rows

    def add(self, start: int, stop: int) -> None:
        """Record rows start:stop as computed (merged with touching intervals)."""
        kept = []
        for a, b in self.filled:
            if b < start or a > stop:
                kept.append((a, b))
            else:
                start, stop = min(a, start), max(b, stop)
        kept.append((start, stop))
        # a new list, bound at once: readers without the lock see old or new
        self.filled = sorted(kept)

    def covers(self, start: int, stop: int) -> bool:
        """Whether rows start:stop are known to be computed."""
        return self.complete or any(a <= start and stop <= b for a, b in self.filled)


# The squad table of each frame's samples. Samples never change, and a frame
# keeps its samples through every change of its value (a new parent, name or
# option), so a table lives as long as the samples it was made for.
_TABLES: weakref.WeakKeyDictionary[Samples, _Table] = weakref.WeakKeyDictionary()


def table_of(frame: FrameData) -> _Table:
    """The squad table of a moving frame's samples (made empty at first use)."""
    table = _TABLES.get(frame.samples)
    if table is None:
        assert frame.track is not None  # (tables are for moving frames)
        table = _TABLES.setdefault(frame.samples, _Table(len(frame.track)))
    return table


class Plan:
    """A chain prepared for the fused kernels."""

    __slots__ = ("code", "statics", "frames", "kinds", "tables", "_slots")

    def __init__(self, code, statics, frames, kinds, tables) -> None:
        self.code = code
        self.statics = statics
        self.frames = frames
        self.kinds = kinds
        self.tables = tables
        self._slots: tuple[np.ndarray, ...] | None = None

    def arguments(self, offsets: np.ndarray, own) -> tuple[Any, ...]:
        """The kernels' leading arguments: chain code, statics, offsets, gaps,
        own runs and the slot arrays.

        The slot arrays are the same at every call (a frame's value and its
        table never change): gathered once.
        """
        slots = self._slots
        if slots is None:
            slots = self._slots = self.slots()
        return (self.code, self.statics, offsets, self.gaps(), _own(own)) + slots

    def slots(self) -> tuple[Any, ...]:
        """The 5 slot arguments for the kernels (``kf.pack_slots``)."""
        out: list[Any] = []
        for frame, table in zip(self.frames, self.tables, strict=True):
            c = table.rows if table is not None else _EMPTY_TABLE
            out.append((frame.track.base, frame.t, frame.signs, frame.rotation, c))
        out += [_EMPTY_SLOT] * (kf.SLOTS - len(self.frames))
        return kf.pack_slots(out)

    def offsets(self, target) -> np.ndarray:
        """Per slot, what to add to the target's base times (``Track.base_in``)."""
        tt = target.track
        off = np.zeros(kf.SLOTS)
        for k, frame in enumerate(self.frames):
            origin = frame.track.origin
            if tt.kind != "numeric" and origin != tt.origin:
                off[k] = (tt.origin - origin) / _NS_PER_S
        return off

    def gaps(self) -> np.ndarray:
        """Per slot, the frame's ``max_gap`` (inf: none)."""
        out = np.full(kf.SLOTS, np.inf)
        for k, frame in enumerate(self.frames):
            if frame.max_gap is not None:
                out[k] = frame.max_gap
        return out

    def unfilled(self, base: np.ndarray, offsets: np.ndarray, own) -> list[_Table]:
        """The tables a call at target times ``base`` may have to fill.

        A table is left out when the rows the call can read are known to be
        computed: the segments between those of the earliest and the latest
        target time (and the last row, which squad reads before the first
        sample). A frame evaluated at its own sample times on the same time
        origin reads no row at all.
        """
        out: list[_Table] = []
        span = None
        for k, (frame, table) in enumerate(zip(self.frames, self.tables, strict=True)):
            if table is None or table.complete:
                continue
            if own[k] and offsets[k] == 0.0:
                continue  # every target time is one of its sample times exactly
            if span is None:
                if len(base) == 0:
                    return out
                # (a track's times are increasing: no pass over them)
                span = float(base[0]), float(base[-1])
            times = frame.track.base
            n = len(times)
            lo, hi = np.searchsorted(times, np.add(span, offsets[k]), side="right") - 1
            inside = hi < 0 or table.covers(max(int(lo), 0), int(hi) + 1)
            if not (inside and (lo >= 0 or table.covers(n - 1, n))):
                out.append(table)
        return out


def plan(steps, compose) -> Plan | None:
    """The plan of a chain, or None if it has no moving frame or too many.

    ``steps`` iterates (FrameData, inverse) pairs; ``compose(run)`` composes
    a run of static steps into (t (1, 3), r (1, 4)). The caller keeps the
    plan (:class:`rbm_nb._engine.chain.Chain` holds it with its steps).
    """
    return _build(steps, compose)


def _build(steps, compose) -> Plan | None:
    moving = [f for f, _ in steps if f.track is not None]
    if not moving or len(moving) > kf.SLOTS:
        return None
    code: list[int] = []
    statics: list[np.ndarray] = []
    frames: list[Any] = []
    kinds: list[int] = []
    tables: list[_Table | None] = []
    run: list[Any] = []

    def flush() -> None:
        if run:
            t, r = compose(run)
            statics.append(np.concatenate([t[0], r[0]]))
            code.extend((kf.STATIC, len(statics) - 1, 0))
            run.clear()

    for frame, inverse in steps:
        if frame.track is None:
            run.append((frame, inverse))
            continue
        flush()
        if frame.discrete:
            kind, table = kf.HELD, None
        elif len(frame.track) < 2:
            kind, table = kf.CONSTANT, None
        else:
            kind, table = kf.SQUAD, table_of(frame)
        code.extend((kind, len(frames), 1 if inverse else 0))
        frames.append(frame)
        kinds.append(kind)
        tables.append(table)
    flush()
    stat = np.array(statics) if statics else np.zeros((1, 7))
    return Plan(np.array(code, dtype=np.int64), stat, frames, kinds, tables)


def _run(p: Plan, serial, parallel, args: tuple[Any, ...], target, offsets, own):
    """``serial(*args)`` or its prange twin (``_parallel.launch``), tables kept safe.

    A short call (serial) holds the table lock. A long one that reads only
    table rows known to be computed runs without it: nothing writes those
    rows again. Otherwise it holds the lock, and a parallel call first fills
    every table row it will read
    (``prefill_chain``, also on all threads), so that the twin's threads
    only read the tables; the intervals it filled are recorded.
    """
    base = target.track.base
    if len(base) < _parallel.MIN_ROWS:
        # a serial call (launch's choice for so few rows): the lock costs less
        # than finding out whether it is needed (unfilled: tens of µs, most
        # of a one-row lookup). The tables are not rescanned for completeness
        # (a pass over every row): rows computed here are found computed by
        # any later call, and a long call's prefill records them.
        with _TABLE_LOCK:
            result = serial(*args)
            if result[-1]:
                # rows of some of the plan's tables, uncounted (see _Table)
                for table in p.tables:
                    if table is not None:
                        table.counted = False
        return result
    unfilled = p.unfilled(base, offsets, own)
    if not unfilled:
        return _parallel.launch(serial, parallel, len(base), *args)
    reports = []

    def prefilled(*a: Any):
        computed, filled = kf.prefill_chain(*a[:_PREFILL_ARGS])
        reports.append(filled)
        *result, late = parallel(*a)
        return (*result, late + computed)

    with _TABLE_LOCK:
        result = _parallel.launch(serial, prefilled, len(base), *args)
        for filled in reports:
            for slot, start, stop in filled.tolist():
                table = p.tables[slot]
                if table is not None:
                    table.add(start, stop)
        if result[-1]:
            if len(unfilled) == 1:
                # only this table could take rows: the kernel's count is its
                # own (a scan of the 66k-row head table took 0.2-0.6 ms)
                unfilled[0].add_computed(result[-1])
            else:
                for table in unfilled:
                    table.update()
    return result


def _own(own) -> np.ndarray:
    out = np.zeros(kf.SLOTS, dtype=np.int64)
    out[: len(own)] = own
    return out


def lookup(p: Plan, target, own, rotation_only: bool = False):
    """(t (m, 3) or (0, 3), r (m, 4)) of a planned chain at the target times.

    ``own[k]``: 1 + the index of the first target time among slot k's
    frame's samples if the target times are a run of them
    (``chain._same_times``), else 0.
    """
    base = target.track.base

    offsets = p.offsets(target)
    args: tuple[Any, ...] = p.arguments(offsets, own) + (base, rotation_only)
    t, r, _ = _run(
        p, kf.lookup_chain, kf.lookup_chain_parallel, args, target, offsets, own
    )
    return t, r


def transform(p: Plan, target, own, data: np.ndarray, kind: str) -> np.ndarray:
    """Points, vectors or quaternions (m|1, k, c) carried through a planned chain.

    ``own`` as for :func:`lookup`.
    """
    mode = {"points": 0, "vectors": 1, "quaternions": 2}[kind]
    base = target.track.base

    offsets = p.offsets(target)
    args: tuple[Any, ...] = p.arguments(offsets, own) + (base, data, mode)
    out, _ = _run(
        p, kf.transform_chain, kf.transform_chain_parallel, args, target, offsets, own
    )
    return out


def body_rates(p: Plan, target, own, in_reference: bool):
    """Angular velocity (m, 3) of a planned chain at its target times, or None.

    The spline estimate of :func:`rbm_nb._engine.velocity.angular_velocity`
    (quaternion mode), in the moving frame's axes or, if ``in_reference``,
    the reference's, computed without the chain's rotations in memory
    (:func:`rbm_nb._kernels.velocity_chain.chain_body_rates`). None if a
    row's rotation is missing or zero: the caller's step-by-step estimate
    handles those. ``target`` has at least 4 strictly increasing times.
    """
    base = target.track.base
    offsets = p.offsets(target)
    axes = kv.REFERENCE if in_reference else kv.BODY
    args: tuple[Any, ...] = p.arguments(offsets, own) + (base, axes)
    rates, bad, _ = _run(
        p,
        kv.chain_body_rates,
        kv.chain_body_rates_parallel,
        args,
        target,
        offsets,
        own,
    )
    return None if bad else rates
