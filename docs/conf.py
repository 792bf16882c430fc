"""Sphinx configuration of the rbm_nb documentation site.

Build: ``python -m sphinx -W -b html docs docs/_build/html`` (``tests/project/test_docs.py``
does this with warnings as errors). The notebooks of ``notebooks/`` are copied
in and executed by myst-nb once; their outputs are cached by jupyter-cache in
``docs/_build/.jupyter_cache`` and reused until a notebook changes.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import rbm_nb

DOCS = Path(__file__).resolve().parent
REPO = DOCS.parent

project = "rbm_nb"
author = "rbm_nb developers"
copyright = "2026, rbm_nb developers"
version = release = rbm_nb.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.viewcode",
    "numpydoc",
    "myst_nb",
]
source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}
exclude_patterns = ["_build", "**.ipynb_checkpoints"]
templates_path = ["_templates"]

# -- API reference: one page per public module, generated from the docstrings
autosummary_generate = True
autosummary_ignore_module_all = False  # a module's __all__ says what is public
autodoc_typehints = "none"  # numpydoc's Parameters sections carry the types
# inherited members too: ReferenceFrame's and Transform's methods are in base
# classes (core.frame_*, core.pose_methods); the skip below keeps rbm_nb's own
autodoc_default_options = {
    "members": True,
    "show-inheritance": True,
    "inherited-members": True,
}
numpydoc_show_class_members = False  # autosummary lists them
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

# -- notebooks (copied from ../notebooks: one source of truth)
nb_execution_mode = "cache"
nb_execution_cache_path = str(DOCS / "_build" / ".jupyter_cache")
nb_execution_timeout = 600
nb_execution_raise_on_error = True
nb_execution_in_temp = True  # the explorer writes exports/ beside itself
nb_merge_streams = True

html_theme = "pydata_sphinx_theme"
html_title = f"rbm_nb {release}"
html_static_path = ["_static"]
# Jupyter's widget manager + anywidget, built from npm by js/embed/build.mjs
# into _static/widgets: notebook pages render their saved widgets (3D views
# included: the scene's snapshot is in the saved state) with no kernel and no
# CDN. myst-nb's default loads require.js and the manager from two CDNs.
nb_ipywidgets_js = {"widgets/embed.js": {}}
html_css_files = ["widgets/embed.css"]
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
}


def _copy_notebooks() -> None:
    """Copy notebooks/*.ipynb into docs/notebooks (only those that changed)."""
    target = DOCS / "notebooks"
    target.mkdir(exist_ok=True)
    wanted = set()
    for src in sorted((REPO / "notebooks").glob("*.ipynb")):
        dst = target / src.name
        wanted.add(dst.name)
        if not dst.exists() or dst.read_bytes() != src.read_bytes():
            shutil.copyfile(src, dst)
    for stale in target.glob("*.ipynb"):
        if stale.name not in wanted:
            stale.unlink()


_copy_notebooks()


def _skip_foreign_members(app, what, name, obj, skip, options):
    """Document rbm_nb's own code only, not what a base class generates.

    (matplotlib, for one, writes a ``set`` method into every Artist subclass
    whose docstring uses matplotlib's private Sphinx roles.)
    """
    # where the member is defined: a property's getter, a builtin's class
    defined = getattr(obj, "fget", None) or getattr(obj, "__objclass__", None) or obj
    module = getattr(defined, "__module__", None)
    if what in ("class", "exception") and module and not module.startswith("rbm_nb"):
        return True
    return None


def setup(app):
    app.connect("autodoc-skip-member", _skip_foreign_members)
