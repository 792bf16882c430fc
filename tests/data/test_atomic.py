"""Atomic writes (issue 12, items 8-11): kills, links, modes, fsync, leftovers, errors.

The kill tests run a real writer in a subprocess and ``kill -9`` it at random
moments (bounded number of rounds); the read-only and disk-full tests use real
mechanisms that also stop root: an immutable folder (``chattr +i``), a
read-only bind mount and a tiny tmpfs in a private mount namespace
(``unshare --mount``), and ``RLIMIT_FSIZE``. Each is skipped, with the reason,
only where the mechanism is missing on the machine.
"""

from __future__ import annotations

import errno
import os
import random
import shutil
import signal
import stat
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO

from rbm_nb._infra import atomic as _atomic
from rbm_nb._infra.atomic import FolderKind, atomic_path, clean_stale_scratch

# the kind of folder these tests write: only part<k>.txt files
PARTS = FolderKind(
    "a folder of part files",
    lambda path: all(p.name.startswith("part") for p in path.iterdir()),
)


def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = str(REPO) + os.pathsep + env.get("PYTHONPATH", "")
    return env


def _write_folder(path: Path, version: int, files: int = 5, size: int = 2000):
    path.mkdir()
    for k in range(files):
        (path / f"part{k}.txt").write_text(f"{version}\n" + "x" * size)


def _folder_version(path: Path, files: int = 5) -> int:
    """The one version all files of a folder hold (fails if mixed or partial)."""
    names = sorted(p.name for p in path.iterdir())
    assert names == [f"part{k}.txt" for k in range(files)], names
    versions = {p.read_text().split("\n", 1)[0] for p in path.iterdir()}
    assert len(versions) == 1, f"mixed versions in {path}: {versions}"
    return int(versions.pop())


def _scratch_entries(folder: Path):
    return sorted(p.name for p in folder.iterdir() if p.name.endswith(".tmp"))


@pytest.fixture
def no_exchange(monkeypatch):
    """Pretend the system has no renameat2(RENAME_EXCHANGE)."""
    monkeypatch.setattr(_atomic, "_RENAMEAT2", [None])


# -- basic replace ---------------------------------------------------------------


@pytest.mark.parametrize("exchange", [True, False], ids=["exchange", "park"])
def test_folder_replace(tmp_path, monkeypatch, exchange):
    if not exchange:
        monkeypatch.setattr(_atomic, "_RENAMEAT2", [None])
    target = tmp_path / "bag"
    for version in range(3):
        with atomic_path(target, folder_kind=PARTS) as tmp:
            _write_folder(tmp, version)
        assert _folder_version(target) == version
        assert sorted(p.name for p in tmp_path.iterdir()) == ["bag"]


def test_failure_leaves_folder_and_nothing_else(tmp_path):
    target = tmp_path / "bag"
    with atomic_path(target, folder_kind=PARTS) as tmp:
        _write_folder(tmp, 1)
    with pytest.raises(RuntimeError, match="boom"):
        with atomic_path(target, folder_kind=PARTS) as tmp:
            _write_folder(tmp, 2)
            raise RuntimeError("boom")
    assert _folder_version(target) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bag"]


def test_nothing_written_names_the_target(tmp_path):
    with pytest.raises(FileNotFoundError) as info:
        with atomic_path(tmp_path / "out.nc"):
            pass
    assert info.value.filename == str(tmp_path / "out.nc")
    assert ".tmp" not in str(info.value)


# -- links and modes ------------------------------------------------------------------


def test_write_through_file_symlink(tmp_path):
    real = tmp_path / "data" / "scene-v1.html"
    real.parent.mkdir()
    real.write_text("old")
    link = tmp_path / "scene.html"
    link.symlink_to(os.path.relpath(real, tmp_path))
    with atomic_path(link) as tmp:
        tmp.write_text("new")
    assert link.is_symlink()
    assert os.readlink(link) == os.path.relpath(real, tmp_path)
    assert real.read_text() == "new"
    assert sorted(p.name for p in real.parent.iterdir()) == ["scene-v1.html"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["data", "scene.html"]


def test_write_through_chain_of_links_to_a_folder(tmp_path):
    real = tmp_path / "runs" / "bag-3"
    real.parent.mkdir()
    _write_folder(real, 3)
    (tmp_path / "latest").symlink_to(real)
    (tmp_path / "bag").symlink_to(tmp_path / "latest")
    with atomic_path(tmp_path / "bag", folder_kind=PARTS) as tmp:
        _write_folder(tmp, 4)
    assert (tmp_path / "bag").is_symlink() and (tmp_path / "latest").is_symlink()
    assert _folder_version(real) == 4
    assert sorted(p.name for p in real.parent.iterdir()) == ["bag-3"]


def test_dangling_link_is_written_through(tmp_path):
    link = tmp_path / "out.html"
    link.symlink_to(tmp_path / "made-later.html")
    with atomic_path(link) as tmp:
        tmp.write_text("first")
    assert link.is_symlink()
    assert (tmp_path / "made-later.html").read_text() == "first"


@pytest.mark.parametrize("mode", [0o600, 0o640, 0o444, 0o755])
def test_file_mode_is_kept(tmp_path, mode):
    target = tmp_path / "cache.nc"
    target.write_text("old")
    os.chmod(target, mode)
    with atomic_path(target) as tmp:
        tmp.write_text("new")
    assert stat.S_IMODE(os.stat(target).st_mode) == mode
    assert target.read_text() == "new"


def test_folder_mode_is_kept(tmp_path):
    target = tmp_path / "bag"
    _write_folder(target, 0)
    os.chmod(target, 0o700)
    with atomic_path(target, folder_kind=PARTS) as tmp:
        _write_folder(tmp, 1)
    assert stat.S_IMODE(os.stat(target).st_mode) == 0o700


def test_mode_kept_through_a_link(tmp_path):
    real = tmp_path / "real.html"
    real.write_text("old")
    os.chmod(real, 0o600)
    link = tmp_path / "link.html"
    link.symlink_to(real)
    with atomic_path(link) as tmp:
        tmp.write_text("new")
    assert stat.S_IMODE(os.stat(real).st_mode) == 0o600
    assert link.is_symlink() and real.read_text() == "new"


def test_new_file_gets_the_usual_mode(tmp_path):
    old = os.umask(0o022)
    try:
        with atomic_path(tmp_path / "new.html") as tmp:
            tmp.write_text("x")
    finally:
        os.umask(old)
    assert stat.S_IMODE(os.stat(tmp_path / "new.html").st_mode) == 0o644


# -- fsync ------------------------------------------------------------------------


def _record_fsyncs(monkeypatch):
    events = []
    real_fsync, real_replace = os.fsync, os.replace

    def fsync(fd):
        st = os.fstat(fd)
        events.append(("fsync", st.st_ino, stat.S_ISDIR(st.st_mode)))
        return real_fsync(fd)

    def replace(src, dst):
        events.append(("replace", os.lstat(src).st_ino, None))
        return real_replace(src, dst)

    monkeypatch.setattr(os, "fsync", fsync)
    monkeypatch.setattr(os, "replace", replace)
    return events


def test_file_is_synced_before_rename_and_folder_after(tmp_path, monkeypatch):
    target = tmp_path / "scene.html"
    target.write_text("old")
    events = _record_fsyncs(monkeypatch)
    with atomic_path(target) as tmp:
        tmp.write_text("new")
    ino = os.stat(target).st_ino
    folder_ino = os.stat(tmp_path).st_ino
    synced = events.index(("fsync", ino, False))
    renamed = events.index(("replace", ino, None))
    assert synced < renamed
    assert ("fsync", folder_ino, True) in events[renamed:]


def test_folder_tree_is_synced(tmp_path, monkeypatch):
    target = tmp_path / "bag"
    _write_folder(target, 0)
    events = _record_fsyncs(monkeypatch)
    with atomic_path(target, folder_kind=PARTS) as tmp:
        _write_folder(tmp, 1)
        (tmp / "sub").mkdir()
        (tmp / "sub" / "meta.yaml").write_text("x")
    synced = {ino for kind, ino, _ in events if kind == "fsync"}
    for path in [target, target / "sub", *target.rglob("*")]:
        assert os.stat(path).st_ino in synced, path
    assert os.stat(tmp_path).st_ino in synced


# -- stale scratch folders --------------------------------------------------------


def _dead_pid() -> int:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def _ours(name, pid, rand="ab12cd34", host=None):
    """A scratch folder name as a writer with ``pid`` on ``host`` makes it."""
    return f".{name}.{pid}-{host or _atomic.host_tag()}_{rand}.tmp"


def test_stale_scratch_is_cleaned_on_the_next_write(tmp_path):
    dead = _dead_pid()
    old = time.time() - _atomic.STALE_AFTER - 60
    elsewhere = "0123abcd" if _atomic.host_tag() != "0123abcd" else "fedc9876"

    def scratch(name, content=("x.bag",), mtime=None):
        path = tmp_path / name
        path.mkdir()
        for entry in content:
            (path / entry).mkdir()
            (path / entry / "data").write_bytes(b"\0" * 1000)
        if mtime is not None:
            for p in [path, *path.rglob("*")]:
                os.utime(p, (mtime, mtime))

    removed = [
        _ours("x.bag", dead),  # its writer was killed
        _ours("other.nc", dead, "zz_9q0aa"),  # another target in the folder
        _ours("x.bag", dead, "a1b2c3d4", host=elsewhere),  # other host, old
        ".x.bag.k2j4_x9a.tmp",  # older naming, old
    ]
    kept = [
        _ours("x.bag", os.getpid(), "live1111"),  # a live writer
        _ours("x.bag", dead, "b1b2c3d4", host=elsewhere),  # other host, recent
        ".x.bag.recent01.tmp",  # older naming, recent
        _ours("x.bag", dead, "foreign1"),  # content is not ours
        _ours("x.bag", dead, "plainfil"),  # a file, not a folder
    ]
    scratch(removed[0])
    scratch(removed[1], content=("other.nc",))
    scratch(removed[2], mtime=old)
    scratch(removed[3], mtime=old)
    scratch(kept[0])
    scratch(kept[1])
    scratch(kept[2])
    scratch(kept[3], content=("notes",))
    (tmp_path / kept[4]).write_text("a file")
    with atomic_path(tmp_path / "x.bag") as tmp:
        tmp.write_text("bag")
    assert set(_scratch_entries(tmp_path)) == set(kept)
    assert (tmp_path / "x.bag").read_text() == "bag"


def test_a_writer_still_writing_is_not_old(tmp_path):
    """Age counts from the newest change inside, not the folder's own mtime."""
    old = time.time() - _atomic.STALE_AFTER - 60
    name = _ours(
        "x.bag", 1, host="0123abcd" if _atomic.host_tag() != "0123abcd" else "fedc9876"
    )
    path = tmp_path / name
    (path / "x.bag").mkdir(parents=True)
    (path / "x.bag" / "chunk").write_bytes(b"new data")  # just written
    os.utime(path, (old, old))
    os.utime(path / "x.bag", (old, old))
    assert clean_stale_scratch(tmp_path) == []
    os.utime(path / "x.bag" / "chunk", (old, old))
    assert clean_stale_scratch(tmp_path) == [path]


def test_live_scratch_of_another_process_is_kept(tmp_path):
    proc = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        name = _ours("x.nc", proc.pid)
        (tmp_path / name).mkdir()
        assert clean_stale_scratch(tmp_path) == []
        proc.kill()
        proc.wait()
        assert clean_stale_scratch(tmp_path) == [tmp_path / name]
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def test_scratch_of_a_killed_writer_through_a_link_is_cleaned(tmp_path):
    real = tmp_path / "runs" / "run-3.html"
    real.parent.mkdir()
    real.write_text("old")
    link = tmp_path / "latest.html"
    link.symlink_to(real)
    script = (
        "import os, signal, sys\n"
        "from rbm_nb._infra.atomic import atomic_path\n"
        "with atomic_path(sys.argv[1]) as tmp:\n"
        "    tmp.write_text('half')\n"
        "    os.kill(os.getpid(), signal.SIGKILL)\n"
    )
    done = subprocess.run([sys.executable, "-c", script, str(link)], env=_env())
    assert done.returncode == -signal.SIGKILL
    assert len(_scratch_entries(real.parent)) == 1  # left by the killed writer
    with atomic_path(link) as tmp:
        tmp.write_text("new")
    assert _scratch_entries(real.parent) == []
    assert real.read_text() == "new" and link.is_symlink()


def test_parked_folder_is_put_back(tmp_path, no_exchange):
    """A kill between parking the old folder and renaming the new one in."""
    dead = _dead_pid()
    scratch = tmp_path / _ours("bag", dead)
    scratch.mkdir()
    _write_folder(scratch / _atomic.PARKED, 7)  # the user's folder, parked
    _write_folder(scratch / "bag", 8)  # the new one, never renamed in
    assert not (tmp_path / "bag").exists()
    with atomic_path(tmp_path / "other.nc") as tmp:  # any write to the folder
        tmp.write_text("x")
    assert _folder_version(tmp_path / "bag") == 7
    assert _scratch_entries(tmp_path) == []


# -- kill -9 in the middle of writes ----------------------------------------------

WRITER = textwrap.dedent(
    """
    import os, sys
    from pathlib import Path
    from rbm_nb._infra import atomic as _atomic
    target, kind, exchange = Path(sys.argv[1]), sys.argv[2], sys.argv[3] == "1"
    if not exchange:
        _atomic._RENAMEAT2[:] = [None]
    print("ready", flush=True)
    version = int(sys.argv[4])
    while True:
        version += 1
        parts = _atomic.FolderKind("parts", lambda path: True)
        folder_kind = parts if kind == "folder" else None
        with _atomic.atomic_path(target, folder_kind=folder_kind) as tmp:
            if kind == "folder":
                tmp.mkdir()
                for k in range(5):
                    (tmp / f"part{k}.txt").write_text(f"{version}\\n" + "x" * 20000)
            else:
                tmp.write_text(f"{version}\\n" + "y" * 200000)
    """
)


def _file_version(path: Path) -> int:
    text = path.read_text()
    head, body = text.split("\n", 1)
    assert body == "y" * 200000, "partial file"
    return int(head)


def _kill_rounds(tmp_path, kind, exchange, rounds):
    target = tmp_path / ("bag" if kind == "folder" else "cache.nc")
    if kind == "folder":
        _write_folder(target, 0, size=20000)
    else:
        target.write_text("0\n" + "y" * 200000)
    rng = random.Random(1234)
    version, absent, left_scratch = 0, 0, 0
    for _ in range(rounds):
        proc = subprocess.Popen(
            [sys.executable, "-c", WRITER, str(target), kind, str(int(exchange)),
             str(version)],
            stdout=subprocess.PIPE, env=_env(),
        )  # fmt: skip
        assert proc.stdout.readline().strip() == b"ready"
        time.sleep(rng.uniform(0.02, 0.5))
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        proc.stdout.close()
        left_scratch += bool(_scratch_entries(tmp_path))
        if not os.path.lexists(target):
            absent += 1
            assert not exchange, "with rename-exchange the target is never absent"
            clean_stale_scratch(tmp_path)  # what the next write does first
        found = _folder_version(target) if kind == "folder" else _file_version(target)
        assert found >= version  # the old one or a newer complete one
        version = found
    # the next write to the folder removes what the killed writers left
    with atomic_path(tmp_path / "after.txt") as tmp:
        tmp.write_text("ok")
    assert _scratch_entries(tmp_path) == []
    return version, absent, left_scratch


@pytest.mark.slow
@pytest.mark.parametrize(
    "kind, exchange",
    [("folder", True), ("folder", False), ("file", True)],
    ids=["folder-exchange", "folder-park", "file"],
)
def test_kill_during_writes_never_loses_the_target(tmp_path, kind, exchange):
    if exchange and _atomic._renameat2() is None:
        pytest.skip("this system has no renameat2(RENAME_EXCHANGE)")
    version, absent, left_scratch = _kill_rounds(tmp_path, kind, exchange, rounds=12)
    assert version > 0, "no write ever completed: the test did not exercise renames"
    assert left_scratch > 0, "no kill landed inside a write: the test has no teeth"


def test_kill_between_park_and_rename_is_repaired(tmp_path):
    """Deterministic: without exchange, die right after parking the old folder."""
    target = tmp_path / "bag"
    _write_folder(target, 5)
    script = textwrap.dedent(
        """
        import os, signal, sys
        from pathlib import Path
        from rbm_nb._infra import atomic as _atomic
        _atomic._RENAMEAT2[:] = [None]
        real_replace = os.replace
        def replace(src, dst):
            real_replace(src, dst)
            if Path(dst).name == _atomic.PARKED:
                os.kill(os.getpid(), signal.SIGKILL)
        os.replace = replace
        parts = _atomic.FolderKind("parts", lambda path: True)
        with _atomic.atomic_path(Path(sys.argv[1]), folder_kind=parts) as tmp:
            tmp.mkdir()
            for k in range(5):
                (tmp / f"part{k}.txt").write_text("6\\n" + "x" * 2000)
        """
    )
    proc = subprocess.run(
        [sys.executable, "-c", script, str(target)], env=_env(), check=False
    )
    assert proc.returncode == -signal.SIGKILL
    assert not target.exists()  # the window the fallback has
    with atomic_path(tmp_path / "unrelated.html") as tmp:
        tmp.write_text("next write")
    assert _folder_version(target) == 5
    assert _scratch_entries(tmp_path) == []


# -- errors name the target ----------------------------------------------------------


def _assert_names_target(err: OSError, target: Path):
    assert err.filename == str(target), err
    assert str(target) in str(err)
    assert ".tmp" not in str(err), err


@pytest.fixture
def immutable_folder(tmp_path):
    folder = tmp_path / "locked"
    folder.mkdir()
    (folder / "scene.html").write_text("old")
    chattr = shutil.which("chattr")
    if chattr is None:
        pytest.skip("chattr is not installed: cannot make a folder immutable")
    done = subprocess.run([chattr, "+i", str(folder)], capture_output=True)
    if done.returncode != 0:
        pytest.skip(f"chattr +i is not supported here: {done.stderr.decode().strip()}")
    try:
        yield folder
    finally:
        subprocess.run([chattr, "-i", str(folder)], check=True)


@pytest.mark.parametrize("name", ["scene.html", "new.html", "bag"])
def test_immutable_folder_error_names_the_target(immutable_folder, name):
    target = immutable_folder / name
    with pytest.raises(PermissionError) as info:
        with atomic_path(target) as tmp:
            tmp.write_text("new")
    _assert_names_target(info.value, target)
    assert (immutable_folder / "scene.html").read_text() == "old"


def _in_mount_namespace(tmp_path, mount_commands: str, code: str):
    """Run ``code`` in a private mount namespace after ``mount_commands``."""
    unshare = shutil.which("unshare")
    if unshare is None:
        pytest.skip("unshare is not installed: no private mount namespace")
    probe = subprocess.run(
        [unshare, "--mount", "--propagation", "private", "true"], capture_output=True
    )
    if probe.returncode != 0:
        pytest.skip(f"cannot create a mount namespace: {probe.stderr.decode().strip()}")
    script = tmp_path / "inside.py"
    script.write_text(textwrap.dedent(code))
    shell = f"set -e\n{mount_commands}\nexec {sys.executable} {script}"
    return subprocess.run(
        [unshare, "--mount", "--propagation", "private", "sh", "-c", shell],
        capture_output=True,
        text=True,
        env=_env(),
    )


CHECK_ERROR = """
import errno, os, sys
from pathlib import Path
from rbm_nb._infra.atomic import atomic_path
target = Path(sys.argv[1]) if len(sys.argv) > 1 else Path({target!r})
try:
    with atomic_path(target) as tmp:
        {write}
except OSError as err:
    print(errno.errorcode[err.errno], err.filename, str(err), sep="\\n")
else:
    print("no error")
"""


def test_read_only_mount_error_names_the_target(tmp_path):
    folder = tmp_path / "ro"
    folder.mkdir()
    (folder / "cache.nc").write_text("old")
    target = folder / "cache.nc"
    done = _in_mount_namespace(
        tmp_path,
        f"mount --bind {folder} {folder}\nmount -o remount,bind,ro {folder}",
        CHECK_ERROR.format(target=str(target), write='tmp.write_text("new")'),
    )
    assert done.returncode == 0, done.stderr
    code, filename, message = done.stdout.strip().split("\n", 2)
    assert code == "EROFS"
    assert filename == str(target)
    assert ".tmp" not in message and str(target) in message
    assert target.read_text() == "old"


@pytest.mark.parametrize("kind", ["file", "folder"])
def test_disk_full_error_names_the_target(tmp_path, kind):
    folder = tmp_path / "small"
    folder.mkdir()
    target = folder / ("scene.html" if kind == "file" else "bag")
    write = (
        'tmp.write_bytes(b"x" * 2_000_000)'
        if kind == "file"
        else 'tmp.mkdir(); (tmp / "db3").write_bytes(b"x" * 2_000_000)'
    )
    done = _in_mount_namespace(
        tmp_path,
        f"mount -t tmpfs -o size=256k tmpfs {folder}\nprintf old > {folder}/keep.txt",
        CHECK_ERROR.format(target=str(target), write=write)
        + "\nprint(sorted(os.listdir(target.parent)))",
    )
    assert done.returncode == 0, done.stderr
    lines = done.stdout.strip().split("\n")
    assert lines[0] == "ENOSPC", done.stdout
    assert lines[1] == str(target)
    assert ".tmp" not in lines[2] and str(target) in lines[2]
    assert lines[-1] == "['keep.txt']"  # nothing left behind on the full disk


def test_file_too_large_error_names_the_target(tmp_path):
    target = tmp_path / "big.nc"
    target.write_text("old")
    code = (
        "import resource\n"
        "resource.setrlimit(resource.RLIMIT_FSIZE, (100_000, 100_000))\n"
        + CHECK_ERROR.format(
            target=str(target), write='tmp.write_bytes(b"x" * 1_000_000)'
        )
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=_env()
    )
    assert done.returncode == 0, done.stderr
    err_code, filename, message = done.stdout.strip().split("\n", 2)
    assert err_code == "EFBIG"
    assert filename == str(target)
    assert ".tmp" not in message
    assert target.read_text() == "old"
    assert _scratch_entries(tmp_path) == []


def test_error_from_the_writer_naming_the_scratch_path_is_rewritten(tmp_path):
    target = tmp_path / "x.bag"
    with pytest.raises(OSError) as info:
        with atomic_path(target) as tmp:
            raise OSError(errno.EIO, "Input/output error", str(tmp))
    _assert_names_target(info.value, target)


def test_unrelated_errors_pass_unchanged(tmp_path):
    elsewhere = tmp_path / "source.csv"
    with pytest.raises(FileNotFoundError) as info:
        with atomic_path(tmp_path / "x.nc"):
            open(elsewhere)
    assert info.value.filename == str(elsewhere)
    err = ValueError("bad input")
    with pytest.raises(ValueError) as info:
        with atomic_path(tmp_path / "x.nc"):
            raise err
    assert info.value is err


ROSBAG_WRITE = """
import errno, os, sys
import numpy as np
from rbm_nb.ros import RosbagWriter
folder = sys.argv[1]
n = 20000
t = np.arange(n) * 0.01
for name, options in [("a.bag", {{}}), ("b", {{}}), ("c", {{"storage": "mcap"}})]:
    target = os.path.join(folder, name)
    try:
        with RosbagWriter(target, **options) as writer:
            writer.write_transform_stamped(
                t, np.zeros((n, 3)), np.tile([1.0, 0, 0, 0], (n, 1)), "/x", "a", "b"
            )
    except OSError as err:
        print(name, errno.errorcode[err.errno], err.filename == target,
              ".tmp" not in str(err) and target in str(err))
    except Exception as err:
        print(name, type(err).__name__, repr(str(err)))
    else:
        print(name, "no error")
print(sorted(os.listdir(folder)))
"""


@pytest.mark.parametrize("kind", ["disk-full", "read-only"])
def test_rosbag_writer_errors_name_the_bag(tmp_path, kind):
    folder = tmp_path / "bags"
    folder.mkdir()
    if kind == "disk-full":
        mounts = f"mount -t tmpfs -o size=256k tmpfs {folder}"
        code = "ENOSPC"
    else:
        mounts = f"mount --bind {folder} {folder}\nmount -o remount,bind,ro {folder}"
        code = "EROFS"
    script = tmp_path / "write_bags.py"
    script.write_text(ROSBAG_WRITE.format())
    done = _in_mount_namespace(
        tmp_path,
        mounts,
        f"import runpy, sys\nsys.argv = ['x', {str(folder)!r}]\n"
        f"runpy.run_path({str(script)!r}, run_name='__main__')",
    )
    assert done.returncode == 0, done.stderr
    lines = done.stdout.strip().split("\n")
    assert lines[:3] == [f"{name} {code} True True" for name in ("a.bag", "b", "c")]
    assert lines[3] == "[]"  # no bag, no scratch folder left


BAG_WRITER = textwrap.dedent(
    """
    import sys
    import numpy as np
    from rbm_nb.ros import RosbagWriter
    target, version = sys.argv[1], int(sys.argv[2])
    n = 2000
    t = np.arange(n) * 0.01
    print("ready", flush=True)
    while True:
        version += 1
        with RosbagWriter(target) as writer:
            writer.write_transform_stamped(
                t, np.full((n, 3), float(version)), np.tile([1.0, 0, 0, 0], (n, 1)),
                "/pose", "world", "head",
            )
    """
)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["rec", "rec.bag"], ids=["ros2-folder", "ros1-file"])
def test_kill_during_rosbag_writes_keeps_a_readable_bag(tmp_path, name):
    """End to end through RosbagWriter: after every kill -9 the bag reads back."""
    from rbm_nb.ros import RosbagReader

    target = tmp_path / name
    rng = random.Random(99)
    version = 0
    subprocess.run(  # a first complete bag (version 1)
        [sys.executable, "-c", BAG_WRITER.replace("while True:", "for _ in [0]:"),
         str(target), "0"],
        env=_env(), check=True, capture_output=True,
    )  # fmt: skip
    left_scratch = 0
    for _ in range(8):
        proc = subprocess.Popen(
            [sys.executable, "-c", BAG_WRITER, str(target), str(version)],
            stdout=subprocess.PIPE, env=_env(),
        )  # fmt: skip
        assert proc.stdout.readline().strip() == b"ready"
        time.sleep(rng.uniform(0.05, 0.6))
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        proc.stdout.close()
        left_scratch += bool(_scratch_entries(tmp_path))
        assert os.path.lexists(target), "the bag vanished"
        with RosbagReader(target) as reader:
            data = reader.load_messages("/pose")
        position = data["position"]
        assert position.shape == (2000, 3)
        assert len(np.unique(position)) == 1  # one complete version
        found = int(position[0, 0])
        assert found >= max(version, 1)
        version = found
    assert left_scratch > 0, "no kill landed inside a write: the test has no teeth"


# -- no writer deletes a folder it did not make (issue 31, item 1) ----------------

WRITERS_AT_A_FOLDER = {
    "netcdf-export": "rosbag_export_to",
    "rosbag-ros2": "rosbag_write_to",
    "synthetic-rosbag": "synthetic_rosbag_to",
    "study-netcdf": "study_to_netcdf_at",
    "html-export": "html_export_to",
}


_AT_A_FOLDER = [
    (writer, name)
    for writer in WRITERS_AT_A_FOLDER
    for name in ["thesis", "old.bag", "s0.nc", "scene.html"]
    # Study.to_netcdf writes only <recording>.nc
    if writer != "study-netcdf" or name.endswith(".nc")
]


@pytest.mark.parametrize("writer, name", _AT_A_FOLDER)
def test_no_writer_deletes_a_folder_that_is_not_its_kind_of_bag(writer, name):
    """Every writer of rbm_nb, at every kind of name, refuses a user's folder."""
    import bad_input_cases as cases

    cases.setup_tree()
    write = getattr(cases, WRITERS_AT_A_FOLDER[writer])
    # the helper asserts afterwards that the folder and thesis.tex are intact
    with pytest.raises(IsADirectoryError, match="folder|directory"):
        cases.writer_at_user_folder(name, write)


def test_a_folder_that_appears_while_writing_is_not_replaced(tmp_path):
    target = tmp_path / "out.nc"
    with pytest.raises(IsADirectoryError, match="refusing to replace a folder"):
        with atomic_path(target) as tmp:
            tmp.write_text("netcdf")
            target.mkdir()  # someone else, meanwhile
            (target / "thesis.tex").write_text("mine")
    assert (target / "thesis.tex").read_text() == "mine"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.nc"]


def test_a_folder_without_a_declared_kind_replaces_nothing(tmp_path):
    target = tmp_path / "data"
    target.write_text("a file of the user's")
    with pytest.raises(NotADirectoryError, match="refusing to replace a file"):
        with atomic_path(target) as tmp:
            _write_folder(tmp, 1)
    assert target.read_text() == "a file of the user's"


def test_a_ros2_bag_is_replaced_only_once_the_new_one_is_complete(tmp_path):
    from rbm_nb.ros import RosbagReader, RosbagWriter

    bag = tmp_path / "run"

    def write(stamps, fail=False):
        with RosbagWriter(bag) as writer:
            n = len(stamps)
            writer.write_transform_stamped(
                stamps,
                np.zeros((n, 3)),
                np.tile([1.0, 0, 0, 0], (n, 1)),
                "/x",
                "a",
                "b",
            )
            if fail:
                raise RuntimeError("interrupted")

    write([1.0, 2.0])
    with pytest.raises(RuntimeError, match="interrupted"):
        write([1.0, 2.0, 3.0], fail=True)
    assert len(RosbagReader(bag).load_dataset("/x").time) == 2
    write([1.0, 2.0, 3.0])  # a bag of its own kind: replaced
    assert len(RosbagReader(bag).load_dataset("/x").time) == 3
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]
