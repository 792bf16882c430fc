"""Kernels compile only what they declare (see rbm_nb._kernels._jit).

The module is named so that it runs last in a session over ``tests/``: by
then the suite has called every kernel through the public API, and any call
that handed a kernel other argument types (a read-only array, an int64
array, a non-contiguous view, a float32...) shows up as an extra signature.
Run alone, it checks what this process has compiled so far.
"""

from __future__ import annotations

import importlib
import json
import os
import pkgutil
import subprocess
import sys
from pathlib import Path

from numba.core import sigutils
from numba.core.dispatcher import Dispatcher

from rbm_nb import _kernels
from rbm_nb._kernels._jit import HELPERS, declared_kernels


def _kernel_modules():
    for info in pkgutil.iter_modules(_kernels.__path__):
        if not info.name.startswith("_"):
            yield importlib.import_module(f"{_kernels.__name__}.{info.name}")


def _argtypes(declared):
    args, _ = sigutils.normalize_signature(declared.signature)
    return tuple(args)


def test_every_numba_function_is_a_declared_kernel_or_a_helper():
    kernels = {id(k.dispatcher) for k in declared_kernels()}
    helpers = {id(h) for hs in HELPERS.values() for h in hs}
    for module in _kernel_modules():
        for name, value in vars(module).items():
            if (
                isinstance(value, Dispatcher)
                and value.py_func.__module__ == module.__name__
            ):
                assert id(value) in kernels | helpers, (
                    f"{module.__name__}.{name} is compiled with numba but declared "
                    f"neither with @kernel(...) nor @helper"
                )


def test_each_kernel_declares_one_signature_that_numba_parses():
    kernels = declared_kernels()
    assert len(kernels) > 30
    for k in kernels:
        args = _argtypes(k)
        assert len(args) == k.dispatcher.py_func.__code__.co_argcount, k.name


def undeclared_signatures() -> dict[str, list[str]]:
    """Per kernel, the signatures this process compiled that it does not declare."""
    undeclared = {}
    for k in declared_kernels():
        want = _argtypes(k)
        other = [s for s in k.dispatcher.signatures if tuple(s) != want]
        if other:
            undeclared[k.name] = [str(s) for s in other]
    return undeclared


# a float32 call, then what the check below finds in that process
_FLOAT32_CALL = """
import json, sys
import numpy as np
sys.path.insert(0, sys.argv[1])
from test_zz_kernel_signatures import undeclared_signatures
from rbm_nb._kernels import quaternion as kq
kq.qconj(np.zeros((2, 4), dtype=np.float32))
print("UNDECLARED" + json.dumps(undeclared_signatures()))
"""


def test_a_call_with_other_types_would_be_caught(tmp_path):
    """The check below really sees extra signatures (a float32 call here).

    In a process of its own with a temporary numba cache: the session's own
    kernels, and the checkout's cache, keep only declared signatures.
    """
    done = subprocess.run(
        [sys.executable, "-c", _FLOAT32_CALL, str(Path(__file__).parent)],
        env={**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)},
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    line = next(x for x in done.stdout.splitlines() if x.startswith("UNDECLARED"))
    undeclared = json.loads(line[len("UNDECLARED") :])
    assert list(undeclared) == ["rbm_nb._kernels.quaternion.qconj"], undeclared
    assert "float32" in undeclared["rbm_nb._kernels.quaternion.qconj"][0]


def test_the_session_compiled_only_declared_signatures():
    undeclared = undeclared_signatures()
    listing = "\n".join(f"{name}: {sigs}" for name, sigs in undeclared.items())
    assert not undeclared, (
        f"kernels compiled signatures they do not declare:\n{listing}"
    )
