"""The warm-up's explorer list is what notebook 06 calls; compile order changes no bit.

Both compile the explorer's kernels from an empty numba cache in fresh
processes (about a minute of one core each, ``fused.lookup_chain`` most of
it), hence slow.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from compile_order import _WORKLOAD, _outputs, _result, _start

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


@pytest.mark.slow
@pytest.mark.timeout(3000)
def test_results_are_the_same_bits_whatever_order_kernels_compiled_in(
    explorer_compiles,
):
    """The explorer's results from kernels compiled in opposite orders, and on first use.

    Kernels share non-inlined helpers (numba caches those separately and
    links a cached one as machine code, an uncached one as IR), so the
    order could in principle change what the optimiser sees.

    The three compiles are independent (one cache folder each), so they run
    side by side, from the start of the session on the core the other tests
    leave idle (compile_order.py); the bits do not depend on what else runs.
    """
    # the three compiles started with the session (compile_order.py)
    caches, compiling = explorer_compiles
    compiled = _outputs(compiling)
    results = {"first use": _result(compiled[-1])}
    assert results["first use"]["compiled"] > 0
    # the same workload loading each order's kernels from its cache
    loaded = _outputs([_start(_WORKLOAD, caches[label]) for label in caches])
    for label, out in zip(caches, loaded, strict=True):
        results[label] = _result(out)
        assert results[label]["compiled"] == 0, (label, results[label])
    digests = {label: r["sha256"] for label, r in results.items()}
    assert len(set(digests.values())) == 1, digests
