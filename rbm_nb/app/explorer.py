"""The head/eye explorer: one definition shared by notebook 06 and ``rbm-nb demo``.

The recording is the example head/eye dataset (real when it can be had, else
the synthetic one). Its frame tree follows guide 1.6 of rigid-body-motion::

    world
    └── t265/world        VR axes (x right, y up, z back) of the head tracker
        └── t265/tracker  the tracked head pose
            ├── head      the same pose in robotics axes (x forward, y left, z up)
            └── pupil/scene_cam     eye tracker's scene camera (calibrated offset)
                ├── pupil/left_eye  eye orientation in camera axes (z = line of sight)
                └── pupil/right_eye
"""

from __future__ import annotations

import html
import warnings
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from .._engine import chain as _chain
from .._infra.frozen import kernel_alias
from .._infra.progress import make_bar
from .._kernels import masked_rows as _masked_rows
from ..core import frames
from ..core import frames as registry
from ..core.lookups import lookup_transform
from ..data.load import last_choice, load_example
from ..io._files import load_netcdf
from . import explorer_prepare

# the frames and the series live in their own modules; their names are the
# explorer's (rbm_nb.explorer.<name>), as before the split
from .explorer_frames import EXAMPLE_FRAMES as EXAMPLE_FRAMES
from .explorer_frames import EYES as EYES
from .explorer_frames import GAZE_COLORS as GAZE_COLORS
from .explorer_frames import MAX_EYE_GAP as MAX_EYE_GAP
from .explorer_frames import MIN_CONFIDENCE as MIN_CONFIDENCE
from .explorer_frames import PLOT_MAX_POINTS as PLOT_MAX_POINTS
from .explorer_frames import R_PUPIL_ROS as R_PUPIL_ROS
from .explorer_frames import R_T265_ROS as R_T265_ROS
from .explorer_frames import SCENE_CAM_ROTATION as SCENE_CAM_ROTATION
from .explorer_frames import SCENE_CAM_ROTATION_XYZW as SCENE_CAM_ROTATION_XYZW
from .explorer_frames import SCENE_CAM_TRANSLATION as SCENE_CAM_TRANSLATION
from .explorer_frames import HeadEyeFrames as HeadEyeFrames
from .explorer_frames import _unconfident as _unconfident
from .explorer_frames import register_head_eye_frames as register_head_eye_frames
from .explorer_series import _outer_yaw as _outer_yaw
from .explorer_series import _seconds as _seconds
from .explorer_series import _yaw_by_angles as _yaw_by_angles
from .explorer_series import explorer_series as explorer_series
from .explorer_series import gaze_angles as gaze_angles
from .explorer_series import gaze_yaw as gaze_yaw
from .explorer_series import guided_instants as guided_instants
from .explorer_series import head_speed as head_speed
from .explorer_series import head_yaw_rate as head_yaw_rate
from .explorer_series import vor_gain as vor_gain


def load_head_eye(source: str = "auto"):
    """Load the head, left-eye and right-eye recordings.

    Parameters
    ----------
    source : {"auto", "remote", "synthetic"}
        As for :func:`rbm_nb.data.load_example`. With "auto", what was
        loaded and why (the real files, your own files in
        ``RBM_NB_DATA_DIR``, or the synthetic recording because the real one
        is unavailable, with the reason and the fix) is said once, in
        ``note``, instead of three warnings. The three parts are always of
        one kind: if one part would be synthetic, all are.

    Returns
    -------
    head, left_eye, right_eye : xarray.Dataset
    note : str
        Which data this is and why, in a sentence or two.
    """
    names = ("head", *EYES)
    with warnings.catch_warnings():
        # said once, in the note
        warnings.simplefilter("ignore", UserWarning)
        parts = [load_example(name, source=source) for name in names]
        choices = [last_choice(name) for name in names]
        kinds = {c.kind for c in choices if c is not None}
        if len(kinds) > 1 and "synthetic" in kinds:
            # a real head with synthetic eyes would be nonsense
            parts = [load_example(name, source="synthetic") for name in names]
            choices = [
                c if c is not None and c.kind == "synthetic" else None for c in choices
            ]
    return (*parts, _data_note(choices))


def _data_note(choices) -> str:
    kinds = {c.kind for c in choices if c is not None}
    if kinds == {"real"}:
        folder = choices[0].path.parent
        return f"real head/eye recording (the rbm-data example files in {folder})"
    if kinds == {"own"} or kinds == {"own", "real"}:
        files = ", ".join(str(c.path) for c in choices)
        return f"your own head/eye recording ({files})"
    reasons = [c.reason for c in choices if c is not None and c.kind == "synthetic"]
    reason = reasons[0] if reasons else "one part of the real recording is unavailable"
    if reason == "the synthetic recording was asked for":
        return "synthetic head/eye recording (asked for)"
    return f"synthetic head/eye recording. {reason}"


def is_synthetic(ds) -> bool:
    """Whether a dataset comes from rbm_nb's synthetic generator."""
    return "synthetic" in str(ds.attrs.get("source", ""))


# the head model's parts, in the head's axes (x forward, y left, z up), from
# the eyes' centre: a head of adult size (half-axes 10 x 7.8 x 11.5 cm) whose
# front is just ahead of the eyeballs, and a nose below and between them
HEAD_RADII = (0.1, 0.078, 0.115)
HEAD_FROM_EYES = (-0.09, 0.0, 0.03)
NOSE_SIZE = (0.03, 0.02, 0.04)
NOSE_FROM_EYES = (0.012, 0.0, -0.035)
EYEBALL_RADIUS = 0.012
HEAD_COLOR = "#d9b38c"


def eye_centres(
    *, head: str | None = None, frames: HeadEyeFrames = EXAMPLE_FRAMES
) -> dict:
    """Median centre of each eye in the head's axes (m), over its valid samples."""
    out = {}
    buffer: list = []  # one (3, n) array for both eyes (fresh memory is slow)
    for eye in EYES:
        kept = _kept_translations(frames.eye(eye), head or frames.head, buffer)
        if kept is None:  # a chain that moves above the eye: the whole lookup
            translation, _ = lookup_transform(frames.eye(eye), head or frames.head)
            out[eye] = np.nanmedian(np.atleast_2d(translation), axis=0)
        else:
            # nanmedian's value: the median of the non-NaN values; the rows
            # are the buffer's (scratch): partitioned in place, not copied
            out[eye] = np.array(
                [
                    np.median(row, overwrite_input=True) if row.size else np.nan
                    for row in kept
                ]
            )
    return out


def _kept_translations(eye: str, into: str, buffer=None) -> np.ndarray | None:
    """The translations (3, m) of the eye's kept samples in ``into``, or None.

    A lookup composes whole transforms (every row's rotation too, and its
    copies: ~0.5 s per eye at 3 h) where the centres need only the
    translations of the samples that are not missing. When every frame
    between the eye's parent and ``into`` is static, one kernel pass carries
    the kept rows through those steps with the lookup's arithmetic (the same
    values); else None. ``buffer`` (a list): the (3, n) array to write, kept
    there for the next call.
    """
    steps = _chain.chain(registry.registry[eye], registry.registry[into])
    first, inverse = steps[0] if steps else (None, True)
    if first is None or inverse or first.track is None:
        return None
    rest = steps[1:]
    if any(frame.track is not None for frame, _ in rest):
        return None
    samples = first.samples
    n = len(samples.stored_t)
    mask = samples.missing_rows
    if mask is None:
        mask = np.zeros(n, dtype=bool)
    if buffer and buffer[0].shape[1] >= n:
        out = buffer[0]
    else:
        out = np.empty((3, n))
        if buffer is not None:
            buffer[:] = [out]
    m = _masked_rows.kept_translations(
        kernel_alias(samples.stored_t),
        kernel_alias(mask),
        np.array([f.t.reshape(3) for f, _ in rest]).reshape(-1, 3),
        np.array([f.rotation.reshape(4) for f, _ in rest]).reshape(-1, 4),
        np.array([inv for _, inv in rest], dtype=bool),
        out,
    )
    return out[:, :m]


def explorer_scene(
    *,
    world: str | None = None,
    name: str | None = None,
    gaze_length: float = 2.0,
    head_model: bool = True,
    frames: HeadEyeFrames = EXAMPLE_FRAMES,
):
    """A Scene with the world axes, a head model and path, and both gaze rays.

    The frames must be registered first (:func:`register_head_eye_frames`).
    The head model (head, nose, one eyeball per eye at its median centre) is
    drawn at real size at the tracked head pose, with the head's triad and
    each eye's gaze ray, ``gaze_length`` metres long and coloured per eye
    (:data:`GAZE_COLORS`), hidden where the eye has no sample. Far from the
    camera the whole model (rays included) is magnified about the head until
    it spans about 70 pixels, and the world's triad about 40, so the view of
    the whole walk still shows where the head is and where it looks; close
    up, everything is at its real size. Click the model or its label to
    select the head.
    """
    # lazy (optional dependency): notebook extras; write_explorer_html needs none
    from ..scene import Scene

    world = world or frames.world
    head = frames.head
    scene = Scene(world, name=name)
    scene.add_frame(world, scale=1.0)
    # everything with base="head" hangs below one node that moves with the
    # head: the browser magnifies that node as one model
    if head_model:
        centres = eye_centres(frames=frames)
        middle = (centres["left_eye"] + centres["right_eye"]) / 2
        scene.add_mesh(
            head,
            "ellipsoid",
            base=head,
            size=HEAD_RADII,
            offset=middle + np.array(HEAD_FROM_EYES),
            color=HEAD_COLOR,
            opacity=0.9,
            label="head model",
        )
        scene.add_mesh(
            head,
            "box",
            base=head,
            size=NOSE_SIZE,
            offset=middle + np.array(NOSE_FROM_EYES),
            color=HEAD_COLOR,
            label="nose",
        )
        for eye in EYES:
            scene.add_mesh(
                head,
                "sphere",
                base=head,
                size=EYEBALL_RADIUS,
                offset=centres[eye],
                color=GAZE_COLORS[eye],
                label=f"{eye.replace('_', ' ')}ball",
            )
    scene.add_frame(head, base=head, scale=0.12, label="head")
    scene.add_path(head, color="#ffffff", max_points=2000)
    for eye in EYES:
        scene.add_vectors(
            frames.eye(eye),
            (0.0, 0.0, 1.0),
            base=head,
            length=gaze_length,
            color=GAZE_COLORS[eye],
            label=f"{eye.replace('_', ' ')} gaze",
        )
    return scene


def explorer_plot(series: dict, player, *, max_points: int | None = PLOT_MAX_POINTS):
    """The time-series plot of the dashboard, following ``player``.

    None when :class:`~rbm_nb.widgets.TimeSeries` is not a widget that can
    follow a player in the browser (then the export has no plot).
    A panel longer than ``max_points`` goes as its min/max overview at the
    plot's pixel width (every column's extremes and first gap, so saccade
    peaks survive, in the same bytes at any length) and zooming in fetches
    every sample in view; the export keeps the overview (1000 columns).
    """
    # lazy (optional dependency): anywidget, only for the dashboard
    from ..widgets import TimeSeries

    if not hasattr(TimeSeries, "_esm"):
        return None
    return TimeSeries(series, player=player, max_points=max_points, panel_height=140)


#: eye rows per step of first_full_instant's search
FIRST_INSTANT_BLOCK = 4096


def first_full_instant(head, left_eye, right_eye, *, min_confidence=MIN_CONFIDENCE):
    """The first eye timestamp, from the head's first sample on, where both eyes
    have a trusted sample: where the explorer starts, with everything drawn."""
    times = left_eye.time.values
    start = head.time.values[0]
    eyes = [
        (eye.orientation.values, eye.confidence.values if "confidence" in eye else None)
        for eye in (left_eye, right_eye)
    ]
    # block by block from the start: the instant is usually in the first
    # second, and a pass over hours of both eyes' rows costs ~0.1 s
    for lo in range(0, len(times), FIRST_INSTANT_BLOCK):
        rows = slice(lo, lo + FIRST_INSTANT_BLOCK)
        ok = times[rows] >= start
        for orientation, confidence in eyes:
            ok &= np.isfinite(orientation[rows]).all(axis=1)
            if confidence is not None:
                ok &= confidence[rows] >= min_confidence
        if ok.any():
            # (at its own timestamps an eye frame gives its sample whatever
            # its neighbours: docs/missing_data.md)
            return times[lo + int(np.argmax(ok))]
    return times[0]


def seek_to(player, instant) -> None:
    """Seek ``player`` to its first sample at or after ``instant``.

    The Player snaps to its own samples; one just before ``instant`` would
    show the eyes' previous row, which may have no sample (a row of the
    other eye): use this to show an instant found in the eye data."""
    player.seek_time(instant)
    target = _seconds(np.asarray([instant]))[0]
    last = len(player.seconds) - 1
    while (
        _seconds(np.asarray([player.timestamp]))[0] < target - 1e-6
        and player.index < last
    ):
        player.seek(player.index + 1)


EYE_MISSING_REASON = (
    "the eye tracker has no trusted sample of this eye here: a row of the other "
    "eye only, a blink or lost pupil, or confidence below {min_confidence}"
)


def _as_dataset(value, name: str):
    if hasattr(value, "data_vars"):
        return value

    try:
        path = Path(value)
    except TypeError:
        raise ValueError(
            f"dashboard: {name} must be an xarray.Dataset or the path of a netCDF "
            f"file, got {type(value).__name__}"
        ) from None
    return load_netcdf(path)


def _registered(frames) -> HeadEyeFrames:
    """``frames`` as HeadEyeFrames: every name a registered frame, the head
    moving in the world and the eyes relative to the head."""
    if isinstance(frames, dict):
        frames = HeadEyeFrames(**frames)
    if not isinstance(frames, HeadEyeFrames):
        raise ValueError(
            "dashboard: frames must be a HeadEyeFrames (world, head, left_eye, "
            f"right_eye names), got {type(frames).__name__}"
        )
    for role, name in frames._asdict().items():
        if name not in registry.registry:
            raise ValueError(
                f"dashboard: frames.{role} is {name!r}, which is not a registered "
                "frame (register it first)"
            )
    moving = [("head", frames.world)] + [(eye, frames.head) for eye in EYES]
    for role, reference in moving:
        if _motion(getattr(frames, role), reference) is None:
            raise ValueError(
                f"dashboard: frames.{role} {getattr(frames, role)!r} does not move "
                f"relative to {reference!r}; the explorer draws and plots a head "
                "moving in the world and eyes moving in the head"
            )
    return frames


def _motion(frame: str, reference: str):
    """(timestamps, rotations) of ``frame`` wrt ``reference``, or None if static."""
    _, rotation, times = lookup_transform(frame, reference, return_timestamps=True)
    return None if times is None else (np.asarray(times), np.asarray(rotation))


def _first_instant_of_frames(frames: HeadEyeFrames):
    """The first time of the left eye, from the head's first sample on, where
    both eyes have a sample (the right eye's at the same time or, on another
    clock, its last one before)."""
    head_times = _motion(frames.head, frames.world)[0]
    times, left = _motion(frames.left_eye, frames.head)
    other, right = _motion(frames.right_eye, frames.head)
    ok = ~np.isnan(left).any(axis=1) & (times >= head_times[0])
    present = ~np.isnan(right).any(axis=1)
    at = np.clip(np.searchsorted(other, times, side="right") - 1, 0, len(other) - 1)
    ok &= present[at] & (other[at] <= times)
    return times[int(np.argmax(ok))] if ok.any() else times[0]


def dashboard(
    head=None,
    left_eye=None,
    right_eye=None,
    *,
    source: str = "auto",
    frames: HeadEyeFrames | None = None,
    note: str | None = None,
    min_confidence: float | None = MIN_CONFIDENCE,
    max_angle: float | None = None,
    gaze_length: float = 2.0,
    height: int = 440,
):
    """The head/eye explorer for any recording: tree, 3D view, Player, plots.

    Give your own recording as three datasets (or netCDF files) in the
    example's schema: ``head`` with ``position`` and ``orientation`` of the
    head tracker (T265 axes) along ``time``, and each eye with
    ``orientation`` (and ``position``, ``confidence``) in the scene camera,
    as Pupil Core reports them. Without them the example recording is
    loaded (:func:`load_head_eye` with ``source``). The frames are
    registered (:func:`register_head_eye_frames`, replacing frames of the
    same names) and the Player starts at the first instant where both eyes
    have a sample.

    Or explore frames you registered yourself: ``frames`` names the world,
    the head (robotics axes: x forward, y left, z up) and the two eye
    frames (z along the line of sight), e.g.
    ``dashboard(frames=HeadEyeFrames("map", "base_head", "eye_l", "eye_r"))``;
    nothing is registered then, and every sample of the eye frames counts
    as trusted.

    Parameters
    ----------
    head, left_eye, right_eye : xarray.Dataset or path, optional
    source : {"auto", "remote", "synthetic"}
        Which example data, when no datasets are given.
    frames : HeadEyeFrames, optional
        Registered frames to explore instead of a recording's datasets.
    note : str, optional
        What the data is, shown above the dashboard (default: the file names
        or :func:`load_head_eye`'s note).
    min_confidence, max_angle : float, optional
        Samples below ``min_confidence`` are missing; gaze further than
        ``max_angle`` degrees from straight ahead is impossible and missing
        (default :data:`rbm_nb.gaze.OCULOMOTOR_RANGE`).
    gaze_length : float, default 2.0
        Length of the gaze rays in metres.
    height : int, default 440
        Height of the 3D view in pixels.

    Returns
    -------
    ipywidgets.VBox
        The dashboard; its ``scene``, ``player``, ``tree``, ``plot``,
        ``series`` and ``note`` attributes are the parts.
    """
    # the code the build needs, loading since the import (usually done by now)
    explorer_prepare.wait()
    import ipywidgets as widgets

    # lazy (optional dependency): ipywidgets, only for the dashboard
    from ..widgets.frame_tree import FrameTree

    given = [head, left_eye, right_eye]
    if frames is not None:
        if any(part is not None for part in given):
            raise ValueError(
                "dashboard: give the recording's datasets or frames=, not both"
            )
        frames = _registered(frames)
        note = note or (
            f"registered frames: head {frames.head!r} and eyes {frames.left_eye!r}, "
            f"{frames.right_eye!r} in {frames.world!r}"
        )
        recording: tuple = (None, None, None)
        start = _first_instant_of_frames(frames)
        reason = "the frame has no sample here (a missing row)"
    else:
        if all(part is None for part in given):
            head, left_eye, right_eye, loaded = load_head_eye(source)
            note = note or loaded
        elif any(part is None for part in given):
            raise ValueError(
                "dashboard: give all of head, left_eye and right_eye, or none"
            )
        else:
            if note is None:
                note = "your recording" + "".join(
                    f", {p}" for p in given if not hasattr(p, "data_vars")
                )
            head, left_eye, right_eye = (
                _as_dataset(part, name)
                for part, name in zip(given, ("head", *EYES), strict=True)
            )
        frames = EXAMPLE_FRAMES
        register_head_eye_frames(
            head, left_eye, right_eye, min_confidence=min_confidence
        )
        recording = (head, left_eye, right_eye)
        start = first_full_instant(head, left_eye, right_eye)
        reason = EYE_MISSING_REASON.format(min_confidence=min_confidence)
    # the plots' series and the 3D scene read the same registered frames and
    # write nothing shared (the engine's caches are thread-safe, its kernels
    # release the GIL): built side by side, on two cores they take the time
    # of the longer one (3 h of the example: ~0.5 and ~0.9 s)
    with ThreadPoolExecutor(1, thread_name_prefix="rbm-explorer-series") as pool:
        pending = pool.submit(
            explorer_series, *recording, max_angle=max_angle, frames=frames
        )
        scene = explorer_scene(gaze_length=gaze_length, frames=frames)
        series = pending.result()
    player = scene.player(speed=1.0)
    seek_to(player, start)
    tree = FrameTree(
        frames.world,
        scene=scene,
        player=player,
        missing_reasons={frames.eye(eye): reason for eye in EYES},
    )
    plot = explorer_plot(series, player)
    scene.widget.height = height
    # min_width 0: flex items may shrink below their content, so nothing
    # spills sideways in a 1280 px window
    scene.widget.layout.flex = "1 1 60%"
    scene.widget.layout.min_width = "0"
    tree.layout.flex = "0 0 38%"
    tree.layout.min_width = "0"
    header = widgets.HTML(f"<i>data: {html.escape(note)}</i>")
    parts = [header, widgets.HBox([tree, scene.widget]), player]
    out = widgets.VBox(
        parts + ([plot] if plot is not None else []),
        layout=widgets.Layout(width="100%", overflow="hidden"),
    )
    out.add_class("rbm-explorer")
    out.scene, out.player, out.tree, out.plot = scene, player, tree, plot
    out.series, out.note = series, note
    return out


def export_html(board, path, *, max_frames: int | None = PLOT_MAX_POINTS) -> Path:
    """Write a :func:`dashboard` (3D view, plots, Player) as one offline HTML page.

    The page names the data in its title and plays in any browser with no
    Python and no network. Moving objects keep at most ``max_frames``
    samples each; the plots keep the overview the dashboard's plot was
    sent (each panel's min/max at ``TimeSeries.overview_width`` pixel
    columns, whatever the recording's length; the plot's header says so),
    so the notebook's export and ``rbm-nb demo --html`` write the same
    content, under 5 MB for the example recording.
    """
    return board.scene.to_html(
        Path(path),
        series=[] if board.plot is None else [board.plot],
        player=board.player,
        max_frames=max_frames,
        title=f"rbm_nb head/eye explorer: {board.note}",
    )


def close_dashboard(board) -> None:
    """Close the widgets of a :func:`dashboard` (the frames stay registered)."""
    for widget in (board.plot, board.tree, board.player):
        if widget is not None:
            widget.close()
    board.scene.close()
    board.close()


def write_explorer_html(
    path,
    *,
    source: str = "auto",
    max_frames: int | None = PLOT_MAX_POINTS,
    progress: bool = True,
) -> Path:
    """Build the explorer's dashboard from the example data and write it as HTML.

    The same page as :func:`export_html` of :func:`dashboard` in notebook 06.
    The registry is left as the caller had it.

    Returns
    -------
    pathlib.Path
        The file written.
    """
    steps = ["building the dashboard", "writing the HTML"]
    bar = make_bar(len(steps), "rbm-nb demo --html", progress=progress)
    previous = dict(frames.registry)
    board = None
    try:
        bar.set_postfix_str(steps[0])
        board = dashboard(source=source)
        bar.update()
        bar.set_postfix_str(steps[1])
        out = export_html(board, path, max_frames=max_frames)
        bar.update()
    finally:
        bar.close()
        if board is not None:
            close_dashboard(board)
        # leave the registry as the caller had it
        frames.clear_registry()
        for frame in previous.values():
            frame.register(update=True)
    return out


# the dashboard's modules and kernels load while the notebook loads its data
explorer_prepare.start()
