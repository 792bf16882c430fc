"""Importing the explorer loads the dashboard's code in the background.

Each case runs in a fresh interpreter: what a process has loaded depends on
everything it ran before.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import pytest

pytest.importorskip("anywidget")

# after `import rbm_nb.explorer` and the thread's end: which explorer kernels
# have machine code in this process, which the account lists as cached, and
# which modules of MODULES are imported
PROBE = textwrap.dedent(
    """
    import json, sys, threading
    from rbm_nb import explorer
    from rbm_nb.app import explorer_prepare
    started = [t.name for t in threading.enumerate()]
    {before}
    explorer_prepare.wait()
    from rbm_nb._kernels import _warmup
    kernels = _warmup.explorer_kernels()
    cached = _warmup.ready(kernels)
    print(json.dumps({{
        "thread": "rbm-explorer-prepare" in started,
        "loaded": sorted(_warmup.short_name(k) for k in kernels if k.dispatcher.overloads),
        "cached": sorted(_warmup.short_name(k) for k in kernels if _warmup.key(k) in cached),
        "compiled": sum(sum(k.dispatcher.stats.cache_misses.values()) for k in kernels),
        "modules": [m in sys.modules for m in explorer_prepare.MODULES],
    }}))
    """
)


def _probe(before: str = "", **env: str) -> dict:
    code = PROBE.format(before=before)
    done = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        timeout=600,
        env={**os.environ, **env},
        check=False,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_importing_the_explorer_loads_its_cached_kernels_and_modules():
    seen = _probe(RBM_NB_PREPARE="1")  # (the test session turns it off)
    assert seen["thread"]
    assert seen["cached"], "the set-up's warm-up leaves the explorer's kernels cached"
    # every cached explorer kernel is loaded, none compiled
    assert seen["loaded"] == seen["cached"]
    assert seen["compiled"] == 0
    assert all(seen["modules"])


def test_a_kernel_not_in_the_cache_is_left_alone():
    # as on a fresh install whose warm-up has not reached the kernels yet:
    # the loading must not compile them (minutes), only load what is there
    hide = (
        "import rbm_nb._kernels._warmup as _w; _w.ready = lambda kernels=None: {}; "
        "print('LOADED', explorer_prepare.load_cached_kernels())"
    )
    seen = _probe(before=hide, RBM_NB_PREPARE="0")
    assert not seen["thread"]
    assert seen["loaded"] == []
    assert seen["compiled"] == 0


def test_the_variable_turns_the_thread_off():
    seen = _probe(RBM_NB_PREPARE="0")
    assert not seen["thread"]
    assert seen["loaded"] == []
