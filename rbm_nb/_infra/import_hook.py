"""Two import-system hooks the package root installs.

* :func:`call_after_import` runs a callback right after a module is imported,
  without importing it now: the ``DataArray.rbm`` accessor is registered the
  moment xarray is loaded, so ``import rbm_nb`` does not pay for xarray.
* :func:`alias_modules` keeps a module importable under the path it had
  before it moved into a sub-package (``rbm_nb.frames`` is
  ``rbm_nb.core.frames``): both names give the same module object, so
  classes, registries and monkeypatching agree whichever name was used.
"""

from __future__ import annotations

import importlib.abc
import importlib.machinery
import sys
from collections.abc import Callable, Mapping


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


class _AliasLoader(importlib.abc.Loader):
    """Loads an old module path by importing the new one and handing it back."""

    def __init__(self, target: str):
        self.target = target

    def create_module(self, spec):
        # the import system keeps the module's own __name__, __spec__ and
        # __file__ (it only fills in attributes a module lacks)
        return importlib.import_module(self.target)

    def exec_module(self, module) -> None:
        """Nothing to run: the module was executed under its own name."""


class _AliasFinder(importlib.abc.MetaPathFinder):
    def __init__(self, package: str, moved: Mapping[str, str]):
        self.targets = {
            f"{package}.{old}": f"{package}.{new}" for old, new in moved.items()
        }

    def find_spec(self, fullname, path=None, target=None):
        new = self.targets.get(fullname)
        if new is None:
            return None
        return importlib.machinery.ModuleSpec(fullname, _AliasLoader(new))


def alias_modules(package: str, moved: Mapping[str, str]) -> None:
    """Make ``package.<old>`` import ``package.<new>`` for each ``old: new``.

    Nothing is imported now; the finder answers only for those exact names.
    """
    sys.meta_path.insert(0, _AliasFinder(package, moved))
