"""The evaluation's door refuses what would be a NaN or a wrong number (issue 32, item 2).

``umeyama_alignment`` checked only shapes: a NaN or an infinity made numpy's
SVD fail to converge (a LinAlgError naming nothing). ``ape``/``rpe`` over a
trajectory with missing samples (NaN rows, which frames keep) returned NaN
statistics without a word, or the same LinAlgError with ``align=True``.
"""

from __future__ import annotations

import numpy as np
import pytest
from rbm_nb.evaluation import ape, rpe, umeyama_alignment

import rbm_nb as rbm

_T = np.arange(10.0)
_P = np.c_[_T, np.sin(_T), 0.1 * _T * _T]
_Q = np.tile([1.0, 0.0, 0.0, 0.0], (10, 1))


def _with_row(arr: np.ndarray, row: int, value: float) -> np.ndarray:
    out = arr.copy()
    out[row] = value
    return out


@pytest.mark.parametrize(
    "source, target, match",
    [
        (_with_row(_P, 3, np.nan), _P, r"^source\[3\] is not finite"),
        (_P, _with_row(_P, 1, np.inf), r"^target\[1\] is not finite"),
        (_P, _with_row(_P, 0, -np.inf), r"^target\[0\] is not finite"),
    ],
)
def test_umeyama_refuses_points_that_are_not_finite(source, target, match):
    with pytest.raises(ValueError, match=match):
        umeyama_alignment(source, target)


def test_umeyama_shape_message_is_unchanged():
    with pytest.raises(ValueError) as info:
        umeyama_alignment(_P, _P[:-1])
    assert str(info.value) == (
        "source and target must both have shape (n, 3), got (10, 3) and (9, 3)"
    )


_MISSING = (
    r"matched poses are missing \(NaN\), the first at time 3\.0 \(matched pose 3\)"
)


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: ape((_T, _P, _Q), (_T, _with_row(_P, 3, np.nan), _Q)), "estimate"),
        (
            lambda: ape((_T, _P, _Q), (_T, _with_row(_P, 3, np.nan), _Q), align=True),
            "estimate",
        ),
        (
            lambda: ape(
                (_T, _P, _Q), (_T, _P, _with_row(_Q, 3, np.nan)), pose_relation="full"
            ),
            "estimate",
        ),
        (lambda: rpe((_T, _with_row(_P, 3, np.nan), _Q), (_T, _P, _Q)), "reference"),
    ],
    ids=["ape", "ape-align", "ape-rotation", "rpe-reference"],
)
def test_missing_poses_are_refused_naming_the_trajectory(call, name):
    with pytest.raises(ValueError, match=rf"^{name}: 1 of the 10 {_MISSING}"):
        call()


def test_a_frame_with_missing_samples_is_refused():
    rbm.clear_registry()
    rbm.register_frame("world")
    rbm.register_frame(
        "track", parent="world", translation=_with_row(_P, 5, np.nan),
        rotation=_Q, timestamps=_T,
    )  # fmt: skip
    # the estimate is interpolated at the reference's times: the missing
    # sample makes the poses next to it missing too
    with pytest.raises(ValueError, match=r"^estimate: \d+ of the \d+ matched poses"):
        ape((_T + 0.5, _P, _Q), "track")
    rbm.clear_registry()


def test_complete_trajectories_still_give_numbers():
    result = ape((_T, _P, _Q), (_T, _P + [0.1, 0.0, 0.0], _Q), align=True)
    assert np.isfinite(result.error.values).all()


def _message(call) -> str:
    with pytest.raises(ValueError) as info:
        call()
    return str(info.value)


@pytest.mark.parametrize(
    "t, p, q",
    [
        (_T, _P[:, :2], _Q),
        (_T, _P[:-1], _Q),
        (_T, _P, _Q[:, :3]),
        (_T, _P, _with_row(_Q, 2, 2.0)),
        (_T, _P, _with_row(_Q, 2, 0.0)),
        (_T, _with_row(_P, 4, np.inf), _Q),
        (_T, _with_row(_P, (4, 1), np.nan), _Q),
        (_T[::-1], _P, _Q),
        (_with_row(_T, 3, np.nan), _P, _Q),
        (_with_row(_T, 3, 2.0), _P, _Q),
    ],
    ids=["p-columns", "p-rows", "q-columns", "q-norm", "q-zero", "p-inf",
         "p-part-nan", "t-decreasing", "t-nan", "t-repeated"],
)  # fmt: skip
def test_array_trajectories_are_refused_as_a_frame_of_them_is(t, p, q):
    """The door checks array trajectories itself (no ReferenceFrame is built):
    its messages stay those of a frame made of the same arrays."""
    as_frame = _message(
        lambda: rbm.ReferenceFrame(
            "estimate",
            parent=rbm.ReferenceFrame("estimate world"),
            translation=p,
            rotation=q,
            timestamps=t,
        )  # fmt: skip
    )
    assert _message(lambda: ape((_T, _P, _Q), (t, p, q))) == as_frame
