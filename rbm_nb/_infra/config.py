"""Options shared by every numba kernel, and the core's numeric tolerances.

Kernels are compiled with one of these option sets, all typed:

* :data:`KERNEL`: ``cache=True`` writes compiled kernels next to the sources
  (or to ``NUMBA_CACHE_DIR``) so that only the very first call in a fresh
  environment pays for compilation; ``nogil=True`` lets threads (and dask's
  threaded scheduler) run kernels side by side; ``fastmath`` stays off: the
  kernels are compared against plain-numpy twins to 1e-12 and fastmath
  reorders floating-point sums.
* :data:`VECTOR_KERNEL`: the same plus ``error_model="numpy"`` (a division
  carries no ZeroDivisionError branch, which would block vectorisation) and
  ``fastmath={"contract"}`` (fused multiply-add only, measured harmless: the
  results stay within one ulp of the libm versions). Used by the branch-free
  conversion loops.
* :data:`EXACT_VECTOR_KERNEL`: :data:`KERNEL` with ``error_model="numpy"``
  alone: loops LLVM must vectorise (counting passes, row passes, the fused
  chain's block passes) lose the ZeroDivisionError branch that would stop
  it, and keep their arithmetic exactly that of scalar code (no fused
  multiply-add: the fused chain's vector passes equal its scalar route bit
  for bit).
* :data:`PARALLEL_KERNEL`: :data:`KERNEL` with ``parallel=True``, for the
  ``prange`` twins of kernels over many rows. They are only ever launched
  through :func:`rbm_nb._infra.parallel.launch`, which picks the serial twin for
  short inputs and whenever a parallel launch would be unsafe.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Final, Literal

from . import numba_cache as _numba_cache


@dataclass(frozen=True)
class JitOptions:
    """Keyword arguments of ``numba.njit`` for one family of kernels."""

    cache: bool = True
    nogil: bool = True
    fastmath: bool | frozenset[str] = False
    error_model: Literal["python", "numpy"] = "python"
    boundscheck: bool | None = None  # None: numba's default (NUMBA_BOUNDSCHECK)
    inline: Literal["never", "always"] = "never"
    parallel: bool = False
    extra: Mapping[str, Any] = field(default_factory=dict)

    def as_kwargs(self) -> dict[str, Any]:
        """The options as keyword arguments for ``numba.njit``."""
        kwargs: dict[str, Any] = {
            # off when no folder is writable for numba's cache (rbm_nb._infra.numba_cache)
            "cache": self.cache and _numba_cache.caching,
            "nogil": self.nogil,
            "fastmath": set(self.fastmath)
            if isinstance(self.fastmath, frozenset)
            else self.fastmath,
            "error_model": self.error_model,
            "inline": self.inline,
        }
        if self.parallel:
            kwargs["parallel"] = True
        if self.boundscheck is not None:
            kwargs["boundscheck"] = self.boundscheck
        kwargs.update(self.extra)
        return kwargs

    def inlined(self) -> JitOptions:
        """The same options for a helper inlined into its callers."""
        return JitOptions(
            self.cache,
            self.nogil,
            self.fastmath,
            self.error_model,
            self.boundscheck,
            "always",
            self.parallel,
            self.extra,
        )


KERNEL: Final = JitOptions()
VECTOR_KERNEL: Final = JitOptions(fastmath=frozenset({"contract"}), error_model="numpy")
EXACT_VECTOR_KERNEL: Final = JitOptions(error_model="numpy")
PARALLEL_KERNEL: Final = JitOptions(parallel=True)


# Quaternions whose norm differs from 1 by less than this are normalised
# silently (recorded data is stored with ~4-7 significant digits); beyond it the
# public functions raise instead of guessing what the caller meant.
UNIT_QUATERNION_TOLERANCE: Final = 1e-2
