"""The exercises of the teaching notebooks: the solutions are right, wrong answers are not.

Every exercise is a cell that assigns ``None`` to a name (``prediction``,
``my_...``) followed by a check cell that calls ``check_answer``. Here each
such cell gets the answer from its folded-away solution (``ANSWERS``) and the
notebook runs in a fresh kernel: every check must then print "Right.". A
second run with a wrong answer in each checks that the check cells can fail.
"""

from __future__ import annotations

import re

import pytest
from conftest import REPO

# answers in the order of the notebook's "<name> = None" cells; each with a
# wrong one to prove the check can fail
ANSWERS = {
    "01_reference_frames.ipynb": [
        ("(1, 0, 0)", "(0, 1, 0)"),
        ("-3", "3"),
        ("4", "5"),
        ("180", "90"),
    ],
    "02_velocities.ipynb": [
        ("(-0.2, 0, 0)", "(0.2, 0, 0)"),
        ("(-0.157, 0, 0)", "(0, 0.157, 0)"),
        ("(0, 0.157, 0.157)", "(0, 0.157, 0)"),
    ],
    "03_estimators.ipynb": [
        ("45", "22.5"),
        ("45", "90"),
        ("False", "True"),
        ("(3, 1, 1)", "(1, 1, 3)"),
    ],
    "04_xarray.ipynb": [
        ('"y"', '"z"'),
        ('left_eye.sizes["time"] - int(outside.sum())', 'left_eye.sizes["time"] + 1'),
        (
            "int((np.diff(np.flatnonzero(np.diff(np.r_[0, both.values.astype(int), 0])))"
            "[::2] * float(np.median(np.diff(left_eye.time.values)) "
            '/ np.timedelta64(1, "s")) >= 0.1).sum())',
            "-1",
        ),
    ],
    "05_rosbag_and_3d.ipynb": [
        ("(-1, 0, 0)", "(0, 0, -1)"),
        ('rbm.lookup_pose("head", "world")[0][player.index]', "(0, 0, 0)"),
    ],
    "08_sdf_and_pose_algebra.ipynb": [
        ("0.03", "0.13"),
        ("1.04", "1.0"),
        ("np.degrees(0.25)", "0.25"),
    ],
    "09_velocity_tools_and_evaluation.ipynb": [
        ("True", "False"),
        ('"z"', '"y"'),
        ("np.radians(1.0) / heading_rate", "1.0 / heading_rate"),
    ],
}
EXERCISE = re.compile(r"^(prediction|my_\w+) = None\b", re.MULTILINE)


def _with_answers(path, which: int):
    import nbformat

    notebook = nbformat.read(path, as_version=4)
    answers = iter(ANSWERS[path.name])
    count = 0
    for cell in notebook.cells:
        if cell.cell_type == "code" and EXERCISE.search(cell.source):
            answer = next(answers)[which]
            cell.source = EXERCISE.sub(
                lambda m, a=answer: f"{m.group(1)} = {a}", cell.source, 1
            )
            count += 1
    assert count == len(ANSWERS[path.name]), f"{path.name}: {count} exercises"
    return notebook


def _checks(notebook) -> list[str]:
    said = []
    for cell in notebook.cells:
        if "check_answer(" not in cell.source:
            continue
        text = "".join(o.get("text", "") for o in cell.get("outputs", []))
        said.append(text)
    return said


@pytest.fixture(scope="module", autouse=True)
def _execute_ahead(request):
    """Start every selected run: two kernels at a time while the tests wait."""
    from conftest import selected_params

    selected = selected_params(request, "test_exercise_checks")
    runs = request.getfixturevalue("executed_notebook") if selected else None
    for params in selected:
        name, which = params["name"], params["which"]
        runs.prefetch_run(
            ("exercises", name, which),
            lambda name=name, which=which: _with_answers(
                REPO / "notebooks" / name, which
            ),
            "synthetic",
        )


@pytest.mark.slow
# waits for its run, which shares the cores with the next one
@pytest.mark.timeout(900)
@pytest.mark.parametrize("name", sorted(ANSWERS))
@pytest.mark.parametrize("which", [0, 1], ids=["solutions", "wrong"])
def test_exercise_checks(name, which, executed_notebook):
    # in a fresh kernel, offline (the synthetic recording), two at a time
    # (tests/notebook_runs.py)
    notebook = executed_notebook.run(
        ("exercises", name, which),
        lambda: _with_answers(REPO / "notebooks" / name, which),
        "synthetic",
    )
    said = _checks(notebook)
    assert len(said) == len(ANSWERS[name])
    verdict = "Right." if which == 0 else "Not quite"
    for text in said:
        assert verdict in text, f"{name}: {text!r}"
