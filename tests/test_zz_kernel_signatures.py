"""Kernels compile only what they declare (see rbm_nb._kernels._jit).

The module is named so that it runs last in a session over ``tests/``: by
then the suite has called every kernel through the public API, and any call
that handed a kernel other argument types (a read-only array, an int64
array, a non-contiguous view, a float32...) shows up as an extra signature.
Run alone, it checks what this process has compiled so far.
"""

from __future__ import annotations

import importlib
import pkgutil

import numpy as np
from numba.core import sigutils
from numba.core.dispatcher import Dispatcher

from rbm_nb import _kernels
from rbm_nb._kernels._jit import DECLARED, HELPERS, declared_kernels


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


def test_a_call_with_other_types_would_be_caught():
    """The check below really sees extra signatures (a float32 call here)."""
    from rbm_nb._kernels import quaternion as kq

    declared = next(k for k in DECLARED[kq.__name__] if k.dispatcher is kq.qconj)
    before = set(kq.qconj.signatures)
    kq.qconj(np.zeros((2, 4), dtype=np.float32))
    extra = set(kq.qconj.signatures) - before - {_argtypes(declared)}
    assert extra, "a float32 call compiled nothing new"


def test_the_session_compiled_only_declared_signatures():
    undeclared = {}
    for k in declared_kernels():
        want = _argtypes(k)
        other = [s for s in k.dispatcher.signatures if tuple(s) != want]
        if k.dispatcher.py_func.__name__ == "qconj":
            # test_a_call_with_other_types_would_be_caught compiles float32 on purpose
            other = [s for s in other if "float32" not in str(s)]
        if other:
            undeclared[k.name] = [str(s) for s in other]
    listing = "\n".join(f"{name}: {sigs}" for name, sigs in undeclared.items())
    assert not undeclared, (
        f"kernels compiled signatures they do not declare:\n{listing}"
    )
