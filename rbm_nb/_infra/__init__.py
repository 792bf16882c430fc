"""Infrastructure under every layer: nothing here knows about reference frames.

Configuration (``config``), lazy imports and import hooks (``lazy``,
``import_hook``), where numba keeps its cache (``numba_cache``), progress
lines (``progress``), threads and memory (``parallel``, ``memory``), the
folders for data and derived files (``folders``) and writes that never damage
what the user had (``atomic``).
"""
