"""Cached kernels are dropped when any kernel module's source changes.

numba keys a cached kernel on its own source file; rbm_nb's kernels inline
helpers from other modules, so an edit there must invalidate them too.
"""

from __future__ import annotations

from rbm_nb._infra import numba_cache as _numba_cache


def _touch(path):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(b"cached")
    return path


def test_stale_kernels_are_dropped_and_only_ours(tmp_path):
    ours = [
        _touch(
            tmp_path / "work" / "rbm_nb" / "_kernels" / "quaternion.qmul-10.py311.nbi"
        ),
        _touch(
            tmp_path / "work" / "rbm_nb" / "_kernels" / "quaternion.qmul-10.py311.1.nbc"
        ),
    ]
    theirs = _touch(tmp_path / "other" / "pkg" / "_kernels" / "k.f-1.py311.nbi")

    assert _numba_cache.drop_stale_kernels(tmp_path) == 2
    assert not any(p.exists() for p in ours) and theirs.exists()
    stamp = tmp_path / "rbm_nb-kernels.sha256"
    assert stamp.read_text() == _numba_cache.kernels_fingerprint()

    # same sources: the cache is kept
    again = _touch(ours[0])
    assert _numba_cache.drop_stale_kernels(tmp_path) == 0
    assert again.exists()

    # a kernel module changed since the cache was made: dropped
    stamp.write_text("fingerprint of other sources")
    assert _numba_cache.drop_stale_kernels(tmp_path) == 1
    assert not again.exists()


def test_the_fingerprint_covers_every_kernel_module():
    names = sorted(p.name for p in _numba_cache.KERNELS.glob("*.py"))
    assert {"scalar.py", "quaternion.py", "_jit.py"} <= set(names)
    assert len(_numba_cache.kernels_fingerprint()) == 64


def test_the_warm_up_lists_are_not_kernel_sources(tmp_path, monkeypatch):
    # editing the warm-up's lists must not drop every compiled kernel; editing
    # any other module of the folder must
    for path in _numba_cache.KERNELS.glob("*.py"):
        (tmp_path / path.name).write_bytes(path.read_bytes())
    monkeypatch.setattr(_numba_cache, "KERNELS", tmp_path)
    before = _numba_cache.kernels_fingerprint()
    warmup = tmp_path / "_warmup.py"
    warmup.write_text(warmup.read_text() + "\n# another list\n")
    assert _numba_cache.kernels_fingerprint() == before
    jit = tmp_path / "_jit.py"
    jit.write_text(jit.read_text() + "\n# a helper changed\n")
    assert _numba_cache.kernels_fingerprint() != before
