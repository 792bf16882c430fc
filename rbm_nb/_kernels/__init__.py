"""numba kernels: unchecked, C-contiguous writeable float64 in, arrays out.

Nothing here validates its input; the public modules do that before calling
in, through the door (:mod:`rbm_nb._door.unpack`). Nothing here compiles at import
time either: kernels compile on first call, or in the warm-up
(``python -m rbm_nb._kernels._warmup``), both from numba's on-disk cache when it is
there.

Modules, by role:

* arithmetic inlined everywhere: ``scalar`` (sin/cos/atan2 and short
  series), ``search`` (the one galloping search of sorted times);
* arrays of rotations and transforms: ``quaternion`` (quaternion algebra,
  slerp/squad), ``conversions`` (rotation representations, vectorised;
  ``euler`` and ``conversion_rows`` beside it), ``rotations`` (checked
  rotations, rotation vectors), ``se3``, ``evaluation``, ``sdf``;
* time series: ``resample`` (interpolation, holding, chain composition,
  applying transforms to blocks), ``differences`` (finite differences,
  splines, outliers), ``times``, ``rows`` (the door's counting passes);
* squad over a stored series in one pass: ``squad_walk`` (the kernels and
  the walk), ``squad_segments`` (setting a block's segments up),
  ``squad_rows`` (evaluating its rows);
* the fused chain: ``fused`` (the kernels called from Python, each serial
  and prange pair from one body), ``chain_block`` (a block of rows through
  every step; the slot arguments), ``chain_rows`` (the block's scratch and
  its vector passes), ``squad_table`` (the lazily filled squad table),
  ``chain_prefill`` (the table rows a parallel call reads, filled first);
  ``velocity_chain`` and ``velocity_fused`` (angular velocity of a chain);
* the scene: ``simplify`` (a 3D path's worst-segment-first split).

Adding a kernel module
----------------------
Every numba function is made with one of the decorators of
:mod:`rbm_nb._kernels._jit`, never with ``numba.njit`` directly::

    from ._jit import F, F2, helper, kernel
    from .._infra.config import VECTOR_KERNEL  # only for branch-free vector loops

    @helper(inline=True)          # called only from kernels
    def _distance1(x, y, z):
        ...

    @kernel(F2, F2, F)            # called from Python: ONE signature,
    def signed_distance(points, centers, radius):   # one type per argument
        ...

* ``@kernel(*argtypes)`` declares the argument types of the one signature
  the kernel is compiled for (``F``/``I``/``B`` scalars, ``F1``/``F2``/``F3``
  C-contiguous float64 arrays of 1-3 dimensions, ``I1``, ``B2``; or any numba
  type string). Callers hand it exactly those types: arrays go through
  :func:`rbm_nb._door.unpack.float_array` or :func:`rbm_nb._door.unpack.kernel_array`.
* The module is picked up automatically (any non-underscore module of this
  package): the warm-up compiles its declared signatures, and
  ``tests/test_zz_kernel_signatures.py`` checks that every numba function of
  the module is declared and that the test suite compiled no other
  signature.
* Options come from :mod:`rbm_nb._infra.config` (``KERNEL`` by default,
  ``EXACT_VECTOR_KERNEL`` for loops that must vectorise and keep scalar
  rounding, ``VECTOR_KERNEL`` where fused multiply-adds are measured
  harmless, ``PARALLEL_KERNEL`` for prange twins); scalar math comes from
  :mod:`rbm_nb._kernels.scalar` (one implementation of each function), the
  search of sorted times from :mod:`rbm_nb._kernels.search`.
* A kernel with a prange twin is written once, as a body whose prange loop
  runs over chunks of rows (``fused._lookup_body``): compiled without
  ``parallel`` with one chunk it is the serial kernel, with ``parallel`` and
  many chunks the twin (each compilation under its own name, so that numba's
  cache files do not collide).
"""

from .._infra.numba_cache import configure as _configure_numba_cache

_configure_numba_cache()  # before any kernel is decorated: a writable cache or none
