"""Damaged and unexpected files: clear errors naming the file, no partial results."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from rbm_nb.io import FileFormatError, load_netcdf, load_optitrack
from rbm_nb.ros import RosbagReader, RosbagWriter

ODOM = "/camera/odom/sample"


@pytest.fixture
def bag(shared_data, tmp_path) -> Path:
    return Path(shutil.copy(shared_data / "test.bag", tmp_path / "rec.bag"))


@pytest.fixture
def csv(shared_data, tmp_path) -> Path:
    return Path(shutil.copy(shared_data / "optitrack.csv", tmp_path / "take.csv"))


def _no_cache(path: Path) -> bool:
    cache = path.parent / "cache"
    return not cache.exists() or not any(cache.iterdir())


# -- rosbags -----------------------------------------------------------------


@pytest.mark.parametrize(
    "damage, problem",
    [
        (lambda d: d[: len(d) // 2], "index looks damaged"),
        (lambda d: d[:100], "not a readable rosbag"),
        (lambda d: b"", "empty"),
        (lambda d: b"hello world\n" * 100, "magic is invalid"),
        (lambda d: d[:4109] + b"\xff" * 16 + d[4125:], "Header could not be read"),
    ],
    ids=["half", "first-100-bytes", "empty", "not-a-bag", "broken-chunk-header"],
)
def test_damaged_bag(bag, damage, problem):
    bag.write_bytes(damage(bag.read_bytes()))
    with pytest.raises(FileFormatError, match=problem) as info:
        RosbagReader(bag).load_dataset(ODOM, cache=True)
    assert str(bag) in str(info.value)
    assert _no_cache(bag)


def test_bag_damaged_in_the_middle_of_a_topic(bag):
    """A broken record header found only while reading: error, no result, no cache."""
    data = bytearray(bag.read_bytes())
    records = [m.start() for m in re.finditer(b"op=\x02", data)]  # message data records
    op = records[300]
    data[op - 8 : op - 4] = (10**7).to_bytes(4, "little")  # absurd header length
    bag.write_bytes(bytes(data))
    reader = RosbagReader(bag)
    with pytest.raises(
        FileFormatError,
        match=r"damaged: reading '/camera/odom/sample' failed after \d+ of 228",
    ) as info:
        reader.load_dataset(ODOM, cache=True)
    assert str(bag) in str(info.value)
    assert _no_cache(bag)


def test_missing_bag(tmp_path):
    with pytest.raises(FileNotFoundError, match="nope.bag"):
        RosbagReader(tmp_path / "nope.bag").get_topics_and_types()


def test_folder_that_is_not_a_ros2_bag(tmp_path):
    (tmp_path / "folder").mkdir()
    with pytest.raises(FileFormatError, match="folder is not a readable rosbag"):
        RosbagReader(tmp_path / "folder").get_topics_and_types()


def test_unknown_topic_lists_available_ones(bag):
    with pytest.raises(ValueError) as info:
        RosbagReader(bag).load_messages("/camera/odom/sampel")
    message = str(info.value)
    assert "'/camera/odom/sampel' is not in" in message
    assert "Did you mean '/camera/odom/sample'" in message
    for topic in (
        "/camera/accel/sample",
        "/camera/gyro/sample",
        ODOM,
        "/vicon/t265_tracker/t265_tracker",
    ):
        assert topic in message


def test_unsupported_message_type_names_supported_ones(bag):
    with pytest.raises(ValueError) as info:
        RosbagReader(bag).load_dataset("/camera/gyro/sample")
    message = str(info.value)
    assert "sensor_msgs/Imu" in message
    for name in (
        "geometry_msgs/TransformStamped",
        "nav_msgs/Odometry",
        "geometry_msgs/PoseStamped",
    ):
        assert name in message
    assert _no_cache(bag)


@pytest.mark.parametrize("name", ["empty.bag", "empty_ros2"])
def test_empty_topic_gives_empty_arrays_and_dataset(tmp_path, name):
    """Documented behaviour: a topic without messages loads as length-0 data."""
    with RosbagWriter(tmp_path / name) as writer:
        writer.write_transform_stamped(
            [], np.empty((0, 3)), np.empty((0, 4)), "/nothing", "a", "b"
        )
    with RosbagReader(tmp_path / name) as reader:
        assert reader.get_topics_and_types() == {
            "/nothing": "geometry_msgs/TransformStamped"
        }
        loaded = reader.load_messages("/nothing")
        ds = reader.load_dataset("/nothing", cache=True)
    assert loaded["timestamps"].shape == (0,)
    assert loaded["position"].shape == (0, 3) and loaded["orientation"].shape == (0, 4)
    assert dict(ds.sizes) == {"time": 0, "cartesian_axis": 3, "quaternion_axis": 4}
    assert ds.time.dtype == np.dtype("datetime64[ns]")


def test_corrupt_cache_file_is_named(bag):
    reader = RosbagReader(bag)
    reader.load_dataset(ODOM, cache=True)
    cache = reader.cache_file(ODOM)
    cache.write_bytes(cache.read_bytes()[:200])
    with pytest.raises(FileFormatError, match="not a readable netCDF file") as info:
        reader.load_dataset(ODOM, cache=True)
    assert str(cache) in str(info.value)


# -- netCDF ------------------------------------------------------------------


def test_truncated_netcdf(bag, tmp_path):
    path = RosbagReader(bag).export(ODOM, tmp_path / "odom.nc")
    path.write_bytes(path.read_bytes()[:1000])
    with pytest.raises(FileFormatError, match="odom.nc is not a readable netCDF file"):
        load_netcdf(path)


def test_netcdf_that_is_text(tmp_path):
    path = tmp_path / "notes.nc"
    path.write_text("just some notes\n")
    with pytest.raises(FileFormatError, match="notes.nc"):
        load_netcdf(path)


def test_failed_export_keeps_the_old_file(bag, tmp_path):
    target = tmp_path / "odom.nc"
    target.write_bytes(b"previous export")
    with pytest.raises(ValueError, match="cannot load"):
        RosbagReader(bag).export("/camera/gyro/sample", target)
    assert target.read_bytes() == b"previous export"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["odom.nc", "rec.bag"]


# -- OptiTrack CSV -------------------------------------------------------------


def test_truncated_csv(csv):
    text = csv.read_text()
    csv.write_text(text[: len(text) // 2])
    with pytest.raises(FileFormatError, match="take.csv ends in the middle of a row"):
        load_optitrack(csv)


def test_csv_with_a_short_row(csv):
    lines = csv.read_text().splitlines(keepends=True)
    lines[20] = ",".join(lines[20].split(",")[:10]) + "\n"
    csv.write_text("".join(lines))
    with pytest.raises(
        FileFormatError, match="take.csv: line 21 has 10 fields, the header has 47"
    ):
        load_optitrack(csv)


def test_csv_with_text_in_the_numbers(csv):
    lines = csv.read_text().splitlines(keepends=True)
    fields = lines[30].split(",")
    fields[4] = "oops"
    lines[30] = ",".join(fields)
    csv.write_text("".join(lines))
    with pytest.raises(
        FileFormatError, match="take.csv: the data rows are not all numbers"
    ):
        load_optitrack(csv)


@pytest.mark.parametrize(
    "content, problem",
    [
        ("a,b,c\n1,2,3\n4,5,6\n", "has 3 lines"),
        ("name,value\n" * 20, "not an OptiTrack CSV export: its first row"),
        ("", "has 0 lines"),
    ],
    ids=["small-csv", "other-csv", "empty"],
)
def test_csv_that_is_not_an_optitrack_export(tmp_path, content, problem):
    path = tmp_path / "other.csv"
    path.write_text(content)
    with pytest.raises(FileFormatError, match=problem) as info:
        load_optitrack(path)
    assert str(path) in str(info.value)


def test_binary_file_as_csv(bag):
    with pytest.raises(
        FileFormatError, match="rec.bag is not an OptiTrack CSV export: it is not text"
    ):
        load_optitrack(bag)


def test_csv_without_frame_header(csv):
    lines = csv.read_text().splitlines(keepends=True)
    lines[6] = lines[6].replace("Frame,Time (Seconds)", "Frame,Seconds")
    csv.write_text("".join(lines))
    with pytest.raises(
        FileFormatError, match="should start with 'Frame', 'Time \\(Seconds\\)'"
    ):
        load_optitrack(csv)


def test_csv_with_bad_start_time(csv):
    csv.write_text(csv.read_text().replace("2020-06-16 07.51.41.245 PM", "June 16th"))
    with pytest.raises(FileFormatError, match="'Capture Start Time' 'June 16th'"):
        load_optitrack(csv)


def test_csv_with_unknown_units(csv):
    lines = csv.read_text().splitlines(keepends=True)
    lines[0] = (
        lines[0].replace(
            "Total Exported Frames,227,",
            "Total Exported Frames,227,Length Units,Furlongs,",
            1,
        )[:-3]
        + "\n"
    )
    csv.write_text("".join(lines))
    with pytest.raises(FileFormatError, match="unknown 'Length Units' 'Furlongs'"):
        load_optitrack(csv)


def test_csv_with_incomplete_rigid_body(csv):
    lines = csv.read_text().splitlines(keepends=True)
    for i in (2, 5):  # drop RigidBody 01's rotation X column from the header
        row = lines[i].split(",")
        row[2] = "Marker" if i == 2 else row[2]
        lines[i] = ",".join(row)
    csv.write_text("".join(lines))
    with pytest.raises(
        FileFormatError, match="rigid body 'RigidBody 01' has position columns"
    ):
        load_optitrack(csv)


def test_bad_import_format(csv):
    with pytest.raises(ValueError, match="import_format must be one of"):
        load_optitrack(csv, import_format="polars")


def test_missing_csv(tmp_path):
    with pytest.raises(FileNotFoundError, match="missing.csv"):
        load_optitrack(tmp_path / "missing.csv")


# -- random corruption: a clear error or valid data, never garbage -------------

TOPICS = (ODOM, "/vicon/t265_tracker/t265_tracker")


def _valid(messages: dict) -> bool:
    """What a caller may rely on: finite stamps, finite (or all-NaN) fields, unit q."""
    if not np.isfinite(messages["timestamps"]).all():
        return False
    for name, values in messages.items():
        if name == "timestamps":
            continue
        ok = np.isfinite(values).all(axis=1) | np.isnan(values).all(axis=1)
        if not ok.all():
            return False
    q = messages["orientation"]
    q = q[np.isfinite(q).all(axis=1)]
    return bool(np.all(np.abs(np.linalg.norm(q, axis=1) - 1.0) <= 1e-2))


def test_random_corruptions_give_a_clear_error_or_valid_data(bag, tmp_path):
    """150 random 8-byte overwrites of a copy of the real bag (fixed seed)."""
    rng = np.random.default_rng(2024)
    original = bag.read_bytes()
    target = tmp_path / "corrupt.bag"
    outcomes = {"error": 0, "valid": 0}
    for trial in range(150):
        data = bytearray(original)
        at = int(rng.integers(0, len(data) - 8))
        data[at : at + 8] = rng.integers(0, 256, 8, dtype=np.uint8).tobytes()
        target.write_bytes(bytes(data))
        for topic in TOPICS:
            try:
                messages = RosbagReader(target).load_messages(topic)
            except FileFormatError as err:
                assert str(target) in str(err), (trial, at, err)
                outcomes["error"] += 1
            except ValueError as err:  # e.g. the topic's connection record was hit
                assert topic in str(err) and str(target) in str(err), (trial, at, err)
                outcomes["error"] += 1
            else:
                assert _valid(messages), (trial, at, topic)
                outcomes["valid"] += 1
    assert outcomes["error"] > 0 and outcomes["valid"] > 0, outcomes


def test_non_unit_quaternion_in_a_bag_names_topic_and_message(bag):
    """The reader checks decoded poses: a quaternion scaled by 1.5 in message 7."""
    with RosbagReader(bag) as reader:
        q = reader.load_messages(ODOM)["orientation"]
    data = bytearray(bag.read_bytes())
    # x, y, z, w of message 7 are stored as little-endian float64 in that order
    raw = np.array(q[7][[1, 2, 3, 0]], "<f8").tobytes()
    at = data.find(raw)
    assert at > 0 and data.find(raw, at + 1) == -1
    data[at : at + 32] = (np.frombuffer(raw, "<f8") * 1.5).tobytes()
    bag.write_bytes(bytes(data))
    with pytest.raises(
        FileFormatError,
        match=r"topic '/camera/odom/sample': message 7 has orientation .* norm 1\.5",
    ):
        RosbagReader(bag).load_messages(ODOM)
    partly_nan = bytearray(data)
    partly_nan[at : at + 8] = np.array([np.nan], "<f8").tobytes()
    bag.write_bytes(bytes(partly_nan))
    with pytest.raises(FileFormatError, match="message 7 has orientation .* all NaN"):
        RosbagReader(bag).load_messages(ODOM)
