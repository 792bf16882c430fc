"""Run a callback right after a module is imported, without importing it now.

Used to register the ``DataArray.rbm`` accessor the moment xarray is loaded, so
that ``import rbm_nb`` does not have to pay for importing xarray itself.
"""

from __future__ import annotations

import importlib.abc
import importlib.machinery
import sys
from collections.abc import Callable


class _AfterImportFinder(importlib.abc.MetaPathFinder):
    def __init__(self, name: str, callback: Callable[[], None]):
        self.name = name
        self.callback = callback

    def find_spec(self, fullname, path=None, target=None):
        if fullname != self.name:
            return None
        # Let the regular finders locate the module; we only wrap its loader.
        spec = importlib.machinery.PathFinder.find_spec(fullname, path)
        if spec is None or spec.loader is None:
            return None
        loader = spec.loader
        exec_module = loader.exec_module
        finder = self

        def exec_and_notify(module):
            exec_module(module)
            _remove(finder)
            finder.callback()

        loader.exec_module = exec_and_notify  # type: ignore[method-assign]
        return spec


def _remove(finder: _AfterImportFinder) -> None:
    try:
        sys.meta_path.remove(finder)
    except ValueError:
        pass


def call_after_import(name: str, callback: Callable[[], None]) -> None:
    """Call ``callback()`` once ``name`` has been imported (now, if it already is)."""
    if name in sys.modules:
        callback()
        return
    sys.meta_path.insert(0, _AfterImportFinder(name, callback))
