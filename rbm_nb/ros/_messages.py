"""Motion messages as numpy arrays: the types rbm_nb reads and writes.

Decoding has a fast path: the messages of one topic almost always share one
byte layout (the frame ids do not change), so all of them are read at once as
rows of a byte matrix. When they do not, each message goes through the
``rosbags`` deserializer instead. Encoding (TransformStamped only) builds the
same byte matrix, for ROS1 and for little-endian CDR (ROS2). The tests check
both directions byte for byte against ``rosbags``' own serializers.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from .._infra.config import UNIT_QUATERNION_TOLERANCE
from ..io._files import FileFormatError

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

TRANSFORM_STAMPED = "geometry_msgs/TransformStamped"
TF_MESSAGE = "tf2_msgs/TFMessage"
# tf (not tf2) spelling of the same message in old ROS1 bags
TF_TYPES = (TF_MESSAGE, "tf/tfMessage")
_TF_DEFINITION = "geometry_msgs/TransformStamped[] transforms"
ODOMETRY = "nav_msgs/Odometry"
POSE_STAMPED = "geometry_msgs/PoseStamped"

_CDR_LE = b"\x00\x01"  # CDR encapsulation header, little endian


@dataclass(frozen=True)
class Kind:
    """Where the numbers of a message type are, after its header strings."""

    has_child_frame: bool
    n_floats: int  # float64 values after the strings
    twist_at: int | None  # index of twist.linear among those floats


KINDS = {
    TRANSFORM_STAMPED: Kind(True, 7, None),
    ODOMETRY: Kind(True, 7 + 36 + 6 + 36, 7 + 36),
    POSE_STAMPED: Kind(False, 7, None),
}
SUPPORTED_TYPES = tuple(KINDS)


def ros1_type_name(msgtype: str) -> str:
    """``geometry_msgs/msg/TransformStamped`` -> ``geometry_msgs/TransformStamped``."""
    return msgtype.replace("/msg/", "/")


def rosbags_type_name(name: str) -> str:
    """``geometry_msgs/TransformStamped`` -> ``geometry_msgs/msg/TransformStamped``."""
    package, _, message = name.partition("/")
    return f"{package}/msg/{message}"


@dataclass
class Messages:
    """Arrays of one topic: stamps split in sec/nsec, poses and maybe twists."""

    sec: np.ndarray  # (n,) int64
    nsec: np.ndarray  # (n,) int64
    position: np.ndarray  # (n, 3)
    orientation: np.ndarray  # (n, 4) w, x, y, z
    linear_velocity: np.ndarray | None = None  # (n, 3)
    angular_velocity: np.ndarray | None = None  # (n, 3)
    frame_id: str = ""
    child_frame_id: str = ""

    @classmethod
    def empty(cls, kind: Kind) -> Messages:
        twist = np.empty((0, 3)) if kind.twist_at is not None else None
        zeros = np.empty(0, np.int64)
        return cls(
            zeros, zeros.copy(), np.empty((0, 3)), np.empty((0, 4)), twist, twist
        )

    @classmethod
    def from_rows(
        cls,
        sec: npt.ArrayLike,
        nsec: npt.ArrayLike,
        pose: np.ndarray,
        twist: np.ndarray | None = None,
        frame_id: str = "",
        child_frame_id: str = "",
    ) -> Messages:
        """From rows of [x, y, z, qx, qy, qz, qw] (n, 7) and [vx, vy, vz, wx, wy, wz] (n, 6)."""
        return cls(
            sec=np.asarray(sec, np.int64),
            nsec=np.asarray(nsec, np.int64),
            position=pose[:, 0:3].copy(),
            orientation=pose[:, [6, 3, 4, 5]],
            linear_velocity=None if twist is None else twist[:, 0:3].copy(),
            angular_velocity=None if twist is None else twist[:, 3:6].copy(),
            frame_id=frame_id,
            child_frame_id=child_frame_id,
        )

    @property
    def timestamps(self) -> np.ndarray:
        """Header stamps as float seconds, computed like rospy's ``Time.to_sec``."""
        return self.sec.astype(np.float64) + self.nsec.astype(np.float64) / 1e9

    @property
    def stamps_ns(self) -> np.ndarray:
        """Header stamps as int64 nanoseconds (exact)."""
        return self.sec * 1_000_000_000 + self.nsec


# ---------------------------------------------------------------------------
# decoding
# ---------------------------------------------------------------------------


# ROS1 starts with seq, sec, nsec; CDR with its encapsulation header, sec,
# nsec: either way the stamp is at bytes 4-12 and frame_id's length at 12
_SEC, _NSEC, _FIRST_STRING = 4, 8, 12


@dataclass(frozen=True)
class _Layout:
    floats: int  # offset of the first float64
    frame_id: str
    child_frame_id: str


def _u32(raw: bytes, offset: int) -> int:
    return int.from_bytes(raw[offset : offset + 4], "little")


def _align(offset: int, base: int, size: int) -> int:
    """Round ``offset`` up to a multiple of ``size`` counted from ``base``."""
    return base + (-(-(offset - base) // size)) * size


def _layout(raw: bytes, kind: Kind, cdr: bool) -> _Layout | None:
    """Offsets in one serialized message, or None if it is not laid out as expected."""
    if cdr and raw[:2] != _CDR_LE:
        return None
    base = 4 if cdr else 0  # CDR aligns relative to the end of its header
    pos, strings = _FIRST_STRING, []
    for _ in range(1 + kind.has_child_frame):
        if cdr:
            pos = _align(pos, base, 4)
        n = _u32(raw, pos)
        text = raw[pos + 4 : pos + 4 + n]
        if cdr:
            if not text.endswith(b"\x00"):
                return None
            text = text[:-1]
        try:
            strings.append(text.decode())
        except UnicodeDecodeError:
            return None
        pos += 4 + n
    floats = _align(pos, base, 8) if cdr else pos
    end = floats + 8 * kind.n_floats
    # CDR messages may be padded to a multiple of 4 or 8 bytes
    if not (end <= len(raw) < end + 8 if cdr else end == len(raw)):
        return None
    strings.append("")
    return _Layout(floats, strings[0], strings[1])


def _column(rows: np.ndarray, offset: int, dtype: str, count: int = 1) -> np.ndarray:
    size = np.dtype(dtype).itemsize * count
    return np.ascontiguousarray(rows[:, offset : offset + size]).view(dtype)


def decode_raw(raws: list, kind: Kind, cdr: bool) -> Messages | None:
    """All messages at once, or None when they do not share one layout."""
    if not raws:
        return Messages.empty(kind)
    size = len(raws[0])
    if any(len(raw) != size for raw in raws):
        return None
    layout = _layout(bytes(raws[0]), kind, cdr)
    if layout is None:
        return None
    rows = np.frombuffer(b"".join(raws), np.uint8).reshape(len(raws), size)
    # the same header strings in every message: the same offsets everywhere
    strings = rows[:, _FIRST_STRING : layout.floats]
    if not (strings == strings[0]).all():
        return None
    sec = _column(rows, _SEC, "<i4" if cdr else "<u4")[:, 0]
    nsec = _column(rows, _NSEC, "<u4")[:, 0]
    floats = _column(rows, layout.floats, "<f8", kind.n_floats)
    twist = (
        None if kind.twist_at is None else floats[:, kind.twist_at : kind.twist_at + 6]
    )
    return Messages.from_rows(
        sec, nsec, floats[:, :7], twist, layout.frame_id, layout.child_frame_id
    )


def decode_objects(msgs: list, name: str) -> Messages:
    """Messages deserialized by rosbags, one by one (the general path)."""
    if not msgs:
        return Messages.empty(KINDS[name])
    pose = np.array([_pose(msg, name) for msg in msgs], dtype=np.float64)
    twist = None
    if name == ODOMETRY:
        twist = np.array([_twist(msg.twist.twist) for msg in msgs], dtype=np.float64)
    sec = [msg.header.stamp.sec for msg in msgs]
    nsec = [msg.header.stamp.nanosec for msg in msgs]
    # frame ids that change within a topic are all listed
    frames = ", ".join(dict.fromkeys(msg.header.frame_id for msg in msgs))
    children = ", ".join(
        dict.fromkeys(getattr(msg, "child_frame_id", "") for msg in msgs)
    )
    return Messages.from_rows(sec, nsec, pose, twist, frames, children)


def _pose(msg, name: str) -> tuple:
    if name == TRANSFORM_STAMPED:
        p, o = msg.transform.translation, msg.transform.rotation
    else:
        pose = msg.pose.pose if name == ODOMETRY else msg.pose
        p, o = pose.position, pose.orientation
    return (p.x, p.y, p.z, o.x, o.y, o.z, o.w)


def _twist(twist) -> tuple:
    lin, ang = twist.linear, twist.angular
    return (lin.x, lin.y, lin.z, ang.x, ang.y, ang.z)


def check_messages(
    messages: Messages, where: str, index: np.ndarray | None = None
) -> None:
    """Raise FileFormatError unless the decoded values are what a bag can hold.

    Each pose field (position, orientation, each twist part) of a message is
    all finite, or all NaN (a sample without data, written so on purpose);
    finite orientations are unit quaternions within
    ``UNIT_QUATERNION_TOLERANCE``; nanoseconds are below 1e9. ``where``
    names the bag and topic in the message, which also gives the index of
    the first bad message (row ``i`` is message ``index[i]`` if given).
    """

    def number(i):
        return int(i if index is None else index[i])

    bad_nsec = np.flatnonzero((messages.nsec < 0) | (messages.nsec >= 1_000_000_000))
    if bad_nsec.size:
        i = int(bad_nsec[0])
        raise FileFormatError(
            f"{where}: message {number(i)} has a header stamp with {messages.nsec[i]} "
            "nanoseconds (must be below 1e9): the bag is damaged"
        )
    fields = [("position", messages.position), ("orientation", messages.orientation)]
    linear, angular = messages.linear_velocity, messages.angular_velocity
    if linear is not None and angular is not None:  # both or neither
        fields += [("linear velocity", linear), ("angular velocity", angular)]
    for name, values in fields:
        finite = np.isfinite(values).all(axis=1)
        bad = np.flatnonzero(~(finite | np.isnan(values).all(axis=1)))
        if bad.size:
            i = int(bad[0])
            raise FileFormatError(
                f"{where}: message {number(i)} has {name} {values[i].tolist()}; a field must be "
                "all finite, or all NaN for a sample without data: the bag is damaged"
            )
    q = messages.orientation
    finite = np.isfinite(q).all(axis=1)
    with np.errstate(over="ignore"):  # a damaged value may be ~1e300: inf norm, refused
        norms = np.linalg.norm(q, axis=1)
    error = np.abs(norms[finite] - 1.0)
    if error.size and error.max() > UNIT_QUATERNION_TOLERANCE:
        i = int(np.flatnonzero(finite)[np.argmax(error > UNIT_QUATERNION_TOLERANCE)])
        raise FileFormatError(
            f"{where}: message {number(i)} has orientation {q[i].tolist()} (w, x, y, z) of norm "
            f"{norms[i]:.6g}, not a unit quaternion (tolerance "
            f"{UNIT_QUATERNION_TOLERANCE}): the bag is damaged"
        )


def register_tf_message(typestore: Typestore) -> None:
    """Teach a rosbags typestore ``tf2_msgs/msg/TFMessage`` (ROS1 stores lack it)."""
    if "tf2_msgs/msg/TFMessage" not in typestore.types:
        from rosbags.typesys import get_types_from_msg

        typestore.register(get_types_from_msg(_TF_DEFINITION, "tf2_msgs/msg/TFMessage"))


@dataclass
class TfPair:
    """Every transform of one parent/child pair found in tf messages."""

    frame_id: str
    child_frame_id: str
    static: bool
    stamps_ns: np.ndarray  # (n,) int64, increasing
    position: np.ndarray  # (n, 3)
    orientation: np.ndarray  # (n, 4) w, x, y, z
    message_index: np.ndarray  # (n,) index of the tf message in its topic

    @property
    def timestamps(self) -> np.ndarray:
        """Header stamps as float seconds."""
        sec, nsec = np.divmod(self.stamps_ns, 1_000_000_000)
        return sec.astype(np.float64) + nsec.astype(np.float64) / 1e9


def split_tf(msgs: list, static: bool) -> dict:
    """Transforms of deserialized tf messages, per (frame_id, child_frame_id).

    Samples of a moving pair are sorted by stamp; of several with the same
    stamp the last one received is kept (a newer one replaces an older one,
    as in tf2's buffer). A static pair keeps its last transform only.
    """
    rows: dict = {}
    for index, msg in enumerate(msgs):
        for tr in msg.transforms:
            key = (tr.header.frame_id, tr.child_frame_id)
            t, r = tr.transform.translation, tr.transform.rotation
            stamp = int(tr.header.stamp.sec) * 1_000_000_000 + int(
                tr.header.stamp.nanosec
            )
            rows.setdefault(key, []).append(
                (
                    stamp,
                    t.x,
                    t.y,
                    t.z,
                    r.w,
                    r.x,
                    r.y,
                    r.z,
                    index,
                    int(tr.header.stamp.nanosec),
                )
            )
    pairs = {}
    for (frame, child), values in rows.items():
        arr = np.array(values, dtype=object)
        stamps = arr[:, 0].astype(np.int64)
        floats = arr[:, 1:8].astype(np.float64)
        received = arr[:, 8].astype(np.int64)
        nsec = arr[:, 9].astype(np.int64)
        if static:
            keep = np.array([len(values) - 1])
        else:
            order = np.argsort(stamps, kind="stable")
            # last of equal stamps: unique on the reversed order
            _, last = np.unique(stamps[order][::-1], return_index=True)
            keep = order[len(order) - 1 - last]
        pairs[(frame, child)] = (
            TfPair(
                frame, child, static, stamps[keep], floats[keep, :3], floats[keep, 3:],
                received[keep],
            ),
            nsec,
            received,
        )  # fmt: skip
    return pairs


def check_tf(pair: TfPair, nsec: np.ndarray, index: np.ndarray, where: str) -> None:
    """:func:`check_messages` for one tf pair; errors name the tf message index."""
    bad = np.flatnonzero((nsec < 0) | (nsec >= 1_000_000_000))
    if bad.size:
        raise FileFormatError(
            f"{where}: message {int(index[bad[0]])} has a stamp with {int(nsec[bad[0]])} "
            "nanoseconds (must be below 1e9): the bag is damaged"
        )
    n = len(pair.stamps_ns)
    messages = Messages(
        np.zeros(n, np.int64), np.zeros(n, np.int64), pair.position, pair.orientation
    )
    check_messages(
        messages,
        f"{where} ({pair.frame_id} -> {pair.child_frame_id})",
        pair.message_index,
    )


def tf_message(
    typestore: Typestore,
    stamps_ns: Sequence[int],
    frames: Sequence[str],
    children: Sequence[str],
    translation: Sequence[np.ndarray] | np.ndarray,
    rotation: Sequence[np.ndarray] | np.ndarray,
) -> Any:
    """A ``tf2_msgs/msg/TFMessage`` object holding one transform per row."""
    # the generated message classes (rosbags types them as a protocol)
    types: dict[str, Any] = typestore.types
    Time = types["builtin_interfaces/msg/Time"]
    Header = types["std_msgs/msg/Header"]
    Vector3 = types["geometry_msgs/msg/Vector3"]
    Quaternion = types["geometry_msgs/msg/Quaternion"]
    Transform = types["geometry_msgs/msg/Transform"]
    Stamped = types["geometry_msgs/msg/TransformStamped"]
    has_seq = "seq" in Header.__dataclass_fields__
    transforms = []
    for stamp, frame, child, t, r in zip(
        stamps_ns, frames, children, translation, rotation, strict=True
    ):
        sec, nsec = divmod(int(stamp), 1_000_000_000)
        time = Time(sec=sec, nanosec=nsec)
        header = (
            Header(seq=0, stamp=time, frame_id=frame)
            if has_seq
            else Header(stamp=time, frame_id=frame)
        )
        transforms.append(
            Stamped(
                header=header,
                child_frame_id=child,
                transform=Transform(
                    translation=Vector3(x=float(t[0]), y=float(t[1]), z=float(t[2])),
                    rotation=Quaternion(
                        x=float(r[1]), y=float(r[2]), z=float(r[3]), w=float(r[0])
                    ),
                ),
            )
        )
    return types["tf2_msgs/msg/TFMessage"](transforms=transforms)


# ---------------------------------------------------------------------------
# encoding
# ---------------------------------------------------------------------------


def _put(rows: np.ndarray, offset: int, values: np.ndarray) -> int:
    """Write each row's ``values`` (n, k) as bytes at ``offset``; returns the offset after."""
    as_bytes = np.ascontiguousarray(values).view(np.uint8)
    rows[:, offset : offset + as_bytes.shape[1]] = as_bytes
    return offset + as_bytes.shape[1]


def _put_string(rows: np.ndarray, offset: int, text: bytes, cdr: bool) -> int:
    if cdr:
        text += b"\x00"
    offset = _put(rows, offset, np.full((rows.shape[0], 1), len(text), "<u4"))
    rows[:, offset : offset + len(text)] = np.frombuffer(text, np.uint8)
    return offset + len(text)


def encode_transform_stamped(
    stamps_ns: np.ndarray,
    translation: np.ndarray,
    rotation: np.ndarray,
    frame_id: str,
    child_frame_id: str,
    cdr: bool,
) -> np.ndarray:
    """Serialized TransformStamped messages as rows of a uint8 matrix (n, size).

    ``stamps_ns`` are int64 ns since the epoch, ``rotation`` is w, x, y, z.
    ROS1 messages carry the row index as header ``seq``.
    """
    n = stamps_ns.shape[0]
    frame, child = frame_id.encode(), child_frame_id.encode()
    if cdr:
        base = 4
        strings = _align(12 + 4 + len(frame) + 1, base, 4) + 4 + len(child) + 1
        size = _align(strings, base, 8) + 56
    else:
        base = 0
        size = 12 + 4 + len(frame) + 4 + len(child) + 56
    rows = np.zeros((n, size), np.uint8)
    sec, nsec = np.divmod(stamps_ns, 1_000_000_000)
    if cdr:
        rows[:, :4] = np.frombuffer(_CDR_LE + b"\x00\x00", np.uint8)
        offset = _put(rows, 4, sec.astype("<i4")[:, None])
    else:
        offset = _put(rows, 0, np.arange(n, dtype="<u4")[:, None])
        offset = _put(rows, offset, sec.astype("<u4")[:, None])
    offset = _put(rows, offset, nsec.astype("<u4")[:, None])
    offset = _put_string(rows, offset, frame, cdr)
    if cdr:
        offset = _align(offset, base, 4)
    offset = _put_string(rows, offset, child, cdr)
    if cdr:
        offset = _align(offset, base, 8)
    floats = np.concatenate([translation, rotation[:, [1, 2, 3, 0]]], axis=1).astype(
        "<f8"
    )
    _put(rows, offset, floats)
    return rows
