"""Every row of the bad-input table raises the expected error with a clear message.

The table (``tests/bad_input_cases.py``) lists distinct mistakes across the
public API. Rows marked with an issue item fail today and are strict xfail:
when the fix lands they XPASS and the mark is removed in the table. Rows with
``exc=None`` are bad input whose right answer is a result, not an error: the
row's call asserts that result itself.
"""

from __future__ import annotations

import re
import warnings

import pytest
from bad_input_cases import CASES, resolve, setup_tree


def _param(case):
    marks = ()
    if case.xfail:
        marks = (pytest.mark.xfail(strict=True, reason=case.xfail),)
    return pytest.param(case, id=case.id, marks=marks)


def test_table_is_large_and_distinct():
    ids = [c.id for c in CASES]
    assert len(ids) == len(set(ids)), "row ids must be unique"
    assert len(CASES) >= 318  # issue 31 grew it from 175; rows are not removed


@pytest.mark.parametrize("case", [_param(c) for c in CASES])
def test_bad_input(case):
    setup_tree()
    func = resolve(case.call)
    if case.exc is None:
        # a row whose correct result is not an error: the call checks it
        # (asserts) and returns what it found, which must not be falsy
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = func(*case.args, **case.kwargs)
        assert result is not None and result is not False, result
        return
    with warnings.catch_warnings():
        # a warning on the way is fine; a silent wrong answer is not
        warnings.simplefilter("ignore")
        with pytest.raises(Exception) as info:
            func(*case.args, **case.kwargs)
    err = info.value
    assert isinstance(err, case.exc), (
        f"expected {case.exc.__name__}, got {type(err).__name__}: {err}"
    )
    message = str(err.args[0]) if isinstance(err, KeyError) and err.args else str(err)
    assert re.search(case.match, message), (
        f"message {message!r} does not match {case.match!r}"
    )
