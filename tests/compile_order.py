"""The compile-order check's processes (tests/project/test_warmup_explorer.py).

Three fresh interpreters compile the explorer's kernels, each into an empty
numba cache of its own: in the warm-up's order, in the reverse order, and on
first use by the process that computes. They need nothing from the session,
so ``explorer_compiles`` (a session fixture, see head_start.py) starts them
with the session when the test is selected; the test awaits them, then loads
each order's kernels in a fresh process and compares the bits.
"""

from __future__ import annotations

import functools
import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from head_start import BACKGROUND, low_priority, running, wait_promoting

REPO = Path(__file__).resolve().parents[1]


# What the explorer computes, hashed to the bit; and what this process compiled.
_WORKLOAD = textwrap.dedent(
    """
    import hashlib, json
    import numpy as np
    import rbm_nb as rbm
    from rbm_nb import explorer
    from rbm_nb._kernels._warmup import kernel_stats

    head, left, right, _ = explorer.load_head_eye("synthetic")
    explorer.register_head_eye_frames(head, left, right)
    series = explorer.explorer_series(head, left, right)
    digest = hashlib.sha256()
    for name in sorted(series):
        digest.update(name.encode())
        digest.update(np.ascontiguousarray(series[name].values).tobytes())
    for name in explorer.EYES:
        t, r = rbm.lookup_transform(outof=f"pupil/{name}", into="world")
        digest.update(t.tobytes() + r.tobytes())
        r = r[np.isfinite(r).all(axis=1)]  # the eye's missing rows: no rotation
        sight = rbm.rotate_vectors(r, np.tile([0.0, 0.0, 1.0], (len(r), 1)))
        digest.update(np.ascontiguousarray(sight).tobytes())
    stats = kernel_stats()
    print("RESULT" + json.dumps({"sha256": digest.hexdigest(),
                                 "compiled": stats.compiled, "loaded": stats.loaded}))
    """
)

# Compiles the explorer's kernels in the given order (names), nothing else.
_COMPILE = textwrap.dedent(
    """
    import sys
    from rbm_nb._kernels import _warmup as _warmup
    by_name = {_warmup.short_name(k): k for k in _warmup.declared_kernels()}
    for name in sys.argv[1:]:
        _warmup.compile_signature(by_name[name])
    """
)


def _start(code: str, cache: Path, *args: str, wrap=list) -> subprocess.Popen:
    """Run ``code`` in a fresh interpreter with ``cache`` as numba's cache.

    ``wrap``: the command under a prefix (head_start.low_priority). Its
    output goes to files beside the cache (read by :func:`_outputs`): a
    pipe nobody reads while another process is waited for could fill up.
    """
    # one thread: the notebook's calls take the serial kernels (EXPLORER), while
    # a plain process on several cores launches the parallel twins for the
    # workload's whole-recording lookups, which the warm-up compiles later
    env = {
        **os.environ,
        "NUMBA_CACHE_DIR": str(cache),
        "PYTHONPATH": str(REPO),
        "RBM_NB_NUM_THREADS": "1",
    }
    cache.mkdir(exist_ok=True)
    n = len(list(cache.parent.glob(f"{cache.name}-*.out")))
    out = cache.parent / f"{cache.name}-{n}.out"
    with open(out, "w") as stdout:
        process = subprocess.Popen(
            wrap([sys.executable, "-c", code, *args]),
            env=env,
            stdout=stdout,
            stderr=subprocess.STDOUT,
            text=True,
        )
    process.output = out  # type: ignore[attr-defined]
    return process


def _outputs(processes: list[subprocess.Popen]) -> list[str]:
    """Wait for every process (stopping the rest if one fails); their output."""
    try:
        for process in processes:
            # started with the session in the idle class: promoted while awaited
            mine = functools.partial(running, [process.pid])
            if not wait_promoting(functools.partial(_exited, process), 1500, mine):
                raise subprocess.TimeoutExpired(process.args, 1500)
    finally:
        for process in processes:
            if process.poll() is None:
                process.kill()
                process.wait()
    outputs = [process.output.read_text() for process in processes]
    for process, out in zip(processes, outputs, strict=True):
        assert process.returncode == 0, out
    return outputs


def _exited(process: subprocess.Popen, seconds: float) -> bool:
    try:
        process.wait(timeout=seconds)
    except subprocess.TimeoutExpired:
        return False
    return True


def _result(out: str) -> dict:
    line = next(x for x in out.splitlines() if x.startswith("RESULT"))
    return json.loads(line[len("RESULT") :])


EXPLORER_ORDERS = ("warm-up order", "reversed")


@pytest.fixture(scope="session")
def explorer_compiles(tmp_path_factory):
    """(caches by order, the three compiling processes: orders', then first use)."""
    from rbm_nb._kernels import _warmup

    root = tmp_path_factory.mktemp("compile-order")
    order = list(_warmup.EXPLORER)
    orders = dict(zip(EXPLORER_ORDERS, (order, order[::-1]), strict=True))
    caches = {label: root / label.replace(" ", "-") for label in orders}
    processes = [
        _start(_COMPILE, caches[label], *names, wrap=low_priority)
        for label, names in orders.items()
    ] + [_start(_WORKLOAD, root / "first-use", wrap=low_priority)]
    BACKGROUND.update(p.pid for p in processes)
    try:
        yield caches, processes
    finally:
        for process in processes:
            if process.poll() is None:
                process.kill()
            process.wait()
