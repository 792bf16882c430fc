"""Rigid body poses from OptiTrack Motive CSV exports.

A Motive export has seven header rows (metadata key/value pairs, a blank row,
then per column: type, name, ID, motion type and axis) followed by one row per
frame: frame number, time in seconds, then the columns. Only rigid body
rotation and position columns are read; markers are skipped.
"""

from __future__ import annotations

import csv
import io
import os
from pathlib import Path

import numpy as np

from ..core.quaternions import from_euler_angles
from ._files import FileFormatError
from ._schema import motion_dataset

IMPORT_FORMATS = ("numpy", "pandas", "xarray")
_N_HEADER_ROWS = 7
_LENGTH_SCALES = {"Meters": 1.0, "Centimeters": 0.01, "Millimeters": 0.001}
_START_TIME_FORMAT = "%Y-%m-%d %I.%M.%S.%f %p"


def load_optitrack(filepath: str | os.PathLike, import_format: str = "numpy") -> dict:
    """Load rigid body poses from an OptiTrack Motive CSV export.

    Parameters
    ----------
    filepath : str or path-like
        Path to the CSV file.
    import_format : {"numpy", "pandas", "xarray"}, default "numpy"
        "numpy" gives a ``(position, orientation, timestamps)`` tuple per body
        with shapes (n, 3), (n, 4) (w, x, y, z) and (n,) (datetime64[ns]);
        "pandas" a DataFrame indexed by time with ``position`` (x, y, z) and
        ``orientation`` (w, x, y, z) column groups; "xarray" a Dataset with
        ``position`` (time, cartesian_axis) and ``orientation`` (time,
        quaternion_axis).

    Returns
    -------
    dict
        One entry per rigid body, keyed by the body's name in the export.

    Notes
    -----
    Timestamps are the export's "Capture Start Time" plus each frame's time.
    Positions are converted to metres when the header states the length unit
    ("Length Units": Meters, Centimeters or Millimeters); without it they are
    kept as exported. Euler-angle exports (degrees, applied in the order of
    "Rotation Type", default XYZ) become quaternions; quaternion exports (x, y,
    z, w columns) are reordered to w, x, y, z. Frames in which a body was not
    tracked are NaN, as in the export.

    Raises
    ------
    FileNotFoundError
        If the file does not exist.
    rbm_nb.io.FileFormatError
        If the file is not a Motive CSV export, is truncated (fewer rows
        than the header's "Total Exported Frames") or has malformed,
        duplicated or reordered rows (frame numbers and times must
        increase); the message names the file and the problem.
    ValueError
        If ``import_format`` is not one of the three formats.
    """
    if import_format not in IMPORT_FORMATS:
        raise ValueError(
            f"import_format must be one of {IMPORT_FORMATS}, got {import_format!r}"
        )
    path = Path(filepath)
    lines = _read_lines(path)
    header = list(csv.reader(lines[:_N_HEADER_ROWS]))
    meta = _metadata(path, header)
    columns = _rigid_body_columns(path, header)
    data = _numbers(path, lines[_N_HEADER_ROWS:], len(header[-1]))
    _check_frames(path, meta, data)
    timestamps = _timestamps(path, meta, data[:, 1])
    scale = _length_scale(path, meta)
    bodies = {
        name: (
            data[:, cols["position"]] * scale,
            _orientation(path, meta, data, cols),
            timestamps,
        )
        for name, cols in columns.items()
    }
    units = "m" if "Length Units" in meta else None
    if import_format == "numpy":
        return bodies
    if import_format == "pandas":
        return {name: _to_dataframe(*arrays) for name, arrays in bodies.items()}
    return {name: _to_dataset(*arrays, units) for name, arrays in bodies.items()}


def _read_lines(path: Path) -> list[str]:
    raw = path.read_bytes()
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        raise FileFormatError(
            f"{path} is not an OptiTrack CSV export: it is not text ({err})"
        ) from None
    if text and not text.endswith(("\n", "\r")):
        raise FileFormatError(
            f"{path} ends in the middle of a row: the export is truncated"
        )
    lines = text.splitlines()
    while lines and not lines[-1].strip():
        lines.pop()
    if len(lines) < _N_HEADER_ROWS:
        raise FileFormatError(
            f"{path} is not an OptiTrack CSV export: it has {len(lines)} lines, "
            f"an export has at least {_N_HEADER_ROWS} header rows"
        )
    return lines


def _metadata(path: Path, header: list[list[str]]) -> dict:
    first = header[0]
    meta = {k: v for k, v in zip(first[0::2], first[1::2], strict=False) if k}
    if "Format Version" not in meta or "Capture Start Time" not in meta:
        raise FileFormatError(
            f"{path} is not an OptiTrack CSV export: its first row should hold "
            f"'Format Version', 'Capture Start Time', ... pairs, got {first[:4]}"
        )
    axes = header[-1]
    if axes[:2] != ["Frame", "Time (Seconds)"]:
        raise FileFormatError(
            f"{path} is not an OptiTrack CSV export: row {_N_HEADER_ROWS} should start "
            f"with 'Frame', 'Time (Seconds)', got {axes[:2]}"
        )
    widths = {len(row) for row in header[2:]}
    if len(widths) != 1:
        raise FileFormatError(
            f"{path}: the column header rows have different lengths {sorted(widths)}"
        )
    return meta


def _rigid_body_columns(path: Path, header: list[list[str]]) -> dict:
    """name -> {"position": [x, y, z] columns, "rotation": columns, "rotation_axes": labels}."""
    types, names, ids, motions, axes = header[2:7]
    bodies: dict[str, dict] = {}
    first_id: dict[str, tuple[str, int]] = {}
    for col, (kind, name, body_id, motion, axis) in enumerate(
        zip(types, names, ids, motions, axes, strict=True)
    ):
        if kind != "Rigid Body" or motion not in ("Position", "Rotation"):
            continue
        # two bodies of one name (Motive allows it) would overwrite each
        # other's columns: refuse, naming both
        seen_id, seen_col = first_id.setdefault(name, (body_id, col))
        if seen_id != body_id:
            raise FileFormatError(
                f"{path}: two rigid bodies are named {name!r} (ID {seen_id} from "
                f"column {seen_col + 1}, ID {body_id} from column {col + 1}); "
                "rename one in Motive and export again"
            )
        body = bodies.setdefault(name, {"position": {}, "rotation": {}})
        if axis.upper() in body[motion.lower()]:
            raise FileFormatError(
                f"{path}: rigid body {name!r} has two {motion} {axis} columns "
                f"({body[motion.lower()][axis.upper()] + 1} and {col + 1})"
            )
        body[motion.lower()][axis.upper()] = col
    out = {}
    for name, body in bodies.items():
        position, rotation = body["position"], body["rotation"]
        if set(position) != {"X", "Y", "Z"} or set(rotation) not in (
            {"X", "Y", "Z"},
            {"X", "Y", "Z", "W"},
        ):
            raise FileFormatError(
                f"{path}: rigid body {name!r} has position columns {sorted(position)} and "
                f"rotation columns {sorted(rotation)}; expected X, Y, Z and X, Y, Z (Euler) "
                "or X, Y, Z, W (quaternion)"
            )
        out[name] = {
            "position": [position[a] for a in "XYZ"],
            "rotation": [rotation[a] for a in ("WXYZ" if "W" in rotation else "XYZ")],
        }
    return out


def _numbers(path: Path, rows: list[str], width: int) -> np.ndarray:
    # every data row has as many fields as the header (the C parser below
    # would fill short rows with NaN without a word)
    for i, row in enumerate(rows):
        if row.count(",") != width - 1:
            raise FileFormatError(
                f"{path}: line {_N_HEADER_ROWS + i + 1} has {row.count(',') + 1} fields, "
                f"the header has {width}"
            )
    if not rows:
        return np.empty((0, width))
    import pandas as pd

    try:
        frame = pd.read_csv(
            io.StringIO("\n".join(rows)),
            header=None,
            dtype=np.float64,
            skip_blank_lines=False,
        )
    except ValueError as err:
        raise FileFormatError(
            f"{path}: the data rows are not all numbers ({err})"
        ) from None
    data = frame.to_numpy()
    if np.isnan(data[:, :2]).any():
        line = (
            _N_HEADER_ROWS
            + 1
            + int(np.flatnonzero(np.isnan(data[:, :2]).any(axis=1))[0])
        )
        raise FileFormatError(f"{path}: line {line} has no frame number or time")
    inf = np.isinf(data)
    if inf.any():
        at, field = (int(v) for v in np.argwhere(inf)[0])
        raise FileFormatError(
            f"{path}: line {_N_HEADER_ROWS + 1 + at}, field {field + 1} is "
            f"{data[at, field]}; values must be finite (an empty field is a "
            "missing sample)"
        )
    return data


def _check_frames(path: Path, meta: dict, data: np.ndarray) -> None:
    """As many rows as the header announces; frame numbers and times increasing."""
    announced = meta.get("Total Exported Frames")
    if announced is not None:
        try:
            expected = int(announced)
        except ValueError:
            raise FileFormatError(
                f"{path}: 'Total Exported Frames' is {announced!r}, not a number"
            ) from None
        if expected != len(data):
            what = "is truncated" if len(data) < expected else "has rows beyond them"
            raise FileFormatError(
                f"{path}: the header announces {expected} exported frames but the file "
                f"has {len(data)} data rows: it {what}"
            )
    for column, name in ((0, "frame number"), (1, "time")):
        back = np.flatnonzero(np.diff(data[:, column]) <= 0)
        if back.size:
            i = int(back[0]) + 1
            line = _N_HEADER_ROWS + 1 + i
            raise FileFormatError(
                f"{path}: line {line} has {name} {data[i, column]:g}, not after "
                f"{data[i - 1, column]:g} on line {line - 1} (duplicated or "
                f"reordered rows); {name}s must increase"
            )


def _timestamps(path: Path, meta: dict, seconds: np.ndarray) -> np.ndarray:
    import pandas as pd

    text = meta["Capture Start Time"]
    try:
        start = pd.to_datetime(text, format=_START_TIME_FORMAT)
        # pandas may hold it at a coarser unit; rbm_nb's timestamps are ns
        if not pd.Timestamp.min <= start <= pd.Timestamp.max:
            raise pd.errors.OutOfBoundsDatetime(text)
    except pd.errors.OutOfBoundsDatetime:
        raise FileFormatError(
            f"{path}: line 1: 'Capture Start Time' {text!r} is outside the years "
            f"{pd.Timestamp.min.year + 1}-{pd.Timestamp.max.year - 1} that nanosecond "
            "timestamps can hold"
        ) from None
    except ValueError:
        raise FileFormatError(
            f"{path}: line 1: 'Capture Start Time' {text!r} is not in Motive's "
            "format (e.g. '2020-06-16 07.51.41.245 PM')"
        ) from None
    # the largest time first: a time the ns clock cannot hold names its line
    latest = int(np.argmax(np.abs(seconds))) if seconds.size else 0
    try:
        return (start + pd.to_timedelta(seconds, unit="s")).to_numpy(
            dtype="datetime64[ns]"
        )
    except (
        pd.errors.OutOfBoundsDatetime,
        pd.errors.OutOfBoundsTimedelta,
        OverflowError,
    ):
        raise FileFormatError(
            f"{path}: line {_N_HEADER_ROWS + 1 + latest}: time {seconds[latest]:g} s "
            f"after the capture start {text!r} is beyond what nanosecond timestamps "
            f"can hold (up to {pd.Timestamp.max})"
        ) from None


def _length_scale(path: Path, meta: dict) -> float:
    units = meta.get("Length Units")
    if units is None:
        return 1.0
    if units not in _LENGTH_SCALES:
        raise FileFormatError(
            f"{path}: unknown 'Length Units' {units!r}, expected one of {sorted(_LENGTH_SCALES)}"
        )
    return _LENGTH_SCALES[units]


def _orientation(path: Path, meta: dict, data: np.ndarray, cols: dict) -> np.ndarray:
    rotation = data[:, cols["rotation"]]
    if len(cols["rotation"]) == 4:
        return rotation  # already reordered to w, x, y, z
    order = meta.get("Rotation Type", "XYZ")
    if sorted(order) != ["X", "Y", "Z"]:
        raise FileFormatError(
            f"{path}: 'Rotation Type' {order!r} is not an order of the axes X, Y, Z"
        )

    # the columns hold the angles about X, Y and Z (degrees); Rotation Type
    # says in which order they are applied
    rpy_order = order.replace("X", "r").replace("Y", "p").replace("Z", "y")
    return from_euler_angles(np.deg2rad(rotation), order=rpy_order)


def _to_dataframe(position, orientation, timestamps):
    import pandas as pd

    index = pd.DatetimeIndex(timestamps, name="time")
    columns = pd.MultiIndex.from_tuples(
        [("position", a) for a in "xyz"] + [("orientation", a) for a in "wxyz"],
        names=[None, "axis"],
    )
    return pd.DataFrame(
        np.hstack([position, orientation]), index=index, columns=columns
    )


def _to_dataset(position, orientation, timestamps, units):
    # without "Length Units" in the header the unit of the positions is unknown
    attrs = None if units else {"position": {"long_name": "Position"}}
    return motion_dataset(
        timestamps, {"position": position, "orientation": orientation}, None, attrs
    )
