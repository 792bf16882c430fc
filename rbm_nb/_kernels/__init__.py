"""numba kernels: unchecked, contiguous float64 in, arrays out.

Nothing here validates its input; the public modules do that before calling
in. Nothing here compiles at import time either: ``@njit`` compiles on first
call (and then from the on-disk cache).
"""

from .._numba_cache import configure as _configure_numba_cache

_configure_numba_cache()  # before any kernel is decorated: a writable cache or none
