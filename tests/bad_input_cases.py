"""Table of bad input to the public API and the error each must give.

Every row is one distinct mistake a user can make: the call (a public name
under ``rbm_nb``, or a small helper below for methods and operators), its
arguments, the exception type expected and a regular expression the message
must match (it names the argument, frame or file and what was expected).
``tests/core/test_bad_input_table.py`` runs every row against a fixed frame tree
(see :func:`setup_tree`).

Rows that fail today carry ``xfail``: the issue item that asks for the fix.
The test marks them ``xfail(strict=True)``, so the fixer sees XPASS and
deletes the reason here. Rows without ``xfail`` pass today and must keep
passing.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

import rbm_nb as rbm


class Case(NamedTuple):
    id: str
    call: Any  # a dotted name under rbm_nb, or a callable
    args: tuple
    kwargs: dict
    exc: type | None  # None: the call succeeds and asserts its own right result
    match: str
    xfail: str | None = None


# ---------------------------------------------------------------------------
# the frame tree every row runs against
# ---------------------------------------------------------------------------

N = 10
T = np.arange(float(N))  # seconds 0..9


def setup_tree() -> None:
    """world ─┬ static (fixed offset)
              ├ moving (10 samples, 0..9 s, translating along x and turning about z)
              ├ one (a single sample at 0 s)
              └ short (5.01..5.09 s, three samples)
    other_root (a second tree)
    """
    rbm.register_frame("world")
    rbm.register_frame(
        "static", parent="world", translation=[1.0, 0, 0], rotation=[1.0, 0, 0, 0]
    )
    angle = 0.1 * T
    rot = np.column_stack(
        [np.cos(angle / 2), np.zeros(N), np.zeros(N), np.sin(angle / 2)]
    )
    trans = np.column_stack([T, np.zeros(N), np.zeros(N)])
    rbm.register_frame(
        "moving", parent="world", translation=trans, rotation=rot, timestamps=T
    )
    rbm.register_frame(
        "one",
        parent="world",
        translation=np.zeros((1, 3)),
        rotation=np.array([[1.0, 0, 0, 0]]),
        timestamps=[0.0],
    )
    rbm.register_frame(
        "short",
        parent="world",
        translation=np.zeros((3, 3)),
        timestamps=[5.01, 5.05, 5.09],
    )
    rbm.register_frame("other_root")
    rbm.register_frame(
        "huge",
        parent="world",
        # (beyond what a scene draws, within what the frame core composes)
        translation=[[1e100, 0.0, 0.0], [-1e100, 0.0, 0.0]],
        timestamps=[0.0, 1.0],
    )


def resolve(call):
    if callable(call):
        return call
    obj = rbm
    for part in call.split("."):
        obj = getattr(obj, part)
    return obj


# ---------------------------------------------------------------------------
# helpers for calls that are not plain functions
# ---------------------------------------------------------------------------


def frame_method(frame, method, *args, **kwargs):
    return getattr(rbm.registry[frame], method)(*args, **kwargs)


def registry_del(name):
    del rbm.registry[name]


def registry_set(name, value):
    rbm.registry[name] = value


def register_twice(name):
    frame = rbm.ReferenceFrame(name, parent="world")
    frame.register()
    frame.register()


def transformer(method, *args, **kwargs):
    from rbm_nb.ros import Transformer

    tf = Transformer.from_reference_frame("world")
    return getattr(tf, method)(*args, **kwargs)


def new_transformer(**kwargs):
    from rbm_nb.ros import Transformer

    return Transformer(**kwargs)


def transform_method(method, *args, **kwargs):
    return getattr(rbm.Transform([1.0, 0, 0]), method)(*args, **kwargs)


def accessor_qinterp(**coords):
    import xarray as xr

    da = xr.DataArray(
        np.tile([1.0, 0, 0, 0], (4, 1)),
        dims=("time", "quaternion_axis"),
        coords={"time": np.arange(4.0), "quaternion_axis": list("wxyz")},
    )
    return da.rbm.qinterp(**coords)


def dataarray_points(**kwargs):
    """transform_points on a DataArray (time, cartesian_axis)."""
    import xarray as xr

    coords = kwargs.pop("coords", {"time": np.linspace(0, 9, 19)})
    da = xr.DataArray(np.zeros((19, 3)), dims=("time", "cartesian_axis"), coords=coords)
    return rbm.transform_points(da, "world", "moving", **kwargs)


def from_dataset(**kwargs):
    import xarray as xr

    ds = xr.Dataset(
        {
            "position": (("time", "cartesian_axis"), np.zeros((4, 3))),
            "orientation": (
                ("time", "quaternion_axis"),
                np.tile([1.0, 0, 0, 0], (4, 1)),
            ),
        },
        coords={"time": np.arange(4.0)},
    )
    args = {"translation": "position", "rotation": "orientation", "timestamps": "time"}
    args.update(kwargs)
    return rbm.ReferenceFrame.from_dataset(ds, parent="world", name="ds", **args)


def rosbag_reader(path, method, *args):
    from rbm_nb.ros import RosbagReader

    return getattr(RosbagReader(path), method)(*args)


def in_temp_folder(func, *args, files=None, **kwargs):
    """Call ``func(folder, *args)`` in a fresh folder holding ``files`` (name: text)."""
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        for name, text in (files or {}).items():
            (folder / name).write_text(text)
        return func(folder, *args, **kwargs)


def optitrack_in(folder, name, **kwargs):
    return rbm.io.load_optitrack(folder / name, **kwargs)


def netcdf_in(folder, name):
    return rbm.io.load_netcdf(folder / name)


def write_bag_in(folder, name, timestamps, **options):
    from rbm_nb.ros import RosbagWriter

    n = len(timestamps)
    with RosbagWriter(folder / name, **options) as writer:
        writer.write_transform_stamped(
            timestamps,
            np.zeros((n, 3)),
            np.tile([1.0, 0, 0, 0], (n, 1)),
            "/x",
            "a",
            "b",
        )


# -- writers at a folder that is the user's (issue 31, item 1) -------------------

THESIS = "\\documentclass{article} my thesis"


def _small_bag(path):
    from rbm_nb.ros import RosbagWriter

    with RosbagWriter(path) as writer:
        writer.write_transform_stamped(
            [1.0, 2.0],
            np.zeros((2, 3)),
            np.tile([1.0, 0, 0, 0], (2, 1)),
            "/x",
            "a",
            "b",
        )
    return path


def writer_at_user_folder(name, write, extra=None):
    """Run ``write(target)`` where ``target`` is a folder holding the user's
    ``thesis.tex`` (and ``extra`` files); afterwards the folder must be intact,
    whatever ``write`` did (an AssertionError replaces the expected error)."""
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as root:
        target = Path(root) / name
        target.mkdir()
        files = {"thesis.tex": THESIS, **(extra or {})}
        for entry, text in files.items():
            (target / entry).write_text(text)
        try:
            write(target)
        finally:
            assert target.is_dir(), f"{target} is gone"
            found = {p.name: p.read_text() for p in target.iterdir()}
            assert found == files, f"{target} changed: {sorted(found)}"


def rosbag_export_to(target):
    from rbm_nb.ros import RosbagReader

    bag = _small_bag(target.parent / "small.bag")
    RosbagReader(bag).export("/x", output_file=target)


def rosbag_write_to(target):
    _small_bag(target)


def synthetic_rosbag_to(target):
    rbm.data.write_synthetic_rosbag(target, duration=16.0)


def study_to_netcdf_at(target):
    """Study.to_netcdf at a folder: refused before any recording is analysed."""
    from rbm_nb.data import synthetic_head_eye
    from rbm_nb.study import open_study

    recs = {target.stem: dict(synthetic_head_eye(duration=16.0, seed=0)._asdict())}
    study = open_study(recs, streams=["head"])
    analysed = []

    def analysis(recording):
        analysed.append(True)
        return recording["head"]

    try:
        study.to_netcdf(analysis, target.parent, progress=False)
    finally:
        assert not analysed, "the analysis ran before the refusal"


def html_export_to(target):
    from rbm_nb.scene import Scene

    scene = Scene()
    scene.add_frame("moving")  # of setup_tree
    scene.to_html(target)


def ros2_bag_over_file(name):
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as root:
        target = Path(root) / name
        target.write_text("my notes")
        try:
            _small_bag(target)
        finally:
            assert target.read_text() == "my notes"


# -- hostile strings in an HTML export (issue 31, item 3) --------------------------

EXPORT_DATA = '<script id="rbm-export-data" type="application/json">'


def export_with_hostile_string(text, where):
    """Export a dashboard with ``text`` as the frame name, label, units or title;
    the page's data element must hold all of the document and give ``text`` back."""
    import json
    import tempfile
    from pathlib import Path

    from rbm_nb.scene import Scene
    from rbm_nb.widgets.timeseries import TimeSeries

    frame = text if where == "frame" else "moving"
    if where == "frame":
        rbm.register_frame(
            text, parent="world", translation=np.zeros((2, 3)), timestamps=[0.0, 1.0]
        )
    scene = Scene()
    scene.add_frame(frame, label=text if where == "label" else None)
    import xarray as xr

    speed = xr.DataArray(
        np.ones(4),
        dims="time",
        coords={"time": np.arange(4.0)},
        attrs={"units": text if where == "units" else "m/s"},
    )
    plot = TimeSeries({text if where == "panel" else "speed": speed})
    with tempfile.TemporaryDirectory() as folder:
        path = scene.to_html(
            Path(folder) / "page.html",
            series=[plot],
            title=text if where == "title" else None,
        )
        page = path.read_text(encoding="utf-8")
    head, rest = page.split(EXPORT_DATA, 1)
    data, tail = rest.split("</script>", 1)
    assert not any(mark in data for mark in ("<", ">", "\u2028", "\u2029"))
    document = json.loads(data)  # the whole document, nothing cut off
    assert tail.lstrip().startswith('<script type="module">')
    if where == "title":
        import html

        assert f"<h1>{html.escape(text)}</h1>" in head
    elif where != "label":  # labels become object names (slugs)
        assert text in json.dumps(document, ensure_ascii=False)
    return document


HOSTILE_STRINGS = {
    "comment-script": "<!--<script>",
    "end-script": "</script><script>alert(1)</script>",
    "line-separators": "a\u2028b\u2029c",
    "ampersand-tags": "&amp; <b>x</b> &#60;",
}


# -- updates the browser sends through a widget's comm (issue 31, item 5) -------


class recorded_comms:
    """Widgets built inside open a RecordingComm (widget_support.py); closed after."""

    def __enter__(self):
        import comm
        from widget_support import RecordingComm

        self.comms = []
        self._module, self._create = comm, comm.create_comm

        def create_comm(**kwargs):
            self.comms.append(RecordingComm(**kwargs))
            return self.comms[-1]

        comm.create_comm = create_comm
        return self.comms

    def __exit__(self, *exc):
        import ipywidgets

        self._module.create_comm = self._create
        ipywidgets.Widget.close_all()


def _widget(kind):
    if kind == "player":
        from rbm_nb.widgets.player import Player

        return Player(np.arange(10.0))
    if kind == "timeseries":
        from rbm_nb.widgets.timeseries import TimeSeries

        return TimeSeries({"speed": (np.arange(10.0), np.ones(10))})
    from rbm_nb.scene import Scene

    scene = Scene()
    scene.add_frame("moving")
    return scene.widget


def browser_sets(kind, state, accepted=()):
    """The browser sends ``state`` to a new widget of ``kind`` as an update.

    Traits in ``accepted`` must take the value sent; every other one must keep
    the kernel's value, which is sent back to the browser. Returns what the
    widget refused."""
    with recorded_comms():
        widget = _widget(kind)
        before = {name: getattr(widget, name) for name in state}
        widget.comm.sent.clear()
        widget.comm.receive_state(state)
        restored = {}
        for data, _ in widget.comm.sent:
            if data.get("method") == "update":
                restored.update(data["state"])
        for name, value in state.items():
            if name in accepted:
                assert getattr(widget, name) == value, (name, getattr(widget, name))
                continue
            kept = getattr(widget, name)
            assert kept == before[name] or (
                kept != kept and before[name] != before[name]
            )
            assert name in restored, f"{name} was not sent back to the browser"
        refused = (
            [name for name, _, _ in widget.refused]
            if hasattr(widget, "refused")
            else []
        )
        assert sorted(refused) == sorted(set(state) - set(accepted)), refused
        return refused or ["nothing refused"]


# -- a Scene refuses an object whole, and stays usable (issue 31, items 4, 14) ----


def scene_refuses(method, *args, **kwargs):
    """Call ``scene.<method>`` on a scene holding one frame; whatever it raises,
    the scene must be unchanged and still take an add and a remove."""
    from rbm_nb.scene import Scene

    scene = Scene()
    scene.add_frame("moving")
    before = (len(scene), scene.camera if hasattr(scene, "camera") else None)
    try:
        getattr(scene, method)(*args, **kwargs)
    finally:
        assert (len(scene), getattr(scene, "camera", None)) == before
        handle = scene.add_points(np.zeros((2, 3)))
        handle.remove()
        assert len(scene) == before[0]
        camera = scene._camera or {}
        assert np.all(np.isfinite(np.asarray(camera.get("position", [0.0]))))


def browser_sends_ready(times, content=None):
    """A page sends ``times`` messages (``{"type": "ready"}`` by default) at once:
    one snapshot at once, at most one more for all the others."""
    with recorded_comms():
        widget = _widget("scene")
        comm = widget.comm
        comm.sent.clear()
        for _ in range(times):
            comm.receive({"type": "ready"} if content is None else content)

        def snapshots():
            return sum(
                1
                for data, _ in comm.sent
                if data.get("content", {}).get("type") == "snapshot"
            )

        at_once = snapshots()
        timer = widget._ready_timer
        if timer is not None:
            timer.join()  # the interval ends: the others are answered together
        total = snapshots()
        if content is not None:
            assert total == 0, total
        else:
            assert at_once == 1 and total == min(times, 2), (at_once, total)
        return [at_once, total]


# -- the rbm-nb command: one-line refusals before any work (items 7, issue 29) -----


class CommandRefused(Exception):
    """``rbm-nb`` exited with status 2; the message is what it printed."""


def rbm_nb_command(*argv):
    """Run ``rbm-nb <argv>`` in this process; a refusal must be one line, exit 2,
    and happen before anything is loaded or written."""
    import contextlib
    import io
    from unittest import mock

    from rbm_nb.app import cli

    def work(*args, **kwargs):
        raise AssertionError(f"rbm-nb {' '.join(argv)} started work")

    err = io.StringIO()
    out = io.StringIO()
    try:
        with (
            contextlib.redirect_stderr(err),
            contextlib.redirect_stdout(out),
            # a server or an export here would be work done before the refusal
            mock.patch.object(cli.os, "execv", work),
            mock.patch.object(cli.os, "execve", work),
            mock.patch.object(cli, "_html_demo", work),
            mock.patch.object(cli, "_text_demo", work),
            mock.patch("rbm_nb.app.server.serve", work),
        ):
            cli.main(list(argv))
    except SystemExit as stop:
        text = err.getvalue()
        assert stop.code == 2, (stop.code, text)
        assert text.count("\n") == 1 and out.getvalue() == "", (text, out.getvalue())
        raise CommandRefused(text.strip()) from None
    raise AssertionError(f"rbm-nb {' '.join(argv)} was not refused")


def bag_with_frame_id(child):
    """Register the tf tree of a bag whose transform names ``child``; a refusal
    must register nothing."""
    import tempfile
    from pathlib import Path

    from rbm_nb.ros import RosbagWriter, register_frames_from_bag

    with tempfile.TemporaryDirectory() as folder:
        bag = Path(folder) / "tf.bag"
        with RosbagWriter(bag) as writer:
            for frame, name in (("map", "odom"), ("odom", child)):
                writer.write_tf(
                    [1.0, 2.0], np.zeros((2, 3)), np.tile([1.0, 0, 0, 0], (2, 1)),
                    frame, name,
                )  # fmt: skip
        before = set(rbm.registry)
        try:
            register_frames_from_bag(bag)
        finally:
            assert set(rbm.registry) == before


def player_with_callbacks():
    """A raising on_time callback: the next still runs, the error is shown."""
    from rbm_nb.widgets.player import Player

    with recorded_comms():
        player = Player(np.arange(10.0))
        seen = []

        @player.on_time
        def broken(t):
            raise RuntimeError("callback boom")

        player.on_time(seen.append)
        player.time = 3.0
        assert seen == [3.0], seen
        assert "broken" in player.error and "callback boom" in player.error
        assert isinstance(player.error_object, RuntimeError)
        return seen


def plot_sends_exactly(values):
    """What a TimeSeries sends for ``values`` is what the browser decodes
    (``typed(v, Float64Array)`` in js/src/timeseries.js): the float64 values."""
    from rbm_nb.widgets.timeseries import TimeSeries

    values = np.asarray(values, dtype=float)
    with recorded_comms():
        plot = TimeSeries({"v": (np.arange(float(len(values))), values)})
        sent = np.frombuffer(plot.data[0]["y"][0], dtype="<f8")
        np.testing.assert_array_equal(sent, values)
        return sent.tolist()


def scene_time_clamped(t):
    """set_time without a player keeps to the times the scene can show."""
    from rbm_nb.scene import Scene

    with recorded_comms():
        scene = Scene()
        scene.add_frame("moving")
        widget = scene.widget
        scene.set_time(t)
        # 'moving' spans 0..9 s: kept between one span before and the end
        assert scene.time in (-9.0, 9.0), scene.time
        assert widget.time in (-9.0, 9.0), widget.time
        return [scene.time]


def mesh_file_in(folder, name, content):
    from rbm_nb.scene import Scene

    path = folder / name
    path.write_bytes(content)
    Scene().add_mesh("world", path)


def player_of(timestamps):
    from rbm_nb.widgets.player import Player

    return Player(timestamps)


def plot_with(**kwargs):
    from rbm_nb.widgets.timeseries import TimeSeries

    return TimeSeries({"v": (np.arange(20.0), np.ones(20))}, **kwargs)


def bag_keeps_quaternions_as_given(norm):
    """Documented (RosbagWriter.write_transform_stamped): a rotation of norm
    ``norm`` within the tolerance is written bit for bit; the transforms of
    the frames read from the bag use it normalised."""
    import tempfile
    from pathlib import Path

    from rbm_nb.ros import RosbagReader

    q = np.array([[np.cos(0.3), 0.0, 0.0, np.sin(0.3)]] * 2) * norm
    with tempfile.TemporaryDirectory() as folder:
        bag = Path(folder) / "q.bag"
        with rbm.ros.RosbagWriter(bag) as writer:
            writer.write_transform_stamped(
                [1.0, 2.0], np.zeros((2, 3)), q, "/x", "a", "b"
            )
        got = RosbagReader(bag).load_dataset("/x").orientation.values
    np.testing.assert_array_equal(got, q)
    rbm.register_frame("q", parent="world", rotation=q[0])
    moved = rbm.transform_vectors([1.0, 0.0, 0.0], "world", "q")
    np.testing.assert_allclose(np.linalg.norm(moved), 1.0, atol=1e-12)
    return got.tolist()


def moving_points_shape(n):
    """Documented: without timestamps, the whole array at every sample of the
    moving frame, under a new leading time axis."""
    out = rbm.transform_points(np.ones((n, 3)), "world", "moving")
    assert out.shape == (N, n, 3), out.shape
    for k in range(N):  # 'moving' at T[k]: turned 0.1 T[k] about z, at x = T[k]
        c, s_ = np.cos(0.1 * T[k]), np.sin(0.1 * T[k])
        expected = np.array([c - s_ + T[k], s_ + c, 1.0])
        np.testing.assert_allclose(out[k], np.tile(expected, (n, 1)), atol=1e-12)
    return list(out.shape)


def lookup_keeps_quaternions_as_given(norm):
    """Documented (lookup_transform, Notes): a frame against its parent at
    its own times gives its samples as stored, bit for bit, as the reference
    does; transforms rotate by the unit quaternion."""
    q = np.array([[np.cos(0.3), 0.0, 0.0, np.sin(0.3)]] * 3) * norm
    rbm.register_frame("q", parent="world", rotation=q, timestamps=[0.0, 1.0, 2.0])
    _, got = rbm.lookup_transform("q", "world")
    np.testing.assert_array_equal(got, q)
    moved = rbm.transform_vectors(
        np.tile([1.0, 0.0, 0.0], (3, 1)), "world", "q", timestamps=[0.0, 1.0, 2.0]
    )
    np.testing.assert_allclose(np.linalg.norm(moved, axis=1), 1.0, atol=1e-12)
    return got.tolist()


def velocity_of_frame_sampled_every(step):
    """A moving frame sampled ``step`` seconds apart, then its twist."""
    t = np.arange(5) * step
    rbm.register_frame(
        "fine",
        parent="world",
        timestamps=t,
        translation=np.column_stack([np.arange(5.0), np.zeros(5), np.zeros(5)]),
    )
    return rbm.lookup_twist("fine", "world")


# -- paths (issue 31, item 9) -----------------------------------------------------


def with_env(variables, func, *args, **kwargs):
    """``func(*args)`` with environment ``variables`` set, restored after."""
    import os

    old = {k: os.environ.get(k) for k in variables}
    os.environ.update(variables)
    try:
        return func(*args, **kwargs)
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def write_long_name(folder, kind, length=255):
    """A legal name of ``length`` bytes is written like any other."""
    name = {"html": "h", "bag": "b", "nc": "n", "ros2": "r"}[kind] * (
        length - len(kind) - 1
    )
    target = folder / f"{name}.{kind}" if kind != "ros2" else folder / ("r" * length)
    assert len(target.name.encode()) == length
    if kind == "html":
        html_export_to(target)
    elif kind in ("bag", "ros2"):
        _small_bag(target)
    else:
        rosbag_export_to(target)
    assert target.exists()
    assert sorted(p.name for p in folder.iterdir() if p.name.startswith(".")) == []
    return [len(target.name.encode())]


def write_through_dangling_link(folder):
    link = folder / "latest.html"
    link.symlink_to(folder / "runs" / "today" / "scene.html")
    try:
        html_export_to(link)
    finally:
        assert not (folder / "runs").exists(), "the link's folders were created"


def static_scene_export(folder):
    from rbm_nb.scene import Scene

    scene = Scene()
    scene.add_frame("static")
    scene.add_points(np.zeros((3, 3)))
    path = scene.to_html(folder / "static.html")
    assert path.stat().st_size > 0
    return [path.name]


def fetch_example(name="head"):
    from rbm_nb.data.fetch import ExampleDataStore

    return ExampleDataStore().fetch(name)


def cache_folder():
    from rbm_nb.data.fetch import cache_dir

    return cache_dir()


def failed_fetch_leaves_no_folder(folder):
    from rbm_nb.data.fetch import ExampleDataStore

    store = ExampleDataStore(
        data_dir=folder / "new" / "data", base_url="http://127.0.0.1:9/", timeout=5
    )
    try:
        store.fetch("head")
    finally:
        assert not (folder / "new").exists(), "a failed fetch created the folder"


def bag_cache_in_a_file(folder):
    """RBM_NB_CACHE_DIR names a file: the error says which variable to fix."""
    from rbm_nb.ros import RosbagReader

    data = folder / "data"
    data.mkdir()
    bag = _small_bag(data / "walk.bag")
    (folder / "not-a-folder").write_text("x")
    with_env(
        {
            "RBM_NB_DATA_DIR": str(data),
            "RBM_NB_CACHE_DIR": str(folder / "not-a-folder"),
        },
        lambda: RosbagReader(bag).load_dataset("/x", cache=True),
    )


# -- OptiTrack exports (issue 31, item 8) ------------------------------------------


def motive_csv(
    names=("Body A", "Body B"), ids=("ID1", "ID2"), start=None, times=None, angle="10"
):
    """A small Motive CSV export: two rigid bodies (Euler XYZ, mm), 3 frames."""
    start = start or "2020-06-16 07.51.41.245 PM"
    times = times or ["0", "0.1", "0.2"]
    cols = 2 + 6 * len(names)
    lines = [
        "Format Version,1.22,Take Name,T,Capture Frame Rate,10,Export Frame Rate,10,"
        f"Capture Start Time,{start},Total Frames in Take,3,Total Exported Frames,3,"
        "Rotation Type,XYZ,Length Units,Millimeters" + "," * (cols - 18),
        "," * (cols - 1),
        ",," + ",".join(["Rigid Body"] * 6 * len(names)),
        ",," + ",".join(n for n in names for _ in range(6)),
        ",," + ",".join(i for i in ids for _ in range(6)),
        ",," + ",".join((["Rotation"] * 3 + ["Position"] * 3) * len(names)),
        "Frame,Time (Seconds)," + ",".join(list("XYZXYZ") * len(names)),
    ]
    for k, t in enumerate(times):
        lines.append(
            f"{k},{t}," + ",".join([angle, "0", "0", "1", "2", "3"] * len(names))
        )
    return "\n".join(lines) + "\n"


def load_motive(folder, **changes):
    path = folder / "take.csv"
    path.write_text(motive_csv(**changes))
    return rbm.io.load_optitrack(path)


def motive_loads(folder):
    bodies = load_motive(folder)
    assert sorted(bodies) == ["Body A", "Body B"], sorted(bodies)
    return sorted(bodies)


def demo_data_note(folder, source, files, *expected):
    """What ``rbm-nb demo`` says about its data, with RBM_NB_DATA_DIR=folder."""
    from rbm_nb.app.cli import _data_note

    for name, text in files.items():
        (folder / name).write_text(text)
    note = with_env({"RBM_NB_DATA_DIR": str(folder)}, _data_note, source)
    assert note.count("\n") == 0, note
    for text in expected:
        assert text in note, (text, note)
    return note


RF = "ReferenceFrame"
Q1 = np.array([1.0, 0, 0, 0])
PTS = np.random.default_rng(7).normal(size=(12, 3))
NAN3 = np.array([np.nan, 0.0, 0.0])
INF3 = np.array([np.inf, 1.0, 1.0])


def _q_rows(*rows):
    return np.array(rows, dtype=float)


def _turning(n=5):
    a = 0.1 * np.arange(n)
    return np.column_stack([np.cos(a / 2), np.zeros(n), np.zeros(n), np.sin(a / 2)])


_NORM3 = _turning(5)
_NORM3[2] *= 3.0  # one far-from-unit row
_INFQ = _turning(5)
_INFQ[3, 0] = np.inf


# one row per line group reads as a table; keep the formatter out

# -- the facades that reach the door through _door.shapes / _door.series (issue 32) --


def gaze_directions_with(dims=("time", "cartesian_axis"), attrs=None, width=3):
    """gaze.angles of a DataArray shaped like gaze.directions' result, but not quite."""
    import xarray as xr

    directions = xr.DataArray(
        np.tile([1.0, 0.0, 0.0], (4, 1))[:, :width], dims=dims,
        coords={dims[0]: np.arange(4.0)},
        attrs={"representation_frame": "world"} if attrs is None else attrs,
    )  # fmt: skip
    return rbm.gaze.angles(directions, "world")


# fmt: off
CASES: list[Case] = [
    # -- ReferenceFrame construction ----------------------------------------
    Case("rf-translation-rows", RF, ("f", "world"),
         {"translation": np.zeros((5, 3)), "timestamps": np.arange(4.0)},
         ValueError, r"translation must have shape \(4, 3\), got \(5, 3\)"),
    Case("rf-rotation-rows", RF, ("f", "world"),
         {"rotation": np.tile(Q1, (3, 1)), "timestamps": np.arange(4.0)},
         ValueError, r"rotation must have shape \(4, 4\)"),
    Case("rf-translation-length", RF, ("f", "world"), {"translation": np.zeros(4)},
         ValueError, r"translation must have shape \(3,\)"),
    Case("rf-rotation-length", RF, ("f", "world"), {"rotation": np.zeros(3)},
         ValueError, r"rotation must have shape \(4,\)"),
    Case("rf-moving-without-timestamps", RF, ("f", "world"),
         {"translation": np.zeros((4, 3))}, ValueError, "needs timestamps"),
    Case("rf-timestamps-2d", RF, ("f", "world"),
         {"translation": np.zeros((4, 3)), "timestamps": np.zeros((4, 1))},
         ValueError, "one-dimensional"),
    Case("rf-empty", RF, ("f", "world"),
         {"translation": np.zeros((0, 3)), "timestamps": np.zeros(0)},
         ValueError, "must not be empty"),
    Case("rf-static-translation-nan", RF, ("f", "world"),
         {"translation": [0.0, np.nan, 0.0]}, ValueError,
         r"translation\[1\] is not finite"),
    Case("rf-static-translation-inf", RF, ("f", "world"),
         {"translation": [0.0, 0.0, -np.inf]}, ValueError,
         r"translation.*not finite"),
    Case("rf-static-rotation-inf", RF, ("f", "world"),
         {"rotation": [np.inf, 0, 0, 0]}, ValueError, r"rotation.*not finite"),
    Case("rf-moving-translation-inf-row", RF, ("f", "world"),
         {"translation": np.vstack([np.zeros((3, 3)), INF3]),
          "timestamps": np.arange(4.0)},
         ValueError, r"translation\[3\].*not finite"),
    Case("rf-moving-rotation-inf-row", RF, ("f", "world"),
         {"rotation": _INFQ, "timestamps": np.arange(5.0)},
         ValueError, r"rotation\[3\].*not finite"),
    Case("rf-translation-strings", RF, ("f", "world"),
         {"translation": ["a", "b", "c"]}, ValueError, "translation must be numeric"),
    Case("rf-rotation-strings", RF, ("f", "world"),
         {"rotation": ["a", "b", "c", "d"]}, ValueError, "rotation must be numeric"),
    Case("rf-timestamps-nan", RF, ("f", "world"),
         {"translation": np.zeros((4, 3)),
          "timestamps": np.array([0.0, 1.0, np.nan, 3.0])},
         ValueError, r"timestamps\[2\] is nan"),
    Case("rf-timestamps-inf", RF, ("f", "world"),
         {"translation": np.zeros((4, 3)),
          "timestamps": np.array([0.0, np.inf, 2.0, 3.0])},
         ValueError, r"timestamps\[1\] is inf"),
    Case("rf-timestamps-decreasing", RF, ("f", "world"),
         {"translation": np.zeros((4, 3)), "timestamps": [0.0, 2.0, 1.0, 3.0]},
         ValueError, r"strictly increasing.*timestamps\[2\]"),
    Case("rf-timestamps-duplicate", RF, ("f", "world"),
         {"translation": np.zeros((4, 3)), "timestamps": [0.0, 1.0, 1.0, 3.0]},
         ValueError, r"timestamps\[2\] = 1.0 is a duplicate"),
    Case("rf-timestamps-nat", RF, ("f", "world"),
         {"translation": np.zeros((4, 3)),
          "timestamps": np.array(["2020-01-01", "NaT", "2020-01-03", "2020-01-04"],
                                 dtype="datetime64[ns]")},
         ValueError, r"timestamps\[1\] is NaT"),
    Case("rf-timestamps-strings", RF, ("f", "world"),
         {"translation": np.zeros((4, 3)), "timestamps": np.array(list("abcd"))},
         ValueError, "numeric or datetime64"),
    Case("rf-zero-quaternion", RF, ("f", "world"), {"rotation": [0.0, 0, 0, 0]},
         ValueError, "zero quaternion"),
    Case("rf-quaternion-norm-1.2", RF, ("f", "world"), {"rotation": [1.2, 0, 0, 0]},
         ValueError, "norm 1.2; rotations must be unit quaternions"),
    Case("rf-moving-quaternion-norm-0.5", RF, ("f", "world"),
         {"rotation": _q_rows([1, 0, 0, 0], [0.5, 0, 0, 0]), "timestamps": [0.0, 1.0]},
         ValueError, r"rotation\[1\] is of norm 0.5"),
    Case("rf-parent-unknown", RF, ("f", "wordl"), {}, ValueError,
         "parent: frame 'wordl'.*did you mean 'world'"),
    Case("rf-parent-wrong-type", RF, ("f", 3.5), {}, TypeError, "parent"),
    Case("rf-from-rotation-matrix-not-orthogonal", "ReferenceFrame.from_rotation_matrix",
         (np.array([[1.0, 0, 0], [0, 2, 0], [0, 0, 1]]), "world"), {}, ValueError,
         "orthogonal|rotation matrix|mat"),
    Case("rf-from-rotation-matrix-reflection", "ReferenceFrame.from_rotation_matrix",
         (np.diag([1.0, 1.0, -1.0]), "world"), {}, ValueError,
         "determinant|reflection|proper|rotation matrix"),
    Case("rf-from-rotation-matrix-shape", "ReferenceFrame.from_rotation_matrix",
         (np.eye(2), "world"), {}, ValueError, r"3, 3|\(3, 3\)|3x3"),
    Case("rf-from-dataset-missing-variable", from_dataset, (), {"translation": "pos"},
         ValueError, "'pos'"),
    Case("rf-from-dataset-missing-time", from_dataset, (), {"timestamps": "t"},
         ValueError, "'t'"),
    # -- registry ------------------------------------------------------------
    Case("register-duplicate-name", "register_frame", ("moving",), {"parent": "world"},
         ValueError, "'moving' is already registered; pass update=True"),
    Case("register-without-name", lambda: rbm.ReferenceFrame().register(), (), {},
         ValueError, "without a name"),
    Case("register-parent-unknown", "register_frame", ("x",), {"parent": "wordl"},
         ValueError, "parent: frame 'wordl'"),
    Case("deregister-unknown", "deregister_frame", ("nope",), {}, ValueError,
         "'nope' not found"),
    Case("find-frame-unknown", "find_frame", ("world/nope",), {}, ValueError, "nope"),
    Case("registry-del-unknown", registry_del, ("nope",), {}, KeyError, "nope"),
    Case("registry-set-not-a-frame", registry_set, ("x", 3), {}, TypeError,
         "ReferenceFrame"),
    Case("register-same-object-twice", register_twice, ("twice",), {}, ValueError,
         "'twice' is already registered"),
    # -- lookups -------------------------------------------------------------
    Case("lookup-unknown-frame", "lookup_transform", ("haed", "world"), {},
         ValueError, r"'haed' not found in registry"),
    Case("lookup-unknown-into", "lookup_transform", ("moving", "wrold"), {},
         ValueError, "'wrold'.*did you mean 'world'"),
    Case("lookup-frame-wrong-type", "lookup_transform", (3, "world"), {}, TypeError,
         "ReferenceFrame or the name"),
    Case("lookup-different-trees", "lookup_transform", ("moving", "other_root"), {},
         ValueError, "different trees"),
    Case("lookup-time-string", "lookup_transform", ("moving", "world"),
         {"time": "soon"}, ValueError, "time"),
    Case("lookup-time-nan", "lookup_transform", ("moving", "world"),
         {"time": np.nan}, ValueError, "time"),
    Case("lookup-pose-unknown-reference", "lookup_pose", ("moving", "wrld"), {},
         ValueError, "'wrld'"),
    Case("lookup-twist-mode", "lookup_twist", ("moving", "world"), {"mode": "euler"},
         ValueError, "mode must be 'quaternion' or 'rotation_vector'"),
    Case("lookup-twist-cutoff-above-1", "lookup_twist", ("moving", "world"),
         {"cutoff": 2.0}, ValueError, r"cutoff.*\(0, 1\)"),
    Case("lookup-twist-cutoff-too-few-samples", "lookup_twist", ("moving", "world"),
         {"cutoff": 0.5}, ValueError, "cutoff: the low-pass filter needs more than"),
    Case("lookup-twist-outlier-negative", "lookup_twist", ("moving", "world"),
         {"outlier_thresh": -1.0}, ValueError, "outlier_thresh must be a non-negative"),
    Case("lookup-twist-outlier-string", "lookup_twist", ("moving", "world"),
         {"outlier_thresh": "big"}, ValueError, "outlier_thresh"),
    Case("lookup-twist-represent-in-unknown", "lookup_twist", ("moving", "world"),
         {"represent_in": "nope"}, ValueError, "'nope'"),
    Case("lookup-linear-velocity-one-sample", "lookup_linear_velocity",
         ("one", "world"), {}, ValueError, "at least 2 samples"),
    Case("lookup-angular-velocity-one-sample", "lookup_angular_velocity",
         ("one", "world"), {}, ValueError, "at least 2 samples"),
    Case("transform-angular-velocity-one-sample-frame", "transform_angular_velocity",
         (np.zeros((1, 3)), "world", "one"), {"timestamps": [0.0]}, ValueError,
         "at least 2 samples"),
    Case("lookup-twist-one-sample", "lookup_twist", ("one", "world"), {}, ValueError,
         "at least 2 samples"),
    Case("lookup-no-sample-in-window", "lookup_transform", ("moving", "short"), {},
         ValueError, r"no sample|no timestamp|none of the \d+ samples|falls? (with)?in"),
    Case("lookup-velocity-no-sample-in-window", "lookup_linear_velocity",
         ("moving", "short"), {}, ValueError,
         r"no sample|no timestamp|none of the \d+ samples|falls? (with)?in"),
    Case("frame-lookup-transform-unknown", frame_method,
         ("moving", "lookup_transform", "nope"), {}, ValueError, "'nope'"),
    # -- transforms ----------------------------------------------------------
    Case("points-unknown-into", "transform_points", (np.zeros(3), "wrld", "static"),
         {}, ValueError, "into: frame 'wrld'"),
    Case("points-unknown-outof", "transform_points", (np.zeros(3), "world", "statc"),
         {}, ValueError, "outof: frame 'statc'"),
    Case("points-last-axis-4", "transform_points", (np.zeros((2, 4)), "world", "static"),
         {}, ValueError, "length 3 along axis -1"),
    Case("points-axis-out-of-range", "transform_points",
         (np.zeros((2, 3)), "world", "static"), {"axis": 2}, ValueError,
         "axis=2 is out of range"),
    Case("points-axis-not-int", "transform_points",
         (np.zeros((2, 3)), "world", "static"), {"axis": 1.5}, ValueError, "axis"),
    Case("points-strings", "transform_points", (np.array(list("abc")), "world", "static"),
         {}, ValueError, "arr must be numeric"),
    Case("points-timestamps-decreasing", "transform_points",
         (np.zeros((4, 3)), "world", "moving"), {"timestamps": [0.0, 1.0, 3.0, 2.0]},
         ValueError, r"timestamps\[3\] = 2.0 is earlier than timestamps\[2\] = 3.0"),
    Case("points-timestamps-duplicate", "transform_points",
         (np.zeros((4, 3)), "world", "moving"), {"timestamps": [0.0, 0.0, 3.0, 4.0]},
         ValueError, r"timestamps\[1\] = 0.0 is a duplicate"),
    Case("points-timestamps-length", "transform_points",
         (np.zeros((4, 3)), "world", "moving"), {"timestamps": [0.0, 1.0, 2.0]},
         ValueError, "has 3 entries but the data has 4 samples"),
    Case("points-timestamps-nan", "transform_points",
         (np.zeros((4, 3)), "world", "moving"),
         {"timestamps": [np.nan, 1.0, 2.0, 3.0]}, ValueError, r"timestamps\[0\] is nan"),
    Case("points-no-overlap", "transform_points", (np.zeros((5, 3)), "world", "moving"),
         {"timestamps": np.arange(20.0, 25.0)}, ValueError,
         r"do not overlap.*frame 'moving': 0.0 to 9.0"),
    Case("points-time-axis-out-of-range", "transform_points",
         (np.zeros((4, 3)), "world", "moving"),
         {"timestamps": np.arange(4.0), "time_axis": 3}, ValueError, "time_axis"),
    Case("points-inf", "transform_points", (INF3[None], "world", "static"), {},
         ValueError, r"arr.*not finite"),
    Case("vectors-inf", "transform_vectors", (INF3[None], "world", "static"), {},
         ValueError, r"arr.*not finite"),
    Case("points-moving-inf", "transform_points", (np.vstack([np.zeros((3, 3)), INF3]),
         "world", "moving"), {"timestamps": np.arange(4.0)}, ValueError,
         r"arr.*not finite"),
    Case("quaternions-norm-2", "transform_quaternions",
         (_q_rows([1, 0, 0, 0], [2, 0, 0, 0]), "world", "static"), {}, ValueError,
         r"arr\[1\] is of norm 2"),
    Case("quaternions-last-axis-3", "transform_quaternions",
         (np.zeros((2, 3)), "world", "static"), {}, ValueError,
         "length 4 along axis -1"),
    Case("quaternions-inf", "transform_quaternions",
         (_q_rows([np.inf, 0, 0, 0]), "world", "static"), {}, ValueError,
         r"arr.*not finite"),
    Case("angular-velocity-what", "transform_angular_velocity",
         (np.zeros((4, 3)), "world", "moving"),
         {"what": "nonsense", "timestamps": np.arange(4.0)}, ValueError,
         "what must be one of"),
    Case("linear-velocity-what", "transform_linear_velocity",
         (np.zeros((4, 3)), "world", "moving"),
         {"what": "nonsense", "timestamps": np.arange(4.0)}, ValueError,
         "what must be one of"),
    Case("angular-velocity-inf", "transform_angular_velocity",
         (INF3[None], "world", "static"), {}, ValueError, r"arr.*not finite"),
    Case("dataarray-time-without-coordinate", dataarray_points, (),
         {"coords": {}, "timestamps": "time"}, ValueError,
         r"time.*(no coordinate|coordinate)"),
    Case("dataarray-timestamps-unknown-coordinate", dataarray_points, (),
         {"timestamps": "stamp"}, ValueError, "'stamp'"),
    Case("dataarray-dim-unknown", dataarray_points, (), {"dim": "xyz"}, ValueError,
         "'xyz'"),
    Case("coordinates-into-unknown", "transform_coordinates", (np.ones(3), "bogus"),
         {"outof": "cartesian"}, ValueError, "'bogus'"),
    Case("coordinates-outof-unknown", "transform_coordinates", (np.ones(3), "polar"),
         {"outof": "bogus"}, ValueError, "'bogus'"),
    Case("coordinates-wrong-length", "transform_coordinates",
         (np.ones(4), "spherical"), {"outof": "cartesian"}, ValueError,
         r"length 3|\b3\b"),
    # -- estimators ----------------------------------------------------------
    Case("linvel-no-timestamps", "estimate_linear_velocity", (np.zeros((4, 3)),), {},
         ValueError, "timestamps"),
    Case("linvel-timestamps-decreasing", "estimate_linear_velocity",
         (np.zeros((4, 3)),), {"timestamps": [0.0, 2.0, 1.0, 3.0]}, ValueError,
         "strictly increasing"),
    Case("linvel-timestamps-length", "estimate_linear_velocity", (np.zeros((4, 3)),),
         {"timestamps": [0.0, 1.0]}, ValueError, r"one entry per sample \(4\)"),
    Case("linvel-timestamps-nan", "estimate_linear_velocity", (np.zeros((4, 3)),),
         {"timestamps": [0.0, 1.0, np.nan, 3.0]}, ValueError, "timestamps must be finite"),
    Case("linvel-timestamps-strings", "estimate_linear_velocity", (np.zeros((4, 3)),),
         {"timestamps": np.array(list("abcd"))}, ValueError,
         "timestamps must be numbers or datetime64"),
    Case("linvel-cutoff-1.5", "estimate_linear_velocity", (np.zeros((40, 3)),),
         {"timestamps": np.arange(40.0), "cutoff": 1.5}, ValueError, r"cutoff.*\(0, 1\)"),
    Case("linvel-cutoff-too-few", "estimate_linear_velocity", (np.zeros((10, 3)),),
         {"timestamps": np.arange(10.0), "cutoff": 0.5}, ValueError,
         "cutoff: the low-pass filter needs more than"),
    Case("linvel-outlier-negative", "estimate_linear_velocity", (np.zeros((4, 3)),),
         {"timestamps": np.arange(4.0), "outlier_thresh": -1}, ValueError,
         "outlier_thresh must be a non-negative"),
    Case("linvel-one-sample", "estimate_linear_velocity", (np.zeros((1, 3)),),
         {"timestamps": [0.0]}, ValueError, "at least 2 samples"),
    Case("linvel-dim-with-ndarray", "estimate_linear_velocity", (np.zeros((4, 3)), "x"),
         {"timestamps": np.arange(4.0)}, ValueError,
         "dim can only be given when arr is a DataArray"),
    Case("linvel-inf", "estimate_linear_velocity",
         (np.vstack([np.zeros((3, 3)), INF3]),), {"timestamps": np.arange(4.0)},
         ValueError, r"arr.*not finite"),
    Case("angvel-one-sample", "estimate_angular_velocity", (Q1[None],),
         {"timestamps": [0.0]}, ValueError, "at least 2 samples"),
    Case("angvel-one-sample-datetime", "estimate_angular_velocity", (Q1[None],),
         {"timestamps": np.array(["2020-01-01"], dtype="datetime64[ns]")}, ValueError,
         "at least 2 samples"),
    Case("angvel-zero-quaternion", "estimate_angular_velocity",
         (_q_rows([1, 0, 0, 0], [0, 0, 0, 0], [1, 0, 0, 0]),),
         {"timestamps": np.arange(3.0)}, ValueError, "zero quaternion"),
    Case("angvel-norm-3-row", "estimate_angular_velocity", (_NORM3,),
         {"timestamps": np.arange(5.0)}, ValueError, r"arr\[2\] is of norm 3"),
    Case("angvel-inf-row", "estimate_angular_velocity", (_INFQ,),
         {"timestamps": np.arange(5.0)}, ValueError, r"arr\[3\].*not finite"),
    Case("angvel-axis-length-3", "estimate_angular_velocity", (np.zeros((4, 3)),),
         {"timestamps": np.arange(4.0)}, ValueError, "length 4 .*along axis"),
    Case("angvel-mode", "estimate_angular_velocity", (_turning(),),
         {"timestamps": np.arange(5.0), "mode": "euler"}, ValueError,
         "mode must be 'quaternion' or 'rotation_vector'"),
    Case("shortest-arc-nan", "shortest_arc_rotation", (NAN3, [0.0, 1.0, 0.0]), {},
         ValueError, r"v1.*not finite"),
    Case("shortest-arc-inf-v2", "shortest_arc_rotation", ([1.0, 0, 0], INF3), {},
         ValueError, r"v2.*not finite"),
    Case("shortest-arc-zero", "shortest_arc_rotation", ([0.0, 0, 0], [0.0, 1, 0]), {},
         ValueError, "v1.*zero"),
    Case("shortest-arc-length-4", "shortest_arc_rotation",
         (np.ones(4), np.ones(4)), {}, ValueError, "length 3"),
    Case("best-fit-rotation-shapes", "best_fit_rotation", (PTS, PTS[:-1]), {},
         ValueError, r"v1.*v2|shape"),
    Case("best-fit-rotation-nan", "best_fit_rotation",
         (np.vstack([PTS, NAN3]), np.vstack([PTS, PTS[:1]])), {}, ValueError,
         r"v1.*finite"),
    Case("best-fit-transform-inf", "best_fit_transform",
         (PTS, np.vstack([PTS[:-1], INF3])), {}, ValueError, r"v2.*finite"),
    Case("best-fit-transform-length-2", "best_fit_transform",
         (np.zeros((5, 2)), np.zeros((5, 2))), {}, ValueError, "length 3"),
    Case("icp-init-nan", "iterative_closest_point", (PTS, PTS),
         {"init_transform": (NAN3, Q1)}, ValueError, r"init_transform.*not finite"),
    Case("icp-init-rotation-zero", "iterative_closest_point", (PTS, PTS),
         {"init_transform": (np.zeros(3), np.zeros(4))}, ValueError,
         r"init_transform.*zero quaternion"),
    Case("icp-init-wrong-shape", "iterative_closest_point", (PTS, PTS),
         {"init_transform": (np.zeros(2), Q1)}, ValueError, "init_transform"),
    Case("icp-max-iterations-nan", "iterative_closest_point", (PTS, PTS),
         {"max_iterations": np.nan}, ValueError, "max_iterations"),
    Case("icp-max-iterations-negative", "iterative_closest_point", (PTS, PTS),
         {"max_iterations": -3}, ValueError, "max_iterations"),
    Case("icp-max-iterations-fraction", "iterative_closest_point", (PTS, PTS),
         {"max_iterations": 2.5}, ValueError, "max_iterations"),
    Case("icp-tolerance-nan", "iterative_closest_point", (PTS, PTS),
         {"tolerance": np.nan}, ValueError, "tolerance"),
    Case("icp-tolerance-negative", "iterative_closest_point", (PTS, PTS),
         {"tolerance": -1.0}, ValueError, "tolerance"),
    Case("icp-nan-points", "iterative_closest_point", (np.vstack([PTS, NAN3]), PTS),
         {}, ValueError, r"v1.*finite"),
    # -- quaternion utilities -------------------------------------------------
    Case("euler-roll-nan", "from_euler_angles", (), {"roll": np.nan}, ValueError,
         r"roll.*not finite"),
    Case("euler-rpy-inf", "from_euler_angles", ([0.0, np.inf, 0.0],), {}, ValueError,
         r"rpy.*not finite"),
    Case("euler-rpy-and-roll", "from_euler_angles", ([0.0, 0, 0],), {"roll": 1.0},
         ValueError, "rpy.*roll|roll.*rpy"),
    Case("euler-rpy-length", "from_euler_angles", ([0.0, 0],), {}, ValueError,
         r"rpy.*length 3|rpy.*3"),
    Case("euler-order", "from_euler_angles", ([0.0, 0, 0],), {"order": "abc"},
         ValueError, "order"),
    Case("qinv-length-3", "qinv", (np.zeros(3),), {}, ValueError, "length 4"),
    Case("qmul-no-arguments", "qmul", (), {}, ValueError, "at least"),
    Case("qmul-shapes", "qmul", (np.tile(Q1, (2, 1)), np.tile(Q1, (3, 1))), {},
         ValueError, r"broadcast|shape"),
    Case("qmean-zero", "qmean", (_q_rows([1, 0, 0, 0], [0, 0, 0, 0]),), {}, ValueError,
         "zero quaternion"),
    Case("qmean-inf", "qmean", (_INFQ,), {}, ValueError, r"q.*not finite"),
    Case("qinterp-norm-3-row", "qinterp", (_NORM3, np.arange(5.0), [1.5]), {},
         ValueError, r"q\[2\] is of norm 3"),
    Case("qinterp-t-in-decreasing", "qinterp",
         (_turning(3), [0.0, 2.0, 1.0], [0.5]), {}, ValueError, "t_in"),
    Case("qinterp-t-in-length", "qinterp", (_turning(3), [0.0, 1.0], [0.5]), {},
         ValueError, "t_in"),
    Case("qinterp-t-out-nan", "qinterp", (_turning(3), [0.0, 1.0, 2.0], [np.nan]), {},
         ValueError, "t_out"),
    Case("qinterp-inf", "qinterp", (_INFQ, np.arange(5.0), [1.5]), {}, ValueError,
         r"q\[3\].*not finite"),
    Case("rotate-vectors-v-length", "rotate_vectors", (Q1, np.zeros(4)), {},
         ValueError, r"v.*length 3"),
    Case("rotate-vectors-zero-q", "rotate_vectors", (np.zeros(4), np.ones(3)), {},
         ValueError, "zero quaternion"),
    Case("rotate-vectors-inf", "rotate_vectors", (Q1, INF3), {}, ValueError,
         r"v.*not finite"),
    Case("accessor-qinterp-two-dims", accessor_qinterp, (),
         {"time": [0.5], "quaternion_axis": ["w"]}, NotImplementedError,
         "single dimension|one dimension"),
    Case("accessor-qinterp-2d-time", accessor_qinterp, (),
         {"time": np.zeros((2, 2))}, NotImplementedError, "one-dimensional"),
    Case("accessor-qinterp-unknown-dim", accessor_qinterp, (), {"stamp": [0.5]},
         ValueError, "'stamp'"),
    # -- coordinate systems ---------------------------------------------------
    Case("cartesian-to-polar-length-3", "cartesian_to_polar", (np.ones(3),), {},
         ValueError, "length 2"),
    Case("polar-to-cartesian-length-3", "polar_to_cartesian", (np.ones(3),), {},
         ValueError, "length 2"),
    Case("cartesian-to-spherical-length-2", "cartesian_to_spherical", (np.ones(2),), {},
         ValueError, "length 3"),
    Case("spherical-to-cartesian-axis", "spherical_to_cartesian", (np.ones(3),),
         {"axis": 1}, ValueError, "axis"),
    Case("cartesian-to-spherical-inf", "cartesian_to_spherical", (INF3,), {},
         ValueError, r"arr.*not finite"),
    # -- conversions and Transform --------------------------------------------
    Case("quaternion-from-matrix-scaled", "quaternion_from_matrix", (2 * np.eye(3),),
         {}, ValueError, "orthogonal|rotation matri"),
    Case("quaternion-from-matrix-shape", "quaternion_from_matrix", (np.eye(4),), {},
         ValueError, r"3, 3"),
    Case("matrix-from-quaternion-zero", "matrix_from_quaternion", (np.zeros(4),), {},
         ValueError, "zero quaternion|norm 0"),
    Case("matrix-from-quaternion-nan", "matrix_from_quaternion",
         (np.array([np.nan, 0, 0, 0]),), {}, ValueError, "not finite"),
    Case("quaternion-from-rotation-vector-length", "quaternion_from_rotation_vector",
         (np.zeros(4),), {}, ValueError, "length 3|3"),
    Case("quaternion-from-axis-angle-zero-axis", "quaternion_from_axis_angle",
         (np.zeros(3), 1.0), {}, ValueError, "axis"),
    Case("quaternion-from-euler-order", "quaternion_from_euler", (np.zeros(3), "xyw"),
         {}, ValueError, "order"),
    Case("euler-from-quaternion-order", "euler_from_quaternion", (Q1, "xxz"), {},
         ValueError, "order"),
    Case("homogeneous-from-transform-translation", "homogeneous_from_transform",
         (np.zeros(2), Q1), {}, ValueError, "translation"),
    Case("transform-from-homogeneous-last-row", "transform_from_homogeneous",
         (np.ones((4, 4)),), {}, ValueError, "last row|bottom row|homogeneous|0, 0, 0, 1"),
    Case("Transform-translation-length", "Transform", (np.zeros(2),), {}, ValueError,
         "translation"),
    Case("Transform-rotation-zero", "Transform", (np.zeros(3), np.zeros(4)), {},
         ValueError, "zero quaternion"),
    Case("Transform-apply-length", transform_method, ("apply", np.zeros(4)), {},
         ValueError, "length 3"),
    # -- ros.Transformer (tf2-like buffer) -------------------------------------
    Case("transformer-cache-time-negative", new_transformer, (), {"cache_time": -1.0},
         ValueError, "cache_time must be >= 0"),
    Case("transformer-unknown-target", transformer,
         ("lookup_transform", "wrld", "static"), {}, ValueError,
         "target_frame 'wrld' does not exist"),
    Case("transformer-unknown-source", transformer,
         ("lookup_transform", "world", "statik"), {}, ValueError,
         "source_frame 'statik' does not exist"),
    Case("transformer-quaternion-zero", transformer,
         ("transform_quaternion", np.zeros(4), "world", "static"), {}, ValueError,
         "zero quaternion"),
    Case("transformer-point-length", transformer,
         ("transform_point", (1.0, 2.0), "world", "static"), {}, ValueError, "p|point"),
    Case("transformer-set-transform-shapes", transformer,
         ("set_transform", np.zeros((3, 3)), np.tile(Q1, (2, 1)), "world", "x"),
         {"time": [0.0, 1.0, 2.0]}, ValueError, r"\(3, 3\) and \(3, 4\)"),
    Case("transformer-set-transform-time-nan", transformer,
         ("set_transform", np.zeros(3), Q1, "world", "x"), {"time": np.nan},
         ValueError, "time is nan; a time must be a finite number"),
    # -- files: OptiTrack, netCDF, rosbag writer ----------------------------------
    Case("optitrack-missing-file", in_temp_folder, (optitrack_in, "nope.csv"), {},
         FileNotFoundError, "nope.csv"),
    Case("optitrack-not-an-export", in_temp_folder, (optitrack_in, "x.csv"),
         {"files": {"x.csv": "hello,world\n1,2\n"}}, rbm.io.FileFormatError,
         "x.csv is not an OptiTrack CSV export"),
    Case("optitrack-import-format", in_temp_folder, (optitrack_in, "x.csv"),
         {"files": {"x.csv": "a"}, "import_format": "excel"}, ValueError,
         "import_format must be one of"),
    Case("netcdf-missing-file", in_temp_folder, (netcdf_in, "nope.nc"), {},
         FileNotFoundError, "nope.nc"),
    Case("netcdf-not-netcdf", in_temp_folder, (netcdf_in, "y.nc"),
         {"files": {"y.nc": "not netcdf"}}, rbm.io.FileFormatError,
         "y.nc is not a readable netCDF file"),
    Case("rosbag-writer-storage", in_temp_folder, (write_bag_in, "b", [1.0]),
         {"storage": "zip"}, ValueError, "storage must be one of"),
    Case("rosbag-writer-storage-for-ros1", in_temp_folder,
         (write_bag_in, "b.bag", [1.0]), {"storage": "mcap"}, ValueError,
         "storage is for ROS2 bags"),
    Case("rosbag-writer-decreasing-stamps", in_temp_folder,
         (write_bag_in, "w.bag", [2.0, 1.0]), {}, ValueError, "timestamps"),
    # -- writers never delete a folder they did not make (issue 31, item 1) -------
    Case("export-netcdf-into-folder", writer_at_user_folder,
         ("thesis", rosbag_export_to), {}, IsADirectoryError,
         r"refusing to replace a folder .*thesis'$"),
    Case("rosbag-writer-ros2-into-folder", writer_at_user_folder,
         ("notes", rosbag_write_to), {}, IsADirectoryError,
         r"not a ROS2 bag folder.*everything in it would be lost"),
    Case("rosbag-writer-ros1-into-folder", writer_at_user_folder,
         ("old.bag", rosbag_write_to), {}, IsADirectoryError,
         r"refusing to replace a folder .*old.bag'$"),
    Case("rosbag-writer-ros2-into-bag-with-notes", writer_at_user_folder,
         ("run1", rosbag_write_to,
          {"metadata.yaml": "rosbag2_bagfile_information:\n", "run1.db3": ""}),
         {}, IsADirectoryError, "not a ROS2 bag folder holding only metadata.yaml"),
    Case("rosbag-writer-ros2-over-file", ros2_bag_over_file, ("notes",), {},
         NotADirectoryError, r"refusing to replace a file with a ROS2 bag folder"),
    Case("synthetic-rosbag-into-folder", writer_at_user_folder,
         ("synthetic.bag", synthetic_rosbag_to), {}, IsADirectoryError,
         r"refusing to replace a folder .*synthetic.bag'$"),
    Case("study-to-netcdf-into-folder", writer_at_user_folder,
         ("s0.nc", study_to_netcdf_at), {}, IsADirectoryError,
         r"refusing to replace a folder .*s0.nc'$"),
    Case("to-html-into-folder", writer_at_user_folder,
         ("scene.html", html_export_to), {}, IsADirectoryError,
         r"scene.html.* is a directory|refusing to replace a folder"),
    # -- hostile strings in every string an HTML export embeds (item 3) ---------
    Case("export-comment-script-in-frame", export_with_hostile_string,
         (HOSTILE_STRINGS["comment-script"], "frame"), {}, None, ""),
    Case("export-comment-script-in-label", export_with_hostile_string,
         (HOSTILE_STRINGS["comment-script"], "label"), {}, None, ""),
    Case("export-comment-script-in-units", export_with_hostile_string,
         (HOSTILE_STRINGS["comment-script"], "units"), {}, None, ""),
    Case("export-comment-script-in-panel", export_with_hostile_string,
         (HOSTILE_STRINGS["comment-script"], "panel"), {}, None, ""),
    Case("export-comment-script-in-title", export_with_hostile_string,
         (HOSTILE_STRINGS["comment-script"], "title"), {}, None, ""),
    Case("export-end-script-in-frame", export_with_hostile_string,
         (HOSTILE_STRINGS["end-script"], "frame"), {}, None, ""),
    Case("export-end-script-in-label", export_with_hostile_string,
         (HOSTILE_STRINGS["end-script"], "label"), {}, None, ""),
    Case("export-end-script-in-units", export_with_hostile_string,
         (HOSTILE_STRINGS["end-script"], "units"), {}, None, ""),
    Case("export-end-script-in-panel", export_with_hostile_string,
         (HOSTILE_STRINGS["end-script"], "panel"), {}, None, ""),
    Case("export-end-script-in-title", export_with_hostile_string,
         (HOSTILE_STRINGS["end-script"], "title"), {}, None, ""),
    Case("export-line-separators-in-frame", export_with_hostile_string,
         (HOSTILE_STRINGS["line-separators"], "frame"), {}, None, ""),
    Case("export-line-separators-in-label", export_with_hostile_string,
         (HOSTILE_STRINGS["line-separators"], "label"), {}, None, ""),
    Case("export-line-separators-in-units", export_with_hostile_string,
         (HOSTILE_STRINGS["line-separators"], "units"), {}, None, ""),
    Case("export-line-separators-in-panel", export_with_hostile_string,
         (HOSTILE_STRINGS["line-separators"], "panel"), {}, None, ""),
    Case("export-line-separators-in-title", export_with_hostile_string,
         (HOSTILE_STRINGS["line-separators"], "title"), {}, None, ""),
    Case("export-ampersand-tags-in-frame", export_with_hostile_string,
         (HOSTILE_STRINGS["ampersand-tags"], "frame"), {}, None, ""),
    Case("export-ampersand-tags-in-label", export_with_hostile_string,
         (HOSTILE_STRINGS["ampersand-tags"], "label"), {}, None, ""),
    Case("export-ampersand-tags-in-units", export_with_hostile_string,
         (HOSTILE_STRINGS["ampersand-tags"], "units"), {}, None, ""),
    Case("export-ampersand-tags-in-panel", export_with_hostile_string,
         (HOSTILE_STRINGS["ampersand-tags"], "panel"), {}, None, ""),
    Case("export-ampersand-tags-in-title", export_with_hostile_string,
         (HOSTILE_STRINGS["ampersand-tags"], "title"), {}, None, ""),
    # -- the browser sets only what is its own, validated (item 5) -------------
    Case("browser-player-duration-negative", browser_sets, ("player", {'duration': -1.0}), {}, None, ""),
    Case("browser-player-duration-nan", browser_sets, ("player", {'duration': np.nan}), {}, None, ""),
    Case("browser-player-origin-nan", browser_sets, ("player", {'origin': np.nan}), {}, None, ""),
    Case("browser-player-t0-ns-year-39381", browser_sets, ("player", {'t0_ns': 1180591620717411303424}), {}, None, ""),
    Case("browser-player-error-set", browser_sets, ("player", {'error': 'fake'}), {}, None, ""),
    Case("browser-player-esm-replaced", browser_sets, ("player", {'_esm': 'alert(1)'}), {}, None, ""),
    Case("browser-player-time-nan", browser_sets, ("player", {'time': np.nan}), {}, None, ""),
    Case("browser-player-speed-negative", browser_sets, ("player", {'speed': -2.0}), {}, None, ""),
    Case("browser-player-skip-from-browser", browser_sets, ("player", {'skip': 1000000000.0}), {}, None, ""),
    Case("browser-scene-time-nan", browser_sets, ("scene", {'time': np.nan}), {}, None, ""),
    Case("browser-scene-time-inf", browser_sets, ("scene", {'time': np.inf}), {}, None, ""),
    Case("browser-scene-height-huge", browser_sets, ("scene", {'height': 1000000000}), {}, None, ""),
    Case("browser-scene-selected-unknown", browser_sets, ("scene", {'selected': 'nope'}), {}, None, ""),
    Case("browser-scene-follow-not-drawn", browser_sets, ("scene", {'follow': 'static'}), {}, None, ""),
    Case("browser-scene-esm-replaced", browser_sets, ("scene", {'_esm': 'alert(1)'}), {}, None, ""),
    Case("browser-scene-frames-replaced", browser_sets, ("scene", {'_frames': {}}), {}, None, ""),
    Case("browser-timeseries-time-nan", browser_sets, ("timeseries", {'time': np.nan}), {}, None, ""),
    Case("browser-timeseries-x-range-reversed", browser_sets, ("timeseries", {'x_range': [5.0, 1.0]}), {}, None, ""),
    Case("browser-timeseries-x-range-three", browser_sets, ("timeseries", {'x_range': [1.0, 2.0, 3.0]}), {}, None, ""),
    Case("browser-timeseries-panel-height-negative", browser_sets, ("timeseries", {'panel_height': -5}), {}, None, ""),
    Case("browser-timeseries-panels-garbage", browser_sets, ("timeseries", {'panels': [{'label': 1}]}), {}, None, ""),
    Case("browser-timeseries-data-garbage", browser_sets, ("timeseries", {'data': [{}]}), {}, None, ""),
    Case("browser-timeseries-t0-ns", browser_sets, ("timeseries", {'t0_ns': 1180591620717411303424}), {}, None, ""),
    Case("browser-timeseries-esm-replaced", browser_sets, ("timeseries", {'_esm': 'alert(1)'}), {}, None, ""),
    Case("browser-player-time-kept-duration-refused", browser_sets,
         ("player", {"time": 2.5, "duration": -1.0}, ("time",)), {}, None, ""),
    Case("browser-scene-selected-known-frame", browser_sets,
         ("scene", {"selected": "moving", "height": 10**9}, ("selected",)), {}, None, ""),
    Case("browser-timeseries-zoom-accepted", browser_sets,
         ("timeseries", {"x_range": [1.0, 5.0], "panels": []}, ("x_range",)), {}, None,
         ""),
    # -- a Scene refuses what it cannot draw, whole (item 4) ----------------------
    Case("scene-points-overflow", scene_refuses,
         ("add_points", [[1e308, 1e308, 0.0], [-1e308, -1e308, 0.0]]), {}, ValueError,
         r"add_points: 'points_world' reaches 1e\+308 m .*draws within 1e\+09 m"),
    Case("scene-frame-scale-1e308", scene_refuses, ("add_frame", "static"),
         {"scale": 1e308}, ValueError, r"add_frame: .* reaches 1e\+308 m"),
    Case("scene-vectors-length-overflow", scene_refuses,
         ("add_vectors", "world", [[1.0, 0.0, 0.0]]), {"length": 1e300}, ValueError,
         r"add_vectors: .* reaches"),
    Case("scene-path-huge-frame", scene_refuses, ("add_path", "huge"), {},
         ValueError, r"add_path: .* reaches"),
    Case("scene-mesh-huge", scene_refuses, ("add_mesh", "world", "box"),
         {"size": [1e300, 1.0, 1.0]}, ValueError, r"add_mesh: .* reaches"),
    # -- "ready" messages answered at most twice per interval (item 6) ------------
    Case("browser-ready-once", browser_sends_ready, (1,), {}, None, ""),
    Case("browser-ready-flood-10", browser_sends_ready, (10,), {}, None, ""),
    Case("browser-ready-flood-200", browser_sends_ready, (200,), {}, None, ""),
    Case("browser-custom-not-a-dict", browser_sends_ready, (3, "ready"), {}, None, ""),
    Case("browser-custom-unknown-type", browser_sends_ready, (3, {"type": "redy"}), {},
         None, ""),
    # -- the rbm-nb command refuses in one line, before any work (item 7) -------
    Case("cli-html-empty", rbm_nb_command, ('demo', '--html', ''), {}, CommandRefused,
         r"--html: give a file name"),
    Case("cli-html-folder", rbm_nb_command, ('demo', '--html', '/tmp'), {}, CommandRefused,
         r"--html: /tmp is a folder; give a file name"),
    Case("cli-html-missing-folder", rbm_nb_command, ('demo', '--html', '/nonexistent-rbm/x.html'), {}, CommandRefused,
         r"--html: the folder '/nonexistent-rbm' does not exist"),
    Case("cli-port-70000", rbm_nb_command, ('demo', '--port', '70000'), {}, CommandRefused,
         r"--port: 70000 is not a port \(0 to 65535"),
    Case("cli-port-negative", rbm_nb_command, ('app', '--port', '-1'), {}, CommandRefused,
         r"--port: -1 is not a port"),
    Case("cli-port-text", rbm_nb_command, ('app', '--port', 'http'), {}, CommandRefused,
         r"--port: not a port number: 'http'"),
    Case("cli-max-frames-0", rbm_nb_command, ('demo', '--html', '/tmp/rbm-x.html', '--max-frames', '0'), {}, CommandRefused,
         r"--max-frames: must be at least 2, got 0"),
    Case("cli-max-frames-text", rbm_nb_command, ('demo', '--html', '/tmp/rbm-x.html', '--max-frames', 'all'), {}, CommandRefused,
         r"--max-frames: not a whole number"),
    Case("cli-source-synthetic-without-html", rbm_nb_command, ('demo', '--source', 'synthetic'), {}, CommandRefused,
         r"--source does not apply to the JupyterLab demo \(add --html"),
    Case("cli-max-frames-without-html", rbm_nb_command, ('demo', '--max-frames', '5'), {}, CommandRefused,
         r"--max-frames does not apply to the JupyterLab demo"),
    Case("cli-port-with-text", rbm_nb_command, ('demo', '--text', '--port', '9000'), {}, CommandRefused,
         r"--port does not apply to demo --text"),
    Case("cli-source-with-text", rbm_nb_command, ('demo', '--text', '--source=remote'), {}, CommandRefused,
         r"--source does not apply to demo --text"),
    Case("cli-port-with-html", rbm_nb_command, ('demo', '--html', '/tmp/rbm-x.html', '--port', '9000'), {}, CommandRefused,
         r"--port does not apply to demo --html"),
    Case("cli-notebook-dir-with-html", rbm_nb_command, ('demo', '--html', '/tmp/rbm-x.html', '--notebook-dir', '/tmp'), {}, CommandRefused,
         r"--notebook-dir does not apply to demo --html"),
    Case("cli-notebook-dir-missing", rbm_nb_command, ('demo', '--notebook-dir', '/nonexistent-rbm'), {}, CommandRefused,
         r"--notebook-dir: '/nonexistent-rbm' is not a folder"),
    Case("cli-html-and-text", rbm_nb_command, ('demo', '--html', '/tmp/rbm-x.html', '--text'), {}, CommandRefused,
         r"not allowed with argument"),
    Case("cli-unknown-option", rbm_nb_command, ('demo', '--bogus'), {}, CommandRefused,
         r"unrecognized arguments: --bogus"),
    # -- frame names with control characters (item 11) ---------------------------
    Case("rf-name-escape", RF, ("head\x1b[2J",), {}, ValueError,
         r"frame name 'head\\x1b\[2J' has the control character U\+001B at index 4"),
    Case("rf-name-bell", "register_frame", ("bell\x07",), {"parent": "world"},
         ValueError, r"control character U\+0007"),
    Case("rf-name-nul", RF, ("a\x00b", "world"), {}, ValueError,
         r"control character U\+0000 at index 1"),
    Case("rf-name-c1-csi", RF, ("x\x9b31m",), {}, ValueError, r"U\+009B"),
    Case("registry-set-escape-name", registry_set, ("x\x1b", rbm.ReferenceFrame("ok")),
         {}, ValueError, r"control character U\+001B"),
    Case("rosbag-frame-id-escape", bag_with_frame_id, ("cam\x1b]0;owned\x07",), {},
         ValueError, r"tf.bag: frame name .* control character U\+001B"),
    # -- a raising on_time callback stops nothing (item 12) ------------------------
    Case("player-on-time-callback-raises", player_with_callbacks, (), {}, None, ""),
    # -- plotted values arrive as the kernel has them (item 13) --------------------
    Case("plot-1e300-stays-finite", plot_sends_exactly, ([1e300, -1e300, 0.0, 1.0],),
         {}, None, ""),
    Case("plot-5e6-millimetre-steps", plot_sends_exactly,
         (5e6 + 0.001 * np.arange(5),), {}, None, ""),
    Case("plot-tiny-values", plot_sends_exactly, ([1e-300, 2e-300, 3e-300],), {},
         None, ""),
    # -- Scene and Player values (item 14) -----------------------------------------
    Case("scene-focus-distance-nan", scene_refuses, ("focus", "moving"),
         {"distance": np.nan}, ValueError,
         r"Scene.focus: distance must be positive and at most 1e\+09 m, got nan"),
    Case("scene-focus-distance-negative", scene_refuses, ("focus", "moving"),
         {"distance": -2.0}, ValueError, r"Scene.focus: distance must be positive"),
    Case("scene-focus-distance-text", scene_refuses, ("focus", "moving"),
         {"distance": "far"}, ValueError, r"distance must be a number of metres"),
    Case("scene-camera-position-is-target", scene_refuses,
         ("set_camera", [1.0, 2.0, 3.0], [1.0, 2.0, 3.0]), {}, ValueError,
         r"set_camera: position and target are the same point"),
    Case("scene-camera-far", scene_refuses,
         ("set_camera", [1e300, 0.0, 0.0], [0.0, 0.0, 0.0]), {}, ValueError,
         r"set_camera: position .* beyond 1e\+09 m"),
    Case("scene-set-time-inf", scene_refuses, ("set_time", np.inf), {}, ValueError,
         r"t|finite"),
    Case("scene-set-time-1e300-clamped", scene_time_clamped, (1e300,), {}, None, ""),
    Case("scene-set-time-before-start-clamped", scene_time_clamped, (-1e300,), {},
         None, ""),
    Case("player-infinite-span", player_of, ([-1e308, 1e308],), {}, ValueError,
         r"Player: the timestamps run from -1e\+308 to 1e\+308 s, a span too long"),
    Case("mesh-stl-not-stl", in_temp_folder, (mesh_file_in, "part.stl", b"hello"), {},
         ValueError, r"part.stl' is not a binary STL .* nor an ASCII STL"),
    Case("mesh-dae-not-collada", in_temp_folder,
         (mesh_file_in, "part.dae", b"<html></html>"), {}, ValueError,
         r"part.dae' is not a COLLADA"),
    Case("plot-max-points-nan", plot_with, (), {"max_points": np.nan}, ValueError,
         r"TimeSeries: max_points must be an integer >= 10, got nan"),
    Case("plot-panel-height-nan", plot_with, (), {"panel_height": np.nan}, ValueError,
         r"TimeSeries: panel_height must be a whole number of pixels .* got nan"),
    Case("plot-panel-height-huge", plot_with, (), {"panel_height": 10**9}, ValueError,
         r"panel_height must be a whole number of pixels in \[40, 4000\]"),
    Case("plot-gap-text", plot_with, (), {"gap": "wide"}, ValueError,
         r"TimeSeries: gap must be a positive number of seconds"),
    Case("scene-path-max-points-nan", scene_refuses, ("add_path", "moving"),
         {"max_points": np.nan}, ValueError,
         r"add_path: max_points must be a whole number, at least 2, got nan"),
    # -- numerics (item 10) ----------------------------------------------------------
    Case("points-partial-nan-row", "transform_points",
         (np.array([[np.nan, 0.0, 0.0]]), "world", "static"), {}, ValueError,
         r"arr\[0\] is not finite: \[nan  0\.  0\.\] \(a missing sample is a row of NaN"),
    Case("points-partial-nan-row-3d", "transform_points",
         (np.array([[[0.0, 0, 0], [1.0, np.nan, 1.0]]]), "world", "static"), {},
         ValueError, r"arr\[0, 1\] is not finite"),
    Case("vectors-partial-nan-moving", "transform_vectors",
         (np.vstack([np.zeros((3, 3)), [0.0, 0.0, np.nan]]), "world", "moving"),
         {"timestamps": np.arange(4.0)}, ValueError, r"arr\[3\] is not finite"),
    Case("quaternions-partial-nan", "transform_quaternions",
         (np.array([[1.0, np.nan, 0, 0]]), "world", "static"), {}, ValueError,
         r"arr\[0\] is not finite"),
    Case("rosbag-writer-norm-1.009-as-given", bag_keeps_quaternions_as_given,
         (1.009,), {}, None, ""),
    Case("lookup-norm-1.009-as-given", lookup_keeps_quaternions_as_given,
         (1.009,), {}, None, ""),
    Case("velocity-1e-300-s-steps", "estimate_linear_velocity",
         (np.column_stack([np.arange(5.0), np.zeros(5), np.zeros(5)]),),
         {"timestamps": np.arange(5) * 1e-300}, ValueError,
         r"timestamps: samples \d and \d are 1e-300 s apart; a velocity needs "
         r"sampling intervals of at least 1e-90 s"),
    Case("angular-velocity-1e-300-s-steps", "estimate_angular_velocity",
         (np.tile([1.0, 0.0, 0.0, 0.0], (5, 1)),),
         {"timestamps": np.arange(5) * 1e-300}, ValueError,
         r"samples \d and \d are 1e-300 s apart"),
    Case("twist-of-frame-1e-300-s-steps", velocity_of_frame_sampled_every,
         (1e-300,), {}, ValueError,
         r"timestamps of 'fine' wrt 'world': samples \d and \d are 1e-300 s apart"),
    Case("static-translation-1e308", "register_frame", ("far",),
         {"parent": "world", "translation": (1e308, 0.0, 0.0)}, ValueError,
         r"frame 'far': translation\[0\] holds 1e\+308, beyond ±1e\+150: coordinates "
         r"that large overflow when frames are composed"),
    Case("moving-translation-1e200", "register_frame", ("far",),
         {"parent": "world", "timestamps": [0.0, 1.0],
          "translation": [[0.0, 0.0, 0.0], [0.0, -1e200, 0.0]]}, ValueError,
         r"frame 'far': translation\[1\] holds -1e\+200, beyond ±1e\+150"),
    Case("points-1e308", "transform_points",
         (np.array([[0.0, 0, 0], [1e308, 0.0, 0.0]]), "world", "static"), {},
         ValueError, r"arr\[1\] holds 1e\+308, beyond ±1e\+150"),
    Case("points-cloud-through-moving-frame", moving_points_shape, (7,), {}, None, ""),
    # -- paths (item 9) ---------------------------------------------------------------
    Case("path-255-byte-html", in_temp_folder, (write_long_name, "html"), {}, None, ""),
    Case("path-255-byte-ros1-bag", in_temp_folder, (write_long_name, "bag"), {}, None,
         ""),
    Case("path-200-byte-ros2-bag", in_temp_folder, (write_long_name, "ros2", 200), {},
         None, ""),
    Case("path-255-byte-ros2-bag", in_temp_folder, (write_long_name, "ros2"), {},
         ValueError, r"the ROS2 bag folder name 'r+' is too long \(255 bytes\): the sqlite3 "
         r"file 'r+\.db3-journal' inside would be 267 bytes"),
    Case("path-240-byte-ros2-bag-sqlite-path", in_temp_folder,
         (write_long_name, "ros2", 240), {}, ValueError,
         r"the path of the ROS2 bag .* is too long for sqlite3 storage: .* at most 512; "
         r"use a shorter name or folder, or storage='mcap'"),
    Case("path-255-byte-netcdf-export", in_temp_folder, (write_long_name, "nc"), {},
         None, ""),
    Case("path-230-byte-html", in_temp_folder, (write_long_name, "html", 230), {},
         None, ""),
    Case("path-dangling-link-folders", in_temp_folder, (write_through_dangling_link,),
         {}, FileNotFoundError,
         r"the link points to .*runs/today/scene.html', whose folder does not exist"),
    Case("to-html-static-scene", in_temp_folder, (static_scene_export,), {}, None, ""),
    Case("env-data-dir-unknown-user", with_env,
         ({"RBM_NB_DATA_DIR": "~nouser-rbm/x"}, fetch_example), {}, ValueError,
         r"RBM_NB_DATA_DIR='~nouser-rbm/x': ~nouser-rbm names no user"),
    Case("env-cache-dir-unknown-user", with_env,
         ({"RBM_NB_CACHE_DIR": "~nouser-rbm/c"}, cache_folder), {}, ValueError,
         r"RBM_NB_CACHE_DIR='~nouser-rbm/c': ~nouser-rbm names no user"),
    Case("fetch-failed-leaves-no-folder", in_temp_folder,
         (failed_fetch_leaves_no_folder,), {}, rbm.data.fetch.ExampleDataUnavailable,
         r"could not be downloaded"),
    Case("env-cache-dir-is-a-file", in_temp_folder, (bag_cache_in_a_file,), {},
         OSError, r"cannot write the cache of this bag in RBM_NB_CACHE_DIR="),
    # -- OptiTrack exports (item 8) ----------------------------------------------------
    Case("optitrack-generated-export-loads", in_temp_folder, (motive_loads,), {}, None,
         ""),
    Case("optitrack-duplicate-body-names", in_temp_folder, (load_motive,),
         {"names": ("Head", "Head")}, rbm.io.FileFormatError,
         r"take.csv: two rigid bodies are named 'Head' \(ID ID1 from column 3, ID ID2 "
         r"from column 9\)"),
    Case("optitrack-time-out-of-range", in_temp_folder, (load_motive,),
         {"times": ["0", "0.1", "1e12"]}, rbm.io.FileFormatError,
         r"take.csv: line 10: time 1e\+12 s after the capture start .* beyond"),
    Case("optitrack-start-year-9999", in_temp_folder, (load_motive,),
         {"start": "9999-06-16 07.51.41.245 PM"}, rbm.io.FileFormatError,
         r"take.csv: line 1: 'Capture Start Time' '9999-06-16 07.51.41.245 PM' is "
         r"outside the years"),
    Case("optitrack-start-year-1600", in_temp_folder, (load_motive,),
         {"start": "1600-06-16 07.51.41.245 PM"}, rbm.io.FileFormatError,
         r"line 1: 'Capture Start Time' .* outside the years"),
    Case("optitrack-inf-euler-angle", in_temp_folder, (load_motive,),
         {"angle": "inf"}, rbm.io.FileFormatError,
         r"take.csv: line 8, field 3 is inf; values must be finite"),
    # -- rbm-nb demo names its data and how to get the real one (issue 29) ----------
    Case("demo-note-synthetic", in_temp_folder,
         (demo_data_note, "synthetic", {}, "the synthetic head/eye recording",
          "--source synthetic"), {}, None, ""),
    Case("demo-note-real-missing", in_temp_folder,
         (demo_data_note, "auto", {}, "head.nc, left_eye.nc, right_eye.nc",
          "downloads the real recording, or the synthetic one if that fails",
          "set RBM_NB_DATA_DIR to the folder"), {}, None, ""),
    Case("demo-note-real-not-matching", in_temp_folder,
         (demo_data_note, "auto", {"head.nc": "not the recording"},
          "head.nc in", "sha256 differs", "shows the synthetic recording",
          "point RBM_NB_DATA_DIR at a folder"), {}, None, ""),
    # -- se3, gaze, plots, Transform methods, coordinates, velocity options at the
    # -- door (issue 32, items 2: _door.shapes, _door.series) --------------------
    Case("se3-skew-shape", "se3.skew", ([1.0, 2.0],), {}, ValueError,
         r"v must have shape \(\.\.\., 3\), got \(2,\)"),
    Case("se3-skew-inf-row", "se3.skew", ([[0.0, 0, 0], [np.inf, 0, 0]],), {},
         ValueError, r"v\[1\] is not finite"),
    Case("se3-tr2adjoint-scaled", "se3.tr2adjoint", (np.diag([2.0, 1, 1, 1]),), {},
         ValueError, r"T is not a rotation: \|RᵀR - I\| reaches 3"),
    Case("se3-tr2adjoint-bottom-row", "se3.tr2adjoint",
         (np.stack([np.eye(4), np.eye(4) + np.eye(4, k=-3)]),), {}, ValueError,
         r"T\[1\] is not a homogeneous matrix: its last row is \[1\.0, 0\.0, 0\.0, 1\.0\]"),
    Case("se3-qlog-zero", "se3.qlog", (np.zeros(4),), {}, ValueError,
         "q is zero: it has no logarithm"),
    Case("gaze-angles-not-dataarray", "gaze.angles", (np.zeros((4, 3)), "world"), {},
         ValueError, "directions must be a DataArray from gaze.directions, got ndarray"),
    Case("gaze-angles-dims", gaze_directions_with, (("t", "cartesian_axis"),), {},
         ValueError, r"directions must have dims \('time', 'cartesian_axis'\)"),
    Case("gaze-angles-two-components", gaze_directions_with, (), {"width": 2},
         ValueError, "directions must have 3 components along 'cartesian_axis'"),
    Case("gaze-angles-no-frame", gaze_directions_with, (), {"attrs": {}}, ValueError,
         "directions has no 'representation_frame' attribute"),
    Case("plot-points-shape", "plot.points", (np.zeros((2, 2)),), {}, ValueError,
         r"points: arr must have shape \(3,\) or \(N, 3\), got \(2, 2\)"),
    Case("plot-quaternions-text", "plot.quaternions", (["a", "b", "c", "d"],), {},
         ValueError, "quaternions: arr must be numeric"),
    Case("plot-quaternions-nan", "plot.quaternions", ([1.0, np.nan, 0.0, 0.0],), {},
         ValueError, "quaternions must be finite and non-zero"),
    Case("plot-quaternions-zero", "plot.quaternions", (np.zeros((2, 4)),), {},
         ValueError, "quaternions must be finite and non-zero"),
    Case("plot-quaternions-base-shape", "plot.quaternions",
         (np.array([[1.0, 0, 0, 0]] * 3),), {"base": np.zeros((2, 3))}, ValueError,
         r"quaternions: base must have shape \(3,\) or \(3, 3\), got \(2, 3\)"),
    Case("Transform-apply-vectors-length", transform_method,
         ("apply_vectors", np.zeros((4, 4))), {}, ValueError,
         r"vectors must have length 3 along its last axis"),
    Case("cartesian-to-polar-length", "cartesian_to_polar", (np.ones((3, 3)),), {},
         ValueError, r"arr must have length 2 \(x, y\) along axis=-1, got shape \(3, 3\)"),
    Case("coordinates-dim-with-ndarray", "transform_coordinates", (np.ones(3),),
         {"into": "spherical", "outof": "cartesian", "dim": "x"}, ValueError,
         "dim can only be given when arr is a DataArray; use axis"),
    Case("shortest-arc-dim-with-ndarray", "shortest_arc_rotation",
         (np.ones(3), np.ones(3)), {"dim": "x"}, ValueError,
         "dim can only be given when v1 is a DataArray; use axis"),
    Case("qmul-second-quaternion-length", "qmul", (np.ones(4), np.ones(3)), {},
         ValueError, r"q\[1\] must have length 4 \(w, x, y, z\) along qaxis=-1"),
    Case("transform-linear-velocity-cutoff", "transform_linear_velocity",
         (np.zeros((4, 3)), "world", "moving"),
         {"timestamps": np.arange(4.0), "cutoff": 1.5}, ValueError,
         r"cutoff must be a fraction of the Nyquist frequency in \(0, 1\), got 1\.5"),
    Case("transform-angular-velocity-cutoff-text", "transform_angular_velocity",
         (np.zeros((4, 3)), "world", "moving"),
         {"timestamps": np.arange(4.0), "cutoff": "0.5"}, ValueError,
         "cutoff must be a fraction of the Nyquist frequency"),
    Case("lookup-linear-velocity-outlier-negative", "lookup_linear_velocity",
         ("moving", "world"), {"outlier_thresh": -1.0}, ValueError,
         "outlier_thresh must be a non-negative number, got -1.0"),
    Case("se3-rotvelxform-tol-inf", "se3.rotvelxform", (np.zeros(3),), {"tol": np.inf},
         ValueError, r"tol must be a finite number >= 0, got inf"),
    Case("icp-tolerance-inf", "iterative_closest_point", (PTS, PTS),
         {"tolerance": np.inf}, ValueError,
         r"tolerance must be a finite number >= 0, got inf"),
    Case("frame-lookup-angular-velocity-mode", frame_method,
         ("moving", "lookup_angular_velocity"), {"mode": "euler"}, ValueError,
         "mode must be 'quaternion' or 'rotation_vector', got 'euler'"),
    # -- rosbags ---------------------------------------------------------------
    Case("rosbag-missing-file", rosbag_reader,
         ("/nonexistent/nope.bag", "get_topics_and_types"), {}, FileNotFoundError,
         "nope.bag"),
]
# fmt: on
