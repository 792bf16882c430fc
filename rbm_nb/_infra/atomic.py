"""Writing files so that a failure never damages what was there before.

Every writer in rbm_nb (rosbags, netCDF caches, HTML exports) goes through
:func:`atomic_path`: it writes into a hidden scratch folder beside the target
and moves the result into place only once everything has been written.

What this guarantees, even if the process is killed at any instant:

* The target is never absent and never half-written. A file is replaced with
  one ``rename``. A folder (ROS2 bags are folders) is swapped in with Linux's
  ``renameat2(RENAME_EXCHANGE)`` where the kernel and file system have it;
  elsewhere the old folder is parked in the scratch folder, the new one
  renamed in, and a kill between the two is repaired by the next write to the
  same folder (the parked folder is put back).
* Symbolic links are written through: the file or folder the link points to
  is replaced and the link stays. The permission bits of what is replaced are
  kept (a 0600 file stays 0600).
* The new data is flushed to disk (``fsync`` of every file and folder written)
  before the rename, and the folder holding the target after it.
* Scratch folders left by killed processes (``.<name>.<pid>-<host>_<random>.tmp``)
  are removed by the next write to the same folder: at once if their process
  is gone, after :data:`STALE_AFTER` seconds without change otherwise (the pid
  may have been reused, or belong to another machine or container sharing the
  folder).
* Errors name the target the user asked for, never the hidden scratch path.
* A folder already at the target is replaced only if the writer says it is
  one of its own kind (a ROS2 bag folder for the rosbag writer, see
  :class:`FolderKind`); any other folder is refused before anything is
  written, and again at the swap, so no writer ever deletes a folder it did
  not make. A folder is never put in place of a file either.
"""

from __future__ import annotations

import ctypes
import errno
import os
import re
import shutil
import stat
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, NamedTuple

#: seconds after which a scratch folder whose owner cannot be told apart from
#: a live process (or with the older name without pid) counts as abandoned
STALE_AFTER = 6 * 3600.0

#: name of the old folder while it is parked in the scratch folder
PARKED = ".previous"

_AT_FDCWD = -100
_RENAME_EXCHANGE = 2
# errno values meaning "this kernel/file system cannot exchange": fall back
_NO_EXCHANGE = {errno.ENOSYS, errno.EINVAL, errno.EOPNOTSUPP, errno.ENOTSUP}
# errors of writing whose message may carry no path: they are about the target
_WRITE_ERRNOS = {
    errno.ENOSPC,
    errno.EDQUOT,
    errno.EFBIG,
    errno.EROFS,
    errno.EIO,
    errno.EACCES,
    errno.EPERM,
}

# scratch names: .<name>.<pid>-<host>_<random>.tmp, where <host> (8 hex) tells
# this machine and pid namespace from others sharing the folder (a pid is only
# meaningful there), and the older .<name>.<random>.tmp; <random> is
# tempfile.mkdtemp's 8 characters of [a-z0-9_]
_SCRATCH = re.compile(
    r"^\.(?P<name>.+)\.(?P<pid>\d+)-(?P<host>[0-9a-f]{8})_[a-z0-9_]{8}\.tmp$"
)
_LEGACY_SCRATCH = re.compile(r"^\.(?P<name>.+)\.[a-z0-9_]{8}\.tmp$")


class FolderKind(NamedTuple):
    """The kind of folder a writer makes, so it may replace one of its own.

    Attributes
    ----------
    name : str
        Said in errors: "a ROS2 bag folder (metadata.yaml and storage files)".
    test : callable
        ``test(path) -> bool``: is the existing folder at ``path`` of this kind?
    """

    name: str
    test: Callable[[Path], bool]


def check_replaceable(
    target: str | os.PathLike, folder_kind: FolderKind | None = None
) -> None:
    """Raise unless what is at ``target`` may be replaced by this writer.

    A file may be replaced by a file; a folder only by a writer whose
    ``folder_kind`` recognises it. Writers call this before doing any work, so
    that a refusal costs nothing; :func:`atomic_path` checks again at the swap.

    Raises
    ------
    IsADirectoryError
        ``target`` is a folder this writer did not make.
    NotADirectoryError
        ``target`` is a file and the writer makes a folder.
    """
    target = Path(target)
    real = Path(os.path.realpath(target))
    old = _stat(real)
    if old is None:
        return
    if stat.S_ISDIR(old.st_mode):
        if folder_kind is None:
            raise IsADirectoryError(
                errno.EISDIR,
                "refusing to replace a folder (everything in it would be lost); "
                "give a file name",
                str(target),
            )
        if not folder_kind.test(real):
            raise IsADirectoryError(
                errno.EISDIR,
                f"refusing to replace a folder that is not {folder_kind.name} "
                "(everything in it would be lost); give another path, or remove "
                "the folder yourself",
                str(target),
            )
    elif folder_kind is not None:
        raise NotADirectoryError(
            errno.ENOTDIR,
            f"refusing to replace a file with {folder_kind.name}; give another path",
            str(target),
        )


# a folder written without a declared kind replaces nothing that exists
_UNDECLARED_FOLDER = FolderKind("a folder this writer declared", lambda path: False)


def _stat(path: Path):
    try:
        return os.stat(path)
    except (FileNotFoundError, NotADirectoryError):
        return None


@contextmanager
def atomic_path(
    target: str | os.PathLike, *, folder_kind: FolderKind | None = None
) -> Iterator[Path]:
    """Yield a temporary path that replaces ``target`` only if the block succeeds.

    The temporary path has the name of the file finally written (``target``,
    or what it links to) inside a hidden folder beside it, on the same file
    system, so the final rename is atomic and leftovers can be recognised. It may become a file or a
    folder. If the block raises, ``target`` is left exactly as it was and the
    scratch folder is removed.

    Parameters
    ----------
    target : str or os.PathLike
        The file or folder to create or replace. If it is a symbolic link,
        the link's destination is replaced and the link kept.
    folder_kind : FolderKind, optional
        For writers of folders: the kind of existing folder they may replace.
        Without it, an existing folder at ``target`` is never replaced.

    Yields
    ------
    Path
        Where to write.

    Raises
    ------
    IsADirectoryError, NotADirectoryError
        What is at ``target`` is not something this writer may replace (see
        :func:`check_replaceable`); raised before the block runs.
    OSError
        From creating, writing or renaming, with ``filename`` and message
        naming ``target`` (not the hidden scratch path).
    """
    target = Path(target)
    check_replaceable(target, folder_kind)
    real = Path(os.path.realpath(target))
    if os.path.islink(target) and not real.parent.is_dir():
        # a dangling link: its destination's folders are not ours to create
        raise FileNotFoundError(
            errno.ENOENT,
            f"the link points to {str(real)!r}, whose folder does not exist",
            str(target),
        )
    try:
        real.parent.mkdir(parents=True, exist_ok=True)
        clean_stale_scratch(real.parent)
        scratch = Path(
            tempfile.mkdtemp(
                dir=real.parent, prefix=scratch_prefix(real.name), suffix=".tmp"
            )
        )
    except OSError as err:
        _reraise(err, _naming_target(err, target, None))
    # named like the file finally written, so leftovers can be recognised
    new = scratch / real.name
    try:
        try:
            yield new
        except BaseException as err:
            _reraise(err, _renamed(err, target, scratch, new))
        try:
            _commit(new, real, scratch, target, folder_kind)
        except OSError as err:
            _reraise(err, _naming_target(err, target, scratch))
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def _reraise(err: BaseException, new: BaseException):
    if new is err:
        raise err
    # the hidden scratch path is an implementation detail: do not chain it in
    raise new from None


# ---------------------------------------------------------------------------
# committing
# ---------------------------------------------------------------------------


def _commit(
    new: Path, real: Path, scratch: Path, target: Path, folder_kind: FolderKind | None
) -> None:
    if not os.path.lexists(new):
        raise FileNotFoundError(errno.ENOENT, "nothing was written", str(target))
    # again: something may have appeared at the target while we wrote
    made_folder = new.is_dir() and not new.is_symlink()
    if made_folder:
        check_replaceable(target, folder_kind or _UNDECLARED_FOLDER)
    else:
        check_replaceable(target, None)
    old = _lstat(real)
    if old is not None:
        _keep_mode(new, old)
    _fsync_tree(new)
    folder_swap = old is not None and (
        stat.S_ISDIR(old.st_mode) or (new.is_dir() and not new.is_symlink())
    )
    if folder_swap:
        _swap_in(new, real, scratch)
    else:
        os.replace(new, real)  # atomic for files (and over nothing)
    _fsync_dir(real.parent)


def _swap_in(new: Path, real: Path, scratch: Path) -> None:
    """Put ``new`` at ``real``, where a folder (or file) already is."""
    if _exchange(new, real):
        return  # the old one is now at ``new``, inside the scratch folder
    # no exchange here: park the old one, rename the new one in; a kill in
    # between is repaired by the next write (see clean_stale_scratch)
    parked = scratch / PARKED
    os.replace(real, parked)
    _fsync_dir(real.parent)
    try:
        os.replace(new, real)
    except BaseException:
        os.replace(parked, real)
        raise


def _exchange(a: Path, b: Path) -> bool:
    """Swap two paths atomically; False if this system cannot."""
    func = _renameat2()
    if func is None:
        return False
    rc = func(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE)
    if rc == 0:
        return True
    code = ctypes.get_errno()
    if code in _NO_EXCHANGE:
        return False
    raise OSError(code, os.strerror(code), str(b))


_RENAMEAT2: list[Any] = []  # cache: [function or None]


def _renameat2():
    if not _RENAMEAT2:
        func = None
        try:
            libc = ctypes.CDLL(None, use_errno=True)
            func = libc.renameat2  # glibc >= 2.28 (Linux >= 3.15)
            func.argtypes = [
                ctypes.c_int,
                ctypes.c_char_p,
                ctypes.c_int,
                ctypes.c_char_p,
                ctypes.c_uint,
            ]
            func.restype = ctypes.c_int
        except (OSError, AttributeError):
            func = None
        _RENAMEAT2.append(func)
    return _RENAMEAT2[0]


def _lstat(path: Path):
    try:
        return os.lstat(path)
    except FileNotFoundError:
        return None


def _keep_mode(new: Path, old: os.stat_result) -> None:
    """Give ``new`` the permission bits (and, as root, the owner) of ``old``."""
    os.chmod(new, stat.S_IMODE(old.st_mode))
    if hasattr(os, "geteuid") and os.geteuid() == 0:
        try:
            os.chown(new, old.st_uid, old.st_gid)
        except OSError:
            pass  # best effort: the data matters more than the owner


# ---------------------------------------------------------------------------
# flushing
# ---------------------------------------------------------------------------


def _fsync_tree(path: Path) -> None:
    if path.is_symlink():
        return
    if path.is_dir():
        for root, dirs, files in os.walk(path):
            for name in files:
                _fsync_file(Path(root) / name)
            for name in dirs:
                _fsync_dir(Path(root) / name)
        _fsync_dir(path)
    else:
        _fsync_file(path)


def _fsync_file(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _fsync_dir(path: Path) -> None:
    flags = os.O_RDONLY | getattr(os, "O_DIRECTORY", 0)
    try:
        fd = os.open(path, flags)
    except OSError:
        return  # some systems cannot open folders; nothing more can be done
    try:
        os.fsync(fd)
    except OSError as err:
        if err.errno not in (errno.EINVAL, errno.EBADF):
            raise
    finally:
        os.close(fd)


# ---------------------------------------------------------------------------
# scratch folders left behind by killed processes
# ---------------------------------------------------------------------------


def clean_stale_scratch(folder: str | os.PathLike) -> list[Path]:
    """Remove abandoned scratch folders of :func:`atomic_path` in ``folder``.

    A scratch folder is abandoned if the process named in it (on this machine
    and in this pid namespace) no longer runs, or if nothing in it changed for
    :data:`STALE_AFTER` seconds. Only folders with our
    naming whose content is what :func:`atomic_path` puts there (the target's
    name and/or a parked old version) are touched. If a folder was killed
    between parking the old version and renaming the new one in, the old
    version is put back first.

    Returns
    -------
    list of Path
        The scratch folders removed.
    """
    folder = Path(folder)
    removed: list[Path] = []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return removed
    now = time.time()
    for entry in entries:
        match = _SCRATCH.match(entry.name) or _LEGACY_SCRATCH.match(entry.name)
        if match is None or not entry.is_dir(follow_symlinks=False):
            continue
        name = match.group("name")
        path = Path(entry.path)
        if not _looks_like_ours(path, name) or not _abandoned(entry, match, now):
            continue
        full = _target_name(path, name)
        if full is None:
            continue  # a parked folder whose target's name was cut: keep it
        try:
            _restore_parked(path, folder / full)
        except OSError:
            continue  # keep it: the parked folder is the user's data
        shutil.rmtree(path, ignore_errors=True)
        if not path.exists():
            removed.append(path)
    return removed


def _looks_like_ours(path: Path, name: str) -> bool:
    """Holds only the target (``name`` as in the scratch name) and/or a parked one."""
    try:
        entries = os.listdir(path)
    except OSError:
        return False
    return all(e == PARKED or scratch_name(e) == name for e in entries)


def _target_name(path: Path, name: str) -> str | None:
    """The full name of the target of a scratch folder; None if it cannot be told."""
    if scratch_name(name) == name:
        return name  # not cut
    try:
        entries = [e for e in os.listdir(path) if e != PARKED]
    except OSError:
        return None
    return entries[0] if entries else None


#: bytes of the target's name kept in a scratch folder's name: the rest of
#: it (pid, host, random part, dots) takes at most 36 more, far within the
#: 255 bytes file systems allow, and the whole path stays short (sqlite
#: refuses paths over 512 bytes)
_NAME_BYTES = 32


def scratch_name(name: str) -> str:
    """``name`` as it appears in a scratch folder's name.

    Names longer than :data:`_NAME_BYTES` bytes are cut and end in ``~`` and
    8 hex digits of their hash, so a legal 255-byte name can still be written.
    """
    raw = os.fsencode(name)
    if len(raw) <= _NAME_BYTES:
        return name
    import hashlib

    digest = hashlib.sha1(raw).hexdigest()[:8]
    cut = os.fsdecode(raw[: _NAME_BYTES - 9])
    # a UTF-8 character cut in half decodes to surrogates: drop them
    while cut and "\udc80" <= cut[-1] <= "\udcff":
        cut = cut[:-1]
    return f"{cut}~{digest}"


def scratch_target(target: str | os.PathLike) -> Path:
    """The longest path :func:`atomic_path` may write to for ``target``."""
    real = Path(os.path.realpath(target))
    pid = "9" * 7  # pids are at most 7 digits (pid_max <= 4194304)
    folder = f".{scratch_name(real.name)}.{pid}-{host_tag()}_{'x' * 8}.tmp"
    return real.parent / folder / real.name


def scratch_prefix(name: str) -> str:
    """Start of the name of a scratch folder this process makes for ``name``."""
    return f".{scratch_name(name)}.{os.getpid()}-{host_tag()}_"


_HOST_TAG: list[str] = []  # cache: [tag]


def host_tag() -> str:
    """8 hex digits naming this machine and pid namespace."""
    if not _HOST_TAG:
        import hashlib
        import socket

        try:
            namespace = os.stat("/proc/self/ns/pid").st_ino
        except OSError:
            namespace = 0
        key = f"{socket.gethostname()}:{namespace}".encode()
        _HOST_TAG.append(hashlib.sha1(key).hexdigest()[:8])
    return _HOST_TAG[0]


def _abandoned(entry: os.DirEntry, match: re.Match, now: float) -> bool:
    fields = match.groupdict()
    if fields.get("host") == host_tag() and not _alive(int(fields["pid"])):
        return True  # its writer is gone
    # someone else's pid, or no pid: only the age tells
    return now - _newest_mtime(Path(entry.path)) > STALE_AFTER


def _newest_mtime(path: Path) -> float:
    """Latest modification anywhere in a scratch folder (a writer still at work
    touches the files it writes, not the folder itself)."""
    newest = 0.0
    for root, dirs, files in os.walk(path):
        for name in [root, *(os.path.join(root, f) for f in files + dirs)]:
            try:
                newest = max(newest, os.lstat(name).st_mtime)
            except OSError:
                pass
    return newest


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True  # exists, owned by someone else
    except OSError:
        return True  # cannot tell: keep it (the age bound still applies)
    return True


def _restore_parked(scratch: Path, target: Path) -> None:
    parked = scratch / PARKED
    if os.path.lexists(parked) and not os.path.lexists(target):
        os.replace(parked, target)
        _fsync_dir(target.parent)


# ---------------------------------------------------------------------------
# errors that name the target
# ---------------------------------------------------------------------------


def _mentions(err: OSError, scratch: Path | None) -> bool:
    if scratch is None:
        return True
    inside = str(scratch)
    return any(
        isinstance(f, (str, bytes, os.PathLike)) and os.fsdecode(f).startswith(inside)
        for f in (err.filename, err.filename2)
    )


def _naming_target(err: OSError, target: Path, scratch: Path | None) -> OSError:
    """``err`` as the same kind of OSError, about ``target``."""
    if err.errno is None:
        return err
    if not _mentions(err, scratch) and not (
        err.filename is None and err.errno in _WRITE_ERRNOS
    ):
        return err
    # OSError(errno, ...) picks the matching subclass (PermissionError, ...)
    new = OSError(err.errno, err.strerror or os.strerror(err.errno), str(target))
    if not isinstance(new, type(err)):
        try:
            new = type(err)(err.errno, new.strerror, str(target))
        except Exception:
            return err
    return new


# errors of libraries that say "disk full" without a path or an errno
# (sqlite3, used by ROS2 bags): lowercase text -> errno
_NO_PATH_ERRORS = {"database or disk is full": errno.ENOSPC}


def _renamed(
    err: BaseException, target: Path, scratch: Path, new: Path
) -> BaseException:
    """An error from inside the block, with the scratch path replaced by ``target``."""
    if isinstance(err, OSError):
        return _naming_target(err, target, scratch)
    if not isinstance(err, Exception):
        return err
    message = str(err)
    for text, code in _NO_PATH_ERRORS.items():
        if text in message.lower():
            return OSError(code, f"{os.strerror(code)} ({message})", str(target))
    if str(scratch) not in message:
        return err
    text = message.replace(str(new), str(target))
    text = text.replace(str(scratch), str(target.parent))
    try:
        renamed = type(err)(text)
    except Exception:
        return err
    return renamed
