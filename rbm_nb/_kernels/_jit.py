"""Kernels declare what they compile: one signature each, known in advance.

Every numba function of :mod:`rbm_nb._kernels` is created by one of two
decorators:

* :func:`kernel` for functions called from Python. It takes the argument
  types of the one signature the kernel is compiled for (spelled with the
  aliases below, e.g. ``@kernel(F2, F1)`` for a C-contiguous (n, k) and an
  (n,) float64 array) and records it in :data:`DECLARED`. The door
  (:mod:`rbm_nb._door.unpack`) hands kernels exactly those types, so a call never
  compiles another variant; :mod:`rbm_nb._kernels._warmup` compiles exactly the
  declared signatures; and ``tests/test_zz_kernel_signatures.py`` fails if
  the test suite made numba compile anything else.
* :func:`helper` for functions only called from other kernels (compiled as
  part of them, for whatever scalar types they receive).

Nothing is compiled at decoration time (numba compiles on first call, or the
warm-up compiles the declared signature, both from the on-disk cache when it
is there).

A kernel's signature compiles at most once over all processes sharing a
cache folder (the set-up's background compile, notebook kernels, test
processes): see :func:`rbm_nb._infra.numba_cache.compile_once`.
"""

from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, TypeVar

from numba import njit

from .._infra import numba_cache as _numba_cache
from .._infra.config import KERNEL, JitOptions

__all__ = [
    "DECLARED",
    "HELPERS",
    "Declared",
    "kernel",
    "helper",
    "compiled_as",
    "F",
    "I",
    "B",
    "F1",
    "F2",
    "F3",
    "I1",
    "S1",
    "B2",
    "RF1",
    "RI1",
]

# numba type strings for the argument types kernels take: C-contiguous,
# writeable arrays ("::1" in the last dimension) and plain scalars
F = "float64"
I = "int64"  # noqa: E741 - the conventional short name next to F and B
B = "boolean"
F1 = "float64[::1]"
F2 = "float64[:, ::1]"
F3 = "float64[:, :, ::1]"
I1 = "int64[::1]"
S1 = "int8[::1]"  # one sign code per sample (signed_rows)
B2 = "boolean[:, ::1]"
# read-only C-contiguous arrays, for the few kernels that only read an
# argument users often hand over read-only (timestamps from an xarray or
# pandas index): the door passes them a read-only view (``_door.read_only``)
# whatever the caller's array is, so that they, too, compile one signature
RF1 = "Array(float64, 1, 'C', readonly=True)"
RI1 = "Array(int64, 1, 'C', readonly=True)"

_Func = TypeVar("_Func", bound=Callable[..., Any])


@dataclass(frozen=True)
class Declared:
    """A kernel and the argument types of the one signature it compiles."""

    dispatcher: Any
    argtypes: tuple[str, ...]

    @property
    def name(self) -> str:
        return f"{self.dispatcher.py_func.__module__}.{self.dispatcher.__name__}"

    @property
    def signature(self) -> str:
        """The argument types as numba parses them: ``"(float64[::1], ...)"``."""
        return "(" + ", ".join(self.argtypes) + ",)"


# module name -> kernels, in definition order
DECLARED: dict[str, list[Declared]] = {}
# module name -> helpers (compiled only inside kernels)
HELPERS: dict[str, list[Any]] = {}


def kernel(*argtypes: str, options: JitOptions = KERNEL) -> Callable[[_Func], _Func]:
    """Compile the decorated function with numba, declaring its one signature.

    Parameters
    ----------
    *argtypes : str
        numba type strings of the arguments, one per parameter.
    options : JitOptions
        The option set from :mod:`rbm_nb._infra.config`.
    """

    def decorate(func: _Func) -> _Func:
        dispatcher = njit(**options.as_kwargs())(func)
        _compile_once(dispatcher)
        DECLARED.setdefault(func.__module__, []).append(Declared(dispatcher, argtypes))
        return dispatcher

    return decorate


def _compile_once(dispatcher: Any) -> None:
    # numba's dispatcher calls self.compile(...) for a call it has no
    # overload for (and the warm-up calls it directly): an attribute of the
    # instance comes first, so every compile of the kernel takes the lock.
    # Under NUMBA_DISABLE_JIT=1 njit gives the plain function: nothing to lock.
    original = getattr(dispatcher, "compile", None)
    if original is None:
        return

    def compile(sig: Any, wait: bool = True) -> Any:
        return _numba_cache.compile_once(dispatcher, original, sig, wait=wait)

    dispatcher.compile = compile


def helper(
    func: _Func | None = None, *, inline: bool = False, options: JitOptions = KERNEL
) -> Any:
    """Compile a function called only from kernels (``@helper`` or ``@helper(...)``).

    ``inline=True`` inlines it into every caller at numba's IR level (the
    branch-free conversion loops need that to vectorise).
    """

    def decorate(f: _Func) -> _Func:
        opts = options.inlined() if inline else options
        dispatcher = njit(**opts.as_kwargs())(f)
        HELPERS.setdefault(f.__module__, []).append(dispatcher)
        return dispatcher

    return decorate if func is None else decorate(func)


def declared_kernels() -> list[Declared]:
    """Every declared kernel of every kernel module (importing them all)."""
    package = __name__.rpartition(".")[0]
    for info in pkgutil.iter_modules(importlib.import_module(package).__path__):
        if not info.name.startswith("_"):
            importlib.import_module(f"{package}.{info.name}")
    return [k for kernels in DECLARED.values() for k in kernels]


def compiled_as(
    name: str, doc: str | None, body: Callable[..., Any]
) -> Callable[..., Any]:
    """``body`` under its kernel's own name, for a serial kernel and its twin.

    A kernel with a prange twin is one body made twice (for one chunk and
    for many) and decorated twice, with and without ``parallel``. numba's
    cache files go by the function's name and source line, not by its
    compile options: under one name the twin would load the serial
    kernel's code (or the reverse). Each compilation therefore gets its
    own name.
    """
    body.__name__ = body.__qualname__ = name
    body.__doc__ = doc
    return body
