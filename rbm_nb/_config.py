"""Options shared by every numba kernel, kept in one place.

``cache=True`` writes compiled kernels next to the sources (or to
``NUMBA_CACHE_DIR``) so that only the very first call in a fresh environment
pays for compilation. ``fastmath`` stays off: the kernels are compared against
plain-numpy twins to 1e-12 and fastmath reorders floating-point sums.
"""

from __future__ import annotations

NJIT_OPTIONS = {"cache": True, "fastmath": False, "nogil": True}

# Quaternions whose norm differs from 1 by less than this are normalised
# silently (recorded data is stored with ~4-7 significant digits); beyond it the
# public functions raise instead of guessing what the caller meant.
UNIT_QUATERNION_TOLERANCE = 1e-2
