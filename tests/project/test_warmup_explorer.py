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
NOTEBOOK = REPO / "notebooks" / "06_head_eye_explorer.ipynb"

# Lists the kernels this process has an overload of (the explorer's calls).
_LISTED = (
    "import json\n"
    "from rbm_nb._kernels._jit import declared_kernels\n"
    "print('KERNELS' + json.dumps(sorted(k.name.removeprefix('rbm_nb._kernels.')"
    " for k in declared_kernels() if k.dispatcher.signatures)))\n"
)


def _run_notebook(tmp_path: Path, env: dict[str, str], synthetic: bool) -> set[str]:
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    nb = nbformat.read(NOTEBOOK, as_version=4)
    if synthetic:
        first = next(c for c in nb.cells if c.cell_type == "code")
        assert "explorer.load_head_eye()" in first.source
        first.source = first.source.replace(
            "explorer.load_head_eye()", 'explorer.load_head_eye("synthetic")'
        )
    nb.cells.append(nbformat.v4.new_code_cell(_LISTED))
    old = dict(os.environ)
    os.environ.update(env)  # the kernel inherits this process's environment
    try:
        client = nbclient.NotebookClient(
            nb,
            timeout=900,
            kernel_name="python3",
            resources={"metadata": {"path": str(tmp_path)}},
        )
        client.execute()
    finally:
        os.environ.clear()
        os.environ.update(old)
    text = "".join(o.get("text", "") for o in nb.cells[-1].outputs)
    return set(json.loads(text[text.index("KERNELS") + len("KERNELS") :]))


@pytest.mark.slow
@pytest.mark.timeout(1800)
def test_the_explorer_list_is_what_notebook_06_calls(tmp_path, shared_data):
    """Run the notebook in a fresh kernel (real and synthetic data); list its kernels."""
    env = {
        "PYTHONPATH": str(REPO),
        "RBM_NB_DATA_DIR": str(shared_data / "rbm-data"),
    }
    real = _run_notebook(tmp_path, env, synthetic=False)
    synthetic = _run_notebook(tmp_path, env, synthetic=True)
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


def _python(code: str, cache: Path, *args: str) -> str:
    # one thread: the notebook's calls take the serial kernels (EXPLORER), while
    # a plain process on several cores launches the parallel twins for the
    # workload's whole-recording lookups, which the warm-up compiles later
    env = {
        **os.environ,
        "NUMBA_CACHE_DIR": str(cache),
        "PYTHONPATH": str(REPO),
        "RBM_NB_NUM_THREADS": "1",
    }
    done = subprocess.run(
        [sys.executable, "-c", code, *args],
        env=env,
        capture_output=True,
        text=True,
        timeout=1500,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    return done.stdout


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
    """
    order = list(_warmup.EXPLORER)
    results = {}
    for label, names in (("warm-up order", order), ("reversed", order[::-1])):
        cache = tmp_path / label.replace(" ", "-")
        _python(_COMPILE, cache, *names)
        results[label] = _result(_python(_WORKLOAD, cache))
        assert results[label]["compiled"] == 0, (label, results[label])
    # compiled on first use by the process that computes (no cache before)
    results["first use"] = _result(_python(_WORKLOAD, tmp_path / "first-use"))
    assert results["first use"]["compiled"] > 0
    digests = {label: r["sha256"] for label, r in results.items()}
    assert len(set(digests.values())) == 1, digests
