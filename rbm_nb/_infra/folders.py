"""Where rbm_nb reads example data and writes what it derives: the two folders.

``RBM_NB_DATA_DIR`` holds the example files (else pooch's cache folder for
rbm_nb); ``RBM_NB_CACHE_DIR`` receives derived files (else ``derived`` in the
user's cache folder). Both :mod:`rbm_nb.data` (the example store, the
synthetic bag) and :mod:`rbm_nb.ros` (a bag's topic caches) follow these
rules; they live here, below both, so that neither imports the other for them.
"""

from __future__ import annotations

import os
from pathlib import Path

# a folder holding the files (or where they should be downloaded to)
DATA_DIR_ENV = "RBM_NB_DATA_DIR"
# a folder for files rbm_nb derives (synthetic bag, rosbag caches of example
# bags); default: a "derived" folder in the user's cache folder for rbm_nb
CACHE_DIR_ENV = "RBM_NB_CACHE_DIR"


def pooch_module():
    """pooch, or an ImportError that says which extra installs it."""
    try:
        import pooch
    except ImportError:
        raise ImportError(
            "the example data are downloaded with pooch: pip install 'rbm_nb[data]'"
        ) from None
    return pooch


def default_data_dir() -> Path:
    """``RBM_NB_DATA_DIR`` if set (read at each call), else pooch's cache folder."""
    if os.environ.get(DATA_DIR_ENV):
        return env_folder(DATA_DIR_ENV)
    return Path(pooch_module().os_cache("rbm_nb"))


def cache_dir() -> Path:
    """The folder for files rbm_nb derives; never the example-data folder.

    ``RBM_NB_CACHE_DIR`` if set (read at each call), else ``derived`` in the
    user's cache folder for rbm_nb (pooch's ``os_cache("rbm_nb")``, or
    ``~/.cache/rbm_nb`` without pooch). The synthetic example bag and the
    rosbag caches of bags in the example-data folder go here, so that only
    the registry's files are ever written into ``RBM_NB_DATA_DIR``.
    """
    if os.environ.get(CACHE_DIR_ENV):
        return env_folder(CACHE_DIR_ENV)
    try:
        base = Path(pooch_module().os_cache("rbm_nb"))
    except ImportError:
        base = (
            Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "rbm_nb"
        )
    return base / "derived"


def example_data_dirs() -> tuple:
    """Folders that hold example data: ``RBM_NB_DATA_DIR`` and the default store's."""
    folders = set()
    try:
        folders.add(default_data_dir().resolve())
    except ImportError:  # no pooch: no default folder either
        pass
    if os.environ.get(DATA_DIR_ENV):
        folders.add(env_folder(DATA_DIR_ENV).resolve())
    return tuple(folders)


def env_folder(variable: str) -> Path:
    """The folder an environment variable names, ``~`` expanded.

    Raises
    ------
    ValueError
        Naming the variable, if ``~user`` names no user here (the path would
        otherwise be taken as a folder called ``~user`` in the working folder).
    """
    value = os.environ[variable]
    # os.path.expanduser leaves an unknown ~user as it is (Path's raises)
    path = Path(os.path.expanduser(value))
    if str(path).startswith("~"):
        user = str(path).split(os.sep, 1)[0]
        raise ValueError(
            f"{variable}={value!r}: {user} names no user on this machine; set "
            f"{variable} to an absolute path"
        )
    return path
