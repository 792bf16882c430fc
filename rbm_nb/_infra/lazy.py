"""Lazy attributes for packages: import a submodule when one of its names is used.

Every package of rbm_nb resolves its public names this way, so that importing
the package costs nothing until something is actually used (numba, xarray,
ipywidgets and meshcat are all slow to import).
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Iterable, Mapping


def lazy_attributes(
    package: str,
    exports: dict[str, str],
    submodules: Iterable[str] | Mapping[str, str] = (),
) -> tuple[Callable[[str], object], Callable[[], list[str]]]:
    """``__getattr__`` and ``__dir__`` for ``package``.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    exports : dict of str to str
        Public name -> submodule (relative to ``package``) that defines it.
    submodules : iterable of str, or dict of str to str
        Submodules that are themselves attributes of the package; a dict maps
        the attribute's name to the submodule's path relative to ``package``
        when the two differ (``{"frames": "core.frames"}``).
    """
    paths = dict(submodules) if isinstance(submodules, Mapping) else {}
    paths.update((name, name) for name in submodules if name not in paths)

    def __getattr__(name: str):
        if name in exports:
            module = importlib.import_module(f"{package}.{exports[name]}")
            value = getattr(module, name)
            # cache on the package: later lookups don't come back here
            setattr(sys.modules[package], name, value)
            return value
        if name in paths:
            return importlib.import_module(f"{package}.{paths[name]}")
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(exports) | set(paths))

    return __getattr__, __dir__
