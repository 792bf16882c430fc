"""load_optitrack on the real Motive export, against rigid-body-motion as the oracle."""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest

import rbm_nb as rbm
from rbm_nb.io import FileFormatError, load_optitrack

BODIES = ["RigidBody 01", "RigidBody 02"]


@pytest.fixture(scope="module")
def csv_path(shared_data):
    return shared_data / "optitrack.csv"


@pytest.fixture
def reference(monkeypatch):
    """rigid-body-motion's loader, runnable on pandas 3.

    It calls ``DataFrame.groupby(level=0, axis=1)``, which pandas 3 removed;
    this shim gives it the same column groups. Importing it registers its own
    ``DataArray.rbm`` accessor, so ours is put back.
    """
    import xarray as xr

    from rbm_nb.core.accessors import DataArrayAccessor

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        import rigid_body_motion

        xr.register_dataarray_accessor("rbm")(DataArrayAccessor)

    groupby = pd.DataFrame.groupby

    def groupby_columns(self, *args, axis=0, **kwargs):
        if axis != 1:
            return groupby(self, *args, **kwargs)
        keys = self.columns.get_level_values(kwargs["level"])
        return [(key, self.loc[:, keys == key]) for key in dict.fromkeys(keys)]

    monkeypatch.setattr(pd.DataFrame, "groupby", groupby_columns)
    return rigid_body_motion.io.load_optitrack


def test_real_export(csv_path):
    data = rbm.io.load_optitrack(csv_path)
    assert sorted(data) == BODIES
    for position, orientation, timestamps in data.values():
        assert (
            position.shape == (227, 3)
            and orientation.shape == (227, 4)
            and timestamps.shape == (227,)
        )
        assert timestamps.dtype == np.dtype("datetime64[ns]")
        assert timestamps[0] == np.datetime64(
            "2020-06-16T19:51:41.245"
        )  # 07.51.41.245 PM
        np.testing.assert_allclose(
            np.diff(timestamps) / np.timedelta64(1, "s"), 1 / 60, atol=2e-6
        )
        np.testing.assert_allclose(np.linalg.norm(orientation, axis=1), 1.0)
    np.testing.assert_array_equal(
        data["RigidBody 01"][0][0], [-10.650912, 155.687256, -27.749178]
    )


@pytest.mark.parametrize("fmt", ["numpy", "xarray", "pandas"])
def test_same_as_reference(csv_path, reference, fmt):
    ours = load_optitrack(csv_path, import_format=fmt)
    theirs = reference(csv_path, import_format=fmt)
    assert sorted(ours) == sorted(theirs)
    for name in ours:
        if fmt == "numpy":
            for a, b in zip(ours[name], theirs[name], strict=True):
                np.testing.assert_array_equal(
                    a, b
                ) if a.dtype.kind == "M" else np.testing.assert_allclose(
                    a, b, rtol=1e-12, atol=1e-15
                )
        elif fmt == "xarray":
            for var in ("position", "orientation"):
                np.testing.assert_allclose(
                    ours[name][var].values,
                    theirs[name][var].values,
                    rtol=1e-12,
                    atol=1e-15,
                )
                assert ours[name][var].dims == theirs[name][var].dims
            np.testing.assert_array_equal(
                ours[name].time.values, theirs[name].time.values
            )
            assert list(ours[name].cartesian_axis.values) == list(
                theirs[name].cartesian_axis.values
            )
            assert list(ours[name].quaternion_axis.values) == list(
                theirs[name].quaternion_axis.values
            )
        else:
            np.testing.assert_allclose(
                ours[name]["position"].values,
                theirs[name]["position"].values,
                rtol=1e-12,
            )
            np.testing.assert_allclose(
                ours[name]["orientation"].values,
                theirs[name]["orientation"].values,
                rtol=1e-12,
                atol=1e-15,
            )
            assert list(ours[name]["orientation"].columns) == list(
                theirs[name]["orientation"].columns
            )
            np.testing.assert_array_equal(
                ours[name].index.values, theirs[name].index.values
            )


def _with_header(csv_path, tmp_path, extra: str, name="edited.csv"):
    """The real export with extra metadata pairs at the end of the first row."""
    lines = csv_path.read_text().splitlines(keepends=True)
    fields = lines[0].rstrip("\r\n").split(",")
    pairs = extra.split(",")
    used = (
        len(fields) - fields[::-1].index(next(f for f in reversed(fields) if f))
        if any(fields)
        else 0
    )
    fields[used : used + len(pairs)] = pairs
    lines[0] = ",".join(fields) + "\n"
    path = tmp_path / name
    path.write_text("".join(lines))
    return path


@pytest.mark.parametrize(
    "units, scale", [("Millimeters", 1e-3), ("Centimeters", 1e-2), ("Meters", 1.0)]
)
def test_length_units_become_metres(csv_path, tmp_path, units, scale):
    edited = _with_header(csv_path, tmp_path, f"Length Units,{units}")
    raw = load_optitrack(csv_path)["RigidBody 01"][0]
    ds = load_optitrack(edited, "xarray")["RigidBody 01"]
    np.testing.assert_allclose(ds.position.values, raw * scale)
    assert ds.position.attrs["units"] == "m"
    assert (
        "units" not in load_optitrack(csv_path, "xarray")["RigidBody 01"].position.attrs
    )


@pytest.mark.parametrize("order", ["XYZ", "ZYX", "YXZ", "XZY"])
def test_rotation_orders_as_reference(csv_path, tmp_path, reference, order):
    edited = _with_header(csv_path, tmp_path, f"Rotation Type,{order}")
    ours = load_optitrack(edited)
    theirs = reference(edited)
    for name in BODIES:
        np.testing.assert_allclose(
            ours[name][1], theirs[name][1], rtol=1e-12, atol=1e-15
        )


def _write_export(path, meta: list, frames, seconds, columns: list) -> None:
    """A Motive-style CSV; ``columns`` are (type, name, motion, axis, values)."""
    header = [["", ""] for _ in range(7)]
    header[6] = ["Frame", "Time (Seconds)"]
    for kind, name, motion, axis, _ in columns:
        for row, value in zip(
            header[2:], (kind, name, "id", motion, axis), strict=True
        ):
            row.append(value)
    width = len(header[6])
    header[0] = meta + [""] * (width - len(meta))
    header[1] = [""] * width
    body = np.column_stack([frames, seconds] + [c[4] for c in columns])
    rows = [",".join(row) for row in header]
    rows += [",".join(repr(float(v)) for v in line) for line in body]
    path.write_text("\n".join(rows) + "\n")


def test_quaternion_exports_are_reordered(csv_path, tmp_path):
    """A quaternion export (X, Y, Z, W columns) loads to the same rotations."""
    base = load_optitrack(csv_path)
    seconds = (base[BODIES[0]][2] - base[BODIES[0]][2][0]) / np.timedelta64(1, "s")
    columns = []
    for name in BODIES:
        position, q, _ = base[name]
        for axis, k in zip("XYZW", (1, 2, 3, 0), strict=True):
            columns.append(("Rigid Body", name, "Rotation", axis, q[:, k]))
        for k, axis in enumerate("XYZ"):
            columns.append(("Rigid Body", name, "Position", axis, position[:, k]))
    meta = [
        "Format Version",
        "1.23",
        "Capture Start Time",
        "2020-06-16 07.51.41.245 PM",
    ]
    meta += ["Rotation Type", "Quaternion"]
    path = tmp_path / "quaternions.csv"
    _write_export(path, meta, np.arange(len(seconds)), seconds, columns)
    loaded = load_optitrack(path)
    for name in BODIES:
        for ours, theirs in zip(loaded[name], base[name], strict=True):
            np.testing.assert_array_equal(ours, theirs)


def test_untracked_frames_stay_nan(csv_path, tmp_path):
    lines = csv_path.read_text().splitlines(keepends=True)
    row = lines[10].split(",")
    row[2:8] = [""] * 6  # RigidBody 01 lost for one frame
    lines[10] = ",".join(row)
    path = tmp_path / "gap.csv"
    path.write_text("".join(lines))
    position, orientation, _ = load_optitrack(path)["RigidBody 01"]
    assert np.isnan(position[3]).all() and np.isnan(orientation[3]).all()
    assert not np.isnan(np.delete(position, 3, axis=0)).any()


def test_header_only_export_gives_empty_arrays(csv_path, tmp_path):
    path = tmp_path / "no_frames.csv"
    header = "".join(csv_path.read_text().splitlines(keepends=True)[:7])
    path.write_text(header)
    # the header still announces 227 frames: that is a truncated file
    with pytest.raises(
        FileFormatError, match="announces 227 exported frames.*0 data rows"
    ):
        load_optitrack(path)
    path.write_text(
        header.replace("Total Exported Frames,227", "Total Exported Frames,0")
    )
    data = load_optitrack(path)
    assert sorted(data) == BODIES
    position, orientation, timestamps = data["RigidBody 01"]
    assert (
        position.shape == (0, 3)
        and orientation.shape == (0, 4)
        and timestamps.shape == (0,)
    )
    assert load_optitrack(path, "xarray")["RigidBody 02"].sizes["time"] == 0


def test_truncated_at_a_line_boundary_names_file_and_counts(csv_path, tmp_path):
    """Cut after a whole row: every line parses, but rows are missing."""
    lines = csv_path.read_text().splitlines(keepends=True)
    path = tmp_path / "cut.csv"
    path.write_text("".join(lines[: 7 + 110]))
    with pytest.raises(
        FileFormatError,
        match=r"cut\.csv: the header announces 227 .* 110 data rows: it is truncated",
    ):
        load_optitrack(path)
    path.write_text("".join(lines + lines[-3:]))
    with pytest.raises(FileFormatError, match="230 data rows: it has rows beyond them"):
        load_optitrack(path)


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        (
            lambda rows: rows[:50] + [rows[49]] + rows[51:],
            "line 58 has frame number 49, not after 49 on line 57",
        ),
        (
            lambda rows: rows[:50] + [rows[51], rows[50]] + rows[52:],
            "line 59 has frame number 50, not after 51 on line 58",
        ),
        (
            lambda rows: (
                rows[:50] + [rows[50].replace("50,0.833333,", "50,0.8,", 1)] + rows[51:]
            ),
            "line 58 has time 0.8, not after 0.816667 on line 57",
        ),
    ],
)
def test_duplicated_or_reordered_rows_raise(csv_path, tmp_path, edit, match):
    lines = csv_path.read_text().splitlines(keepends=True)
    path = tmp_path / "rows.csv"
    path.write_text("".join(lines[:7] + edit(lines[7:])))
    with pytest.raises(FileFormatError, match=match):
        load_optitrack(path)
