"""Where the first lookup after registration spends its time (issue 16).

Issue 16 asks for the first ``lookup_transform("left_eye", "world")`` on
freshly registered frames to cost at most 1.5x the steady state. The first
call computes the head's squad table (66k segments, 15 float64 each) as it
goes; the eye is read at its own sample times and needs no table. This
script splits that call, on one thread, into

1. its parts: the steady state; the first call; the first call with the
   head table's memory already faulted in (so the difference is the
   table's page faults and zeroing); that fault-in alone; the first call
   with the table already complete (what is left: plan, output, checks);
2. the table fill itself, loop by loop: a copy of the fill's block
   (``_kernels.fused._fill_block``) that returns before loop k, run over
   the whole head recording into a table whose memory is already touched;
   the difference between consecutive prefixes is loop k's cost.

Part 2 compiles a staged copy of the block's source; it checks that the
copy has the loops named below and that, run to the end, it writes the
same rows as ``squad_table``, and stops if either changed.

Run:  RBM_NB_DATA_DIR=../shared/data/rbm-data RBM_NB_NUM_THREADS=1 \
      .venv/bin/python benchmarks/bench_first_lookup.py
"""

from __future__ import annotations

import ast
import inspect
import re
import sys
import textwrap
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))

import bench_fused  # noqa: E402  (the head/eye workload)

ROUNDS = 9
REPEATS = 20
# the top-level loops of _fill_block, in order
FILL_LOOPS = (
    "gather the block's samples",
    "sampling intervals",
    "their inverses",
    "logs of the steps (series)",
    "logs off the series (exact route)",
    "control points a",
    "control points b",
    "arcs r[i] -> r[i+1]",
    "arcs of repeated samples",
    "arcs a -> b",
    "store the rows (exact route where needed)",
)


def _ms(seconds: float) -> str:
    return f"{seconds * 1e3:6.2f} ms"


def parts() -> None:
    import rbm_nb as rbm
    from rbm_nb._engine import fused as FU
    from rbm_nb._kernels import fused as kf
    from rbm_nb.core import frames as F

    name, (frames, *_rest) = bench_fused.workload()
    print(f"== the first lookup_transform left_eye->world, in parts ({name})")

    def lookup() -> float:
        t0 = time.perf_counter()
        rbm.lookup_transform("left_eye", "world")
        return time.perf_counter() - t0

    def head():
        return F.resolve_frame("head")

    times: dict[str, list[float]] = {
        "steady state": [],
        "first call": [],
        "first call, head table memory already faulted in": [],
        "  fault-in of the head table alone": [],
        "first call, head table already complete": [],
    }
    for _ in range(ROUNDS):
        bench_fused.register(rbm, frames)
        times["first call"].append(lookup())
        times["steady state"].append(lookup())

        bench_fused.register(rbm, frames)
        t0 = time.perf_counter()
        FU.table_of(head().data).rows[:, 0] = 0.0  # one write per page (and cache line)
        times["  fault-in of the head table alone"].append(time.perf_counter() - t0)
        times["first call, head table memory already faulted in"].append(lookup())

        bench_fused.register(rbm, frames)
        h = head()
        table = FU.table_of(h.data)
        table.rows[...] = kf.squad_table(
            h.data.signs, h.data.rotation, h.data.track.base
        )
        table.update()  # (complete: the scan is outside the timing)
        times["first call, head table already complete"].append(lookup())
    steady = min(times["steady state"])
    for label, values in times.items():
        print(
            f"  {label:<52} {_ms(min(values))}  ({min(values) / steady:4.2f}x steady)"
        )
    print(f"  (minimum of {ROUNDS} rounds each)")


def _staged_fill():
    """The fill's block with ``if stage <= k: return`` before its loop k, and
    a driver running it over a whole recording."""
    import numba

    from rbm_nb._kernels import squad_table as kst

    # the fill's block is its stages, inlined: their loops, in order
    stages = (
        kst._block_logs,
        kst._block_control_points,
        kst._block_arcs,
        kst._block_store,
    )
    source = "def staged_block(stage, sg, rp, t, c, i0, i1, s):\n    m = i1 - i0\n"
    for stage_helper in stages:
        fn = ast.parse(textwrap.dedent(inspect.getsource(stage_helper.py_func))).body[0]
        body = fn.body[1:] if isinstance(fn.body[0], ast.Expr) else fn.body
        source += (
            textwrap.indent("\n".join(ast.unparse(b) for b in body), "    ") + "\n"
        )
    lines, k = [], 0
    for line in source.splitlines():
        if re.match(r"    for ", line):
            lines.append(f"    if stage <= {k}:\n        return")
            k += 1
        lines.append(line)
    if k != len(FILL_LOOPS):
        raise SystemExit(
            f"_fill_block has {k} top-level loops, this script names {len(FILL_LOOPS)}: "
            "update FILL_LOOPS"
        )
    namespace = dict(vars(kst))
    exec("\n".join(lines), namespace)  # noqa: S102 - the kernel's own source
    block = numba.njit(error_model="numpy", nogil=True)(namespace["staged_block"])
    rows, width = kst._S_ROWS, kst.FILL_BLOCK

    @numba.njit(error_model="numpy", nogil=True)
    def fill(stage, sg, rp, t, c):
        n = sg.shape[0]
        s = np.zeros((rows, width + 3))
        i = 1
        while i < n - 2:
            j = min(i + width, n - 2)
            block(stage, sg, rp, t, c, i, j, s)
            i = j

    return fill


def fill_loops() -> None:
    import rbm_nb as rbm
    from rbm_nb._kernels import fused as kf
    from rbm_nb.core import frames as F

    _, (frames, *_rest) = bench_fused.workload()
    bench_fused.register(rbm, frames)
    h = F.resolve_frame("head")
    sg, rp, t = h.data.signs, h.data.rotation, h.data.track.base
    fill = _staged_fill()
    table = np.zeros((len(t), kf.TABLE_COLUMNS))
    fill(len(FILL_LOOPS), sg, rp, t, table)
    whole = kf.squad_table(sg, rp, t)
    if not np.array_equal(table[1:-2], whole[1:-2]):
        raise SystemExit("the staged copy no longer fills what squad_table fills")

    def best(stage: int) -> float:
        return bench_fused.best(lambda: fill(stage, sg, rp, t, table), REPEATS)

    t_whole = bench_fused.best(lambda: kf.squad_table(sg, rp, t), REPEATS)
    print(
        f"\n== the head table's fill, loop by loop ({len(t)} segments, "
        f"table memory already touched, best of {REPEATS})"
    )
    previous = best(0)
    print(f"  {'calls and loop set-up':<44} {_ms(previous)}")
    for k, label in enumerate(FILL_LOOPS, start=1):
        now = best(k)
        print(f"  {label:<44} {_ms(now - previous)}")
        previous = now
    print(
        f"  {'all loops':<44} {_ms(previous)}  ({previous / len(t) * 1e9:.0f} ns/segment)"
    )
    print(f"  squad_table (its own fresh table included)   {_ms(t_whole)}")


if __name__ == "__main__":
    parts()
    fill_loops()
