"""rbm_nb._warmup: how the work is shared between processes (fast checks).

The whole parallel warm-up, in a fresh environment with an empty cache, is
run by ``binder/postBuild`` in ``tests/project/test_binder.py``, which then
checks that a first call and the explorer notebook compile nothing.
"""

from __future__ import annotations

import os

import pytest

from rbm_nb import _warmup
from rbm_nb._kernels._jit import declared_kernels


def test_a_claimed_kernel_is_left_to_the_process_that_claimed_it(tmp_path, monkeypatch):
    compiled = []
    monkeypatch.setattr(_warmup, "_compile", lambda k: compiled.append(k.name))
    kernels = declared_kernels()
    taken = {0, 3, len(kernels) - 1}  # claimed by other processes
    for index in taken:
        (tmp_path / str(index)).touch()
    _warmup._compile_claimed(str(tmp_path), verbose=False)
    assert compiled == [k.name for i, k in enumerate(kernels) if i not in taken]
    assert sorted(os.listdir(tmp_path), key=int) == [
        str(i) for i in range(len(kernels))
    ]
    # a second process finds everything claimed
    compiled.clear()
    _warmup._compile_claimed(str(tmp_path), verbose=False)
    assert compiled == []


@pytest.mark.parametrize("value", ["0", "-1", "two", None])
def test_jobs_must_be_a_positive_number(capsys, value):
    argv = ["--jobs"] if value is None else ["--jobs", value]
    assert _warmup.main(argv) == 2
    assert "--jobs needs a positive number of processes" in capsys.readouterr().out
