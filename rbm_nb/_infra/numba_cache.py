"""Where numba keeps rbm_nb's compiled kernels, also when the install is read-only.

The kernels are decorated with ``cache=True``. numba then looks for a folder
it can write to, in this order: ``NUMBA_CACHE_DIR`` if set, ``__pycache__``
beside the kernel sources, and its per-user cache folder (``~/.cache/numba``).
If none is writable -- site-packages and ``HOME`` read-only, as in containers
and on HPC systems -- the decorator itself raises ``RuntimeError: cannot cache
function ...: no locator available`` and the first kernel import dies.

:func:`configure` runs before any kernel is decorated (it is called from
``rbm_nb._kernels``). When numba would find a writable folder it changes
nothing. Otherwise it points ``NUMBA_CACHE_DIR`` at a private folder in the
temporary directory (kept between processes, so a second run loads instead of
compiling), or, when not even that is writable, switches caching off; either
way with one warning that names the folders and says how to choose one.

Users choose the folder with the environment variable ``NUMBA_CACHE_DIR``
before importing rbm_nb.
"""

from __future__ import annotations

import hashlib
import os
import stat
import tempfile
import time
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, NamedTuple

KERNELS = Path(__file__).resolve().parents[1] / "_kernels"

_configured = False

#: False once :func:`configure` found no writable folder; read by
#: :meth:`rbm_nb._infra.config.JitOptions.as_kwargs` when kernels are decorated
caching = True


class NumbaCacheWarning(UserWarning):
    """numba cannot cache where it normally would; rbm_nb chose another way."""


def configure() -> None:
    """Make sure numba can cache rbm_nb's kernels, or turn caching off.

    Idempotent; the first call decides. Imports numba only when the usual
    folders are not writable.

    Warns
    -----
    NumbaCacheWarning
        Once, if the cache had to move to the temporary directory or be turned
        off.
    """
    global _configured
    if _configured:
        return
    _configured = True
    user_dir = os.environ.get("NUMBA_CACHE_DIR", "")
    if user_dir and _writable(Path(user_dir)):
        drop_stale_kernels(Path(user_dir))
        return
    if _writable(KERNELS / "__pycache__"):
        drop_stale_kernels(KERNELS / "__pycache__")
        return
    numba_user_dir = _numba_user_cache_dir()
    if _writable(numba_user_dir):
        drop_stale_kernels(numba_user_dir)
        return
    tried = [str(KERNELS / "__pycache__"), str(numba_user_dir)]
    if user_dir:
        tried.insert(0, f"NUMBA_CACHE_DIR={user_dir}")
    fallback = _private_temp_dir()
    if fallback is not None:
        drop_stale_kernels(fallback)
        _set_numba_cache_dir(fallback)
        outcome = f"compiled kernels are cached in {fallback} instead"
    else:
        _turn_caching_off()
        outcome = (
            "no writable temporary folder either, so kernels are compiled in every "
            "new process (caching is off)"
        )
    warnings.warn(
        f"rbm_nb: numba cannot write its cache to any of {', '.join(tried)}; "
        f"{outcome}. Set the environment variable NUMBA_CACHE_DIR to a writable "
        "folder before importing rbm_nb to choose where.",
        NumbaCacheWarning,
        stacklevel=2,
    )


def _writable(folder: Path) -> bool:
    """Whether ``folder`` exists or can be made, and a file can be written in it.

    The same test numba applies (``makedirs`` and a temporary file); write
    permission bits alone say nothing about read-only mounts.
    """
    try:
        folder.mkdir(parents=True, exist_ok=True)
        tempfile.TemporaryFile(dir=folder).close()
    except OSError:
        return False
    return True


def _numba_user_cache_dir() -> Path:
    """numba's per-user cache folder for rbm_nb's kernels (its own rule)."""
    from numba.misc.appdirs import AppDirs

    return Path(AppDirs(appname="numba", appauthor=False).user_cache_dir)


def _private_temp_dir() -> Path | None:
    """A folder in the temporary directory only this user can write, or None.

    The name is stable, so later processes find what earlier ones compiled.
    numba's cache files are pickles, so a folder someone else could have
    planted or can write to is refused (then a fresh ``mkdtemp`` is used).
    """
    uid = os.getuid() if hasattr(os, "getuid") else 0
    try:
        # raises (FileNotFoundError) itself when no candidate folder is writable
        stable = Path(tempfile.gettempdir()) / f"rbm_nb-numba-cache-{uid}"
        stable.mkdir(mode=0o700, exist_ok=True)
        info = stable.lstat()
        private = (
            stat.S_ISDIR(info.st_mode)
            and (not hasattr(os, "getuid") or info.st_uid == uid)
            and not info.st_mode & (stat.S_IWGRP | stat.S_IWOTH)
        )
        if private and _writable(stable):
            return stable
        return Path(tempfile.mkdtemp(prefix="rbm_nb-numba-cache-"))
    except OSError:
        return None


def _set_numba_cache_dir(folder: Path) -> None:
    # numba re-reads the environment when it compiles, so the variable (not
    # only numba.config.CACHE_DIR) must say it; child processes inherit it.
    os.environ["NUMBA_CACHE_DIR"] = str(folder)
    from numba.core import config

    config.reload_config()


def _turn_caching_off() -> None:
    # read by every option set of rbm_nb._infra.config when a kernel is decorated
    global caching
    caching = False


def kernels_fingerprint() -> str:
    """A hash of every kernel module's source and of numba's version.

    numba keys a cached kernel on its own file only, but kernels inline
    helpers from other modules (``scalar``, ``quaternion``): after an edit of
    one of those, the cache of an unchanged module would serve stale code.
    The warm-up's module (``_warmup.py``: lists and commands, no kernel)
    does not count, so editing its lists keeps the compiled kernels.
    """
    digest = hashlib.sha256()
    # numba ignores entries another numba version wrote; the account of
    # compiles (ACCOUNT) must then start again too
    try:
        from importlib.metadata import version

        digest.update(f"numba {version('numba')}".encode())
    except Exception:  # noqa: BLE001 - no metadata: the sources still count
        pass
    for path in sorted(KERNELS.glob("*.py")):
        if path.name.startswith("_warmup"):
            continue
        digest.update(path.name.encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def drop_stale_kernels(root: Path) -> int:
    """Delete rbm_nb's cached kernels under ``root`` if the sources changed.

    ``root`` is the folder numba caches into (``_kernels/__pycache__`` or a
    ``NUMBA_CACHE_DIR``); a stamp file there remembers the fingerprint of
    the sources the cache was made from. Returns the number of files removed.
    """
    stamp = root / "rbm_nb-kernels.sha256"
    fingerprint = kernels_fingerprint()
    try:
        if stamp.read_text() == fingerprint:
            return 0
    except OSError:
        pass
    removed = 0
    for path in [*root.rglob("*.nb[ic]"), *root.rglob(ACCOUNT)]:
        # under NUMBA_CACHE_DIR numba mirrors the sources' path: keep to ours
        parts = path.parent.parts
        if root == KERNELS / "__pycache__" or (
            "rbm_nb" in parts and "_kernels" in parts
        ):
            try:
                path.unlink()
                removed += 1
            except OSError:
                pass
    try:
        stamp.write_text(fingerprint)
    except OSError:
        pass
    return removed


# -- one compile per signature, across processes ---------------------------
#
# numba alone lets every process that misses the cache compile: a set-up's
# background compile, a notebook's kernel and a test process would each
# compile a kernel none of them has found in the cache yet (a minute for the
# largest). Every declared kernel therefore compiles through
# :func:`compile_once`: an exclusive lock per signature, a file in numba's
# cache folder for that kernel, held while the signature is compiled (or
# loaded). A process that needs a signature another process is compiling
# waits for the lock, then loads what the other one saved.

#: one line per signature compiled (by any process) and per signature a
#: warm-up process loaded: "KEY compiled|loaded SECONDS PID ROLE UNIXTIME"
ACCOUNT = "rbm_nb-compiles.log"
#: the role written in the account; the warm-up's processes set it
ROLE_VARIABLE = "RBM_NB_COMPILE_ROLE"

# keys whose lock this process holds (numba's compiler lock makes one
# thread at a time compile, so a set is enough): a compile that re-enters
# the same signature must not wait for itself
_holding: set[str] = set()


def cache_folder(dispatcher: Any) -> Path | None:
    """The folder numba caches ``dispatcher`` in, or None when it does not cache."""
    path = getattr(getattr(dispatcher, "_cache", None), "cache_path", None)
    return Path(path) if path else None


def signature_key(dispatcher: Any, args: tuple) -> str:
    """``module.function(type,type,...)``: one signature, without spaces."""
    func = dispatcher.py_func
    types = ",".join(str(a).replace(" ", "") for a in args)
    return f"{func.__module__}.{func.__qualname__}({types})"


def _lock_path(folder: Path, key: str) -> Path:
    name, _, _ = key.partition("(")
    digest = hashlib.sha256(key.encode()).hexdigest()[:16]
    return folder / f"{name}-{digest}.lock"


def compile_once(dispatcher: Any, compile_: Any, sig: Any, wait: bool = True) -> Any:
    """Run numba's ``compile_(sig)`` holding ``sig``'s lock; account for it.

    Another process compiling the same signature holds the lock: this one
    waits, and numba then loads the signature from the cache instead of
    compiling it again; with ``wait=False`` it returns None at once instead.
    """
    from numba.core.compiler_lock import global_compiler_lock
    from numba.core.sigutils import normalize_signature

    args, _ = normalize_signature(sig)
    folder = cache_folder(dispatcher)
    if folder is None or dispatcher.overloads.get(tuple(args)) is not None:
        return compile_(sig)
    key = signature_key(dispatcher, tuple(args))
    # numba's own lock first: a thread of this process that waited for our
    # file lock while another thread of it held numba's lock and needed ours
    # would never wake up
    with global_compiler_lock:
        if key in _holding:
            return compile_(sig)
        _holding.add(key)
        try:
            with _file_lock(_lock_path(folder, key), wait) as locked:
                if not locked:
                    return None
                misses = sum(dispatcher.stats.cache_misses.values())
                start = time.perf_counter()
                entry = compile_(sig)
                compiled = sum(dispatcher.stats.cache_misses.values()) > misses
                _account(folder, key, compiled, time.perf_counter() - start)
        finally:
            _holding.discard(key)
    return entry


@contextmanager
def _file_lock(path: Path, wait: bool = True) -> Iterator[bool]:
    """Hold an exclusive lock on ``path``; yields False if busy and not ``wait``."""
    try:
        import fcntl
    except ImportError:  # not POSIX: each process compiles what it misses
        yield True
        return
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o600)
    except OSError:  # the folder is not ours to lock in: numba will say more
        yield True
        return
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | (0 if wait else fcntl.LOCK_NB))
        except BlockingIOError:
            yield False
            return
        yield True
    finally:
        os.close(fd)  # releases the lock


def _account(folder: Path, key: str, compiled: bool, seconds: float) -> None:
    """Append the compile (always) or load (warm-up processes only) to the account."""
    role = os.environ.get(ROLE_VARIABLE, "")
    if not compiled and not role:
        return  # an ordinary process loading from the cache: nothing to say
    line = (
        f"{key} {'compiled' if compiled else 'loaded'} {seconds:.2f} "
        f"{os.getpid()} {role or 'user'} {time.time():.3f}\n"
    )
    try:
        # one write of a short line in append mode: lines of processes that
        # write at the same time do not mix
        fd = os.open(folder / ACCOUNT, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o600)
    except OSError:
        return
    try:
        os.write(fd, line.encode())
    finally:
        os.close(fd)


class AccountRow(NamedTuple):
    key: str
    outcome: str  # "compiled" or "loaded"
    seconds: float
    pid: int
    role: str
    time: float  # when it was written (seconds since the epoch)


def read_account(folder: Path) -> list[AccountRow]:
    """The account's lines (see :data:`ACCOUNT`)."""
    rows: list[AccountRow] = []
    try:
        text = (folder / ACCOUNT).read_text()
    except OSError:
        return rows
    for line in text.splitlines():
        parts = line.split(" ")
        if len(parts) == 6:
            rows.append(
                AccountRow(
                    parts[0],
                    parts[1],
                    float(parts[2]),
                    int(parts[3]),
                    parts[4],
                    float(parts[5]),
                )
            )
    return rows


def sources_mtime() -> float:
    """The latest modification time of a kernel source (numba's cache key)."""
    return max(path.stat().st_mtime for path in KERNELS.glob("*.py"))
