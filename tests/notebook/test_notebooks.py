"""The teaching notebooks run top to bottom offline, each in a fresh kernel."""

from __future__ import annotations

import json
import time

import pytest
from conftest import REPO

NOTEBOOKS = sorted((REPO / "notebooks").glob("*.ipynb"))
# what each notebook must say about where its data came from
SAYS_ITS_DATA = {
    "04_xarray.ipynb": "data source:",
    "05_rosbag_and_3d.ipynb": "bag:",
    "06_head_eye_explorer.ipynb": "data:",
    "07_many_recordings.ipynb": "data:",
    "08_sdf_and_pose_algebra.ipynb": "data: synthetic",
    "09_velocity_tools_and_evaluation.ipynb": "data:",
}


# notebooks that load the example recording: each runs on the real one and on
# the synthetic stand-in
USES_EXAMPLE_DATA = {
    "04_xarray.ipynb",
    "05_rosbag_and_3d.ipynb",
    "06_head_eye_explorer.ipynb",
    "07_many_recordings.ipynb",
    "09_velocity_tools_and_evaluation.ipynb",
}


def _runs():
    for path in NOTEBOOKS:
        if path.name in USES_EXAMPLE_DATA:
            yield pytest.param(path, "real", id=f"{path.stem}-real")
            yield pytest.param(path, "synthetic", id=f"{path.stem}-synthetic")
        else:
            yield pytest.param(path, None, id=path.stem)


def test_the_notebooks_are_there():
    assert [nb.name for nb in NOTEBOOKS] == [
        "01_reference_frames.ipynb",
        "02_velocities.ipynb",
        "03_estimators.ipynb",
        "04_xarray.ipynb",
        "05_rosbag_and_3d.ipynb",
        "06_head_eye_explorer.ipynb",
        "07_many_recordings.ipynb",
        "08_sdf_and_pose_algebra.ipynb",
        "09_velocity_tools_and_evaluation.ipynb",
    ]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_outputs_are_stripped_in_the_repo(path):
    notebook = json.loads(path.read_text())
    for cell in notebook["cells"]:
        assert not cell.get("outputs"), f"{path.name} has stored outputs"
        assert cell.get("execution_count") is None, f"{path.name} has execution counts"


def _stream_text(notebook) -> str:
    texts = []
    for cell in notebook.cells:
        for output in cell.get("outputs", []):
            if output.get("output_type") == "stream":
                texts.append(output["text"])
            elif "text/plain" in output.get("data", {}):
                texts.append(output["data"]["text/plain"])
    return "\n".join(texts)


@pytest.fixture(scope="module", autouse=True)
def _execute_ahead(request):
    """Start every selected run: two kernels at a time while the tests wait."""
    from conftest import selected_params

    selected = selected_params(request, "test_notebook_runs_offline_in_a_fresh_kernel")
    if selected:  # else the fast tests here need no kernel
        runs = request.getfixturevalue("executed_notebook")
        for params in selected:
            runs.prefetch(params["path"].name, params["source"])


@pytest.mark.slow
# waits for its run, which shares the cores with the next one
@pytest.mark.timeout(900)
@pytest.mark.parametrize("path, source", list(_runs()))
def test_notebook_runs_offline_in_a_fresh_kernel(path, source, executed_notebook):
    # executed once per session, two at a time (tests/notebook_runs.py): the
    # kernel gets no display, matplotlib config in tmp, and the example data
    # from the real folder or from an empty one (offline, the recording is
    # then the synthetic stand-in); test_warmup_explorer.py and
    # test_browser_offline.py check the same executions
    start = time.perf_counter()
    notebook = executed_notebook(path.name, source)
    print(f"{path.name}: waited {time.perf_counter() - start:.1f} s for its run")
    text = _stream_text(notebook)
    if path.name in SAYS_ITS_DATA:
        marker = SAYS_ITS_DATA[path.name]
        assert marker in text, f"{path.name} does not say its data"
        said = next(line for line in text.splitlines() if marker in line)
        # the example bag is not among the real files: notebook 05 makes its own
        if source is not None and path.name != "05_rosbag_and_3d.ipynb":
            assert source in said.lower(), f"{path.name} on {source} data said {said!r}"
    widget_state = notebook.metadata.get("widgets", {})
    if path.name in ("05_rosbag_and_3d.ipynb", "06_head_eye_explorer.ipynb"):
        # the widget cells really created widgets in the kernel
        models = widget_state.get("application/vnd.jupyter.widget-state+json", {})
        assert models.get("state"), f"{path.name} created no widgets"
