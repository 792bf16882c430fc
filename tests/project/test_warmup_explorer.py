"""The warm-up's explorer list is what notebook 06 calls; compile order changes no bit.

Both compile the explorer's kernels from an empty numba cache in fresh
processes (about a minute of one core each, ``fused.lookup_chain`` most of
it), hence slow.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from rbm_nb._kernels import _warmup

REPO = Path(__file__).resolve().parents[2]

NOTEBOOK = "06_head_eye_explorer.ipynb"


@pytest.mark.slow
@pytest.mark.timeout(1800)
def test_the_explorer_list_is_what_notebook_06_calls(executed_notebook, shared_data):
    """Run the notebook in a fresh kernel (real and synthetic data); list its kernels.

    The two executions are test_notebooks.py's (one per session, see
    tests/notebook_runs.py), which end by listing the kernels their process
    called.
    """
    from notebook_runs import kernels_called

    assert (shared_data / "rbm-data").is_dir()
    executed_notebook.prefetch(NOTEBOOK, "synthetic")  # both at once when alone
    real = kernels_called(executed_notebook(NOTEBOOK, "real"))
    synthetic = kernels_called(executed_notebook(NOTEBOOK, "synthetic"))
    listed = set(_warmup.EXPLORER)
    assert real | synthetic == listed, (
        f"called but not in EXPLORER: {sorted((real | synthetic) - listed)}; "
        f"in EXPLORER but not called: {sorted(listed - real - synthetic)}"
    )


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
        _warmup._compile(by_name[name])
    """
)


def _start(code: str, cache: Path, *args: str) -> subprocess.Popen:
    """Run ``code`` in a fresh interpreter with ``cache`` as numba's cache.

    Its output goes to files beside the cache (read by :func:`_outputs`): a
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
            [sys.executable, "-c", code, *args],
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
            process.wait(timeout=1500)
    finally:
        for process in processes:
            if process.poll() is None:
                process.kill()
                process.wait()
    outputs = [process.output.read_text() for process in processes]
    for process, out in zip(processes, outputs, strict=True):
        assert process.returncode == 0, out
    return outputs


def _result(out: str) -> dict:
    line = next(x for x in out.splitlines() if x.startswith("RESULT"))
    return json.loads(line[len("RESULT") :])


@pytest.mark.slow
@pytest.mark.timeout(3000)
def test_results_are_the_same_bits_whatever_order_kernels_compiled_in(tmp_path):
    """The explorer's results from kernels compiled in opposite orders, and on first use.

    Kernels share non-inlined helpers (numba caches those separately and
    links a cached one as machine code, an uncached one as IR), so the
    order could in principle change what the optimiser sees.

    The three compiles are independent (one cache folder each), so they run
    side by side: on CI's two cores that halves the test's time, and the
    bits do not depend on what else runs.
    """
    order = list(_warmup.EXPLORER)
    orders = {"warm-up order": order, "reversed": order[::-1]}
    caches = {label: tmp_path / label.replace(" ", "-") for label in orders}
    # compiled in the given order into an empty cache; and compiled on first
    # use by the process that computes (no cache before)
    compiled = _outputs(
        [_start(_COMPILE, caches[label], *names) for label, names in orders.items()]
        + [_start(_WORKLOAD, tmp_path / "first-use")]
    )
    results = {"first use": _result(compiled[-1])}
    assert results["first use"]["compiled"] > 0
    # the same workload loading each order's kernels from its cache
    loaded = _outputs([_start(_WORKLOAD, caches[label]) for label in orders])
    for label, out in zip(orders, loaded, strict=True):
        results[label] = _result(out)
        assert results[label]["compiled"] == 0, (label, results[label])
    digests = {label: r["sha256"] for label, r in results.items()}
    assert len(set(digests.values())) == 1, digests
