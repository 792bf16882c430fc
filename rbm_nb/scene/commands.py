"""meshcat commands lowered to the bytes the viewer decodes.

Scene objects are built from meshcat's own geometry classes and lowered with
``umsgpack``, like meshcat-python does. ``set_transform`` is the per-step hot
path, so its msgpack encoding is assembled directly from a prefix computed once
per path and the 16 matrix entries.
"""

from __future__ import annotations

import importlib.util
import math
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import umsgpack


@dataclass(frozen=True)
class Message:
    """One lowered meshcat command.

    Attributes
    ----------
    op : str
        ``set_object``, ``set_transform``, ``set_property`` or ``delete``.
    path : str
        Scene path, e.g. ``/rbm/root/head/pose``.
    data : bytes
        The msgpack bytes meshcat's viewer decodes.
    prop : str
        Property name for ``set_property``.
    """

    op: str
    path: str
    data: bytes
    prop: str = ""


def meshcat_js_path() -> Path:
    """Path of meshcat's own viewer bundle (``meshcat/viewer/dist/main.min.js``)."""
    spec = importlib.util.find_spec("meshcat")
    if spec is None or not spec.submodule_search_locations:
        raise ModuleNotFoundError(
            "the 3D scene needs meshcat: pip install 'rbm_nb[notebook]'"
        )
    path = (
        Path(list(spec.submodule_search_locations)[0])
        / "viewer"
        / "dist"
        / "main.min.js"
    )
    if not path.is_file():
        raise FileNotFoundError(f"meshcat's viewer bundle is missing: {path}")
    return path


def _msgpack_str(text: str) -> bytes:
    raw = text.encode("utf-8")
    n = len(raw)
    if n < 32:
        return bytes([0xA0 | n]) + raw
    if n < 256:
        return bytes([0xD9, n]) + raw
    return bytes([0xDA]) + n.to_bytes(2, "big") + raw


_F64 = np.dtype(">f8")


def meshcat_geometry():
    """``meshcat.geometry``, imported without the noise of meshcat's package init.

    Importing any meshcat module runs its ``__init__``, which loads its ZeroMQ
    server module and with it a deprecated pyzmq module; rbm_nb does not use
    that server.
    """
    with warnings.catch_warnings():
        warnings.filterwarnings(
            "ignore",
            message="zmq.eventloop.ioloop is deprecated",
            category=DeprecationWarning,
        )
        import meshcat.geometry

    return meshcat.geometry


class TransformPacker:
    """Encodes ``set_transform`` commands for one path, fast.

    The bytes are exactly what ``umsgpack.packb`` makes of meshcat's lowered
    ``SetTransform`` (a map of type, path and the column-major matrix).
    """

    __slots__ = ("path", "_prefix", "_buf")

    def __init__(self, path: str):
        self.path = path
        self._prefix = (
            b"\x83"
            + _msgpack_str("type")
            + _msgpack_str("set_transform")
            + _msgpack_str("path")
            + _msgpack_str(path)
            + _msgpack_str("matrix")
            + b"\xdc\x00\x10"
        )
        self._buf = np.empty((16, 9), dtype=np.uint8)
        self._buf[:, 0] = 0xCB  # msgpack float64 marker

    def pack(self, matrix: np.ndarray) -> bytes:
        """Bytes of the command for a (4, 4) homogeneous matrix."""
        column_major = np.ascontiguousarray(matrix, dtype=np.float64).T.reshape(16)
        self._buf[:, 1:] = column_major.astype(_F64).view(np.uint8).reshape(16, 8)
        return self._prefix + self._buf.tobytes()

    def message(self, matrix: np.ndarray) -> Message:
        return Message("set_transform", self.path, self.pack(matrix))


def pose_matrix(translation, rotation) -> np.ndarray:
    """Homogeneous (4, 4) matrix of one pose.

    Parameters
    ----------
    translation : array_like, shape (3,)
    rotation : array_like, shape (4,)
        Quaternion ``(w, x, y, z)``; normalised here.
    """
    w, x, y, z = (float(v) for v in rotation)
    norm = math.sqrt(w * w + x * x + y * y + z * z)
    if norm == 0.0 or not math.isfinite(norm):
        raise ValueError(
            f"rotation must be a non-zero finite quaternion, got {rotation}"
        )
    w, x, y, z = w / norm, x / norm, y / norm, z / norm
    m = np.empty((4, 4))
    m[0, 0] = 1 - 2 * (y * y + z * z)
    m[0, 1] = 2 * (x * y - w * z)
    m[0, 2] = 2 * (x * z + w * y)
    m[1, 0] = 2 * (x * y + w * z)
    m[1, 1] = 1 - 2 * (x * x + z * z)
    m[1, 2] = 2 * (y * z - w * x)
    m[2, 0] = 2 * (x * z - w * y)
    m[2, 1] = 2 * (y * z + w * x)
    m[2, 2] = 1 - 2 * (x * x + y * y)
    m[:3, 3] = translation
    m[3] = (0.0, 0.0, 0.0, 1.0)
    return m


def set_transform(path: str, matrix: np.ndarray) -> Message:
    return TransformPacker(path).message(matrix)


def set_object(path: str, obj) -> Message:
    """``set_object`` of a meshcat geometry ``Object`` (Mesh, LineSegments, ...)."""
    lowered = {"type": "set_object", "object": obj.lower(), "path": path}
    return Message("set_object", path, umsgpack.packb(lowered))


def set_property(path: str, key: str, value) -> Message:
    lowered = {"type": "set_property", "path": path, "property": key, "value": value}
    return Message("set_property", path, umsgpack.packb(lowered), prop=key)


def delete(path: str) -> Message:
    return Message("delete", path, umsgpack.packb({"type": "delete", "path": path}))


def color_int(color, name: str = "color") -> int:
    """A colour as the 0xRRGGBB integer three.js wants.

    Accepts ``"#rrggbb"``, ``"#rrggbbaa"`` (alpha ignored here), ``"#rgb"``,
    an integer or an RGB tuple of floats in [0, 1].
    """
    if isinstance(color, (int, np.integer)) and not isinstance(color, bool):
        if not 0 <= int(color) <= 0xFFFFFF:
            raise ValueError(f"{name} must be in [0, 0xffffff], got {color}")
        return int(color)
    if isinstance(color, str):
        text = color.strip().lstrip("#")
        if len(text) == 3:
            text = "".join(c * 2 for c in text)
        if len(text) in (6, 8):
            try:
                return int(text[:6], 16)
            except ValueError:
                pass
        raise ValueError(f"{name} must look like '#rrggbb', got {color!r}")
    rgb = np.asarray(color, dtype=float)
    if rgb.shape not in ((3,), (4,)) or not np.all((rgb >= 0) & (rgb <= 1)):
        raise ValueError(
            f"{name} must be '#rrggbb' or an RGB tuple in [0, 1], got {color!r}"
        )
    r, g, b = (int(round(c * 255)) for c in rgb[:3])
    return (r << 16) | (g << 8) | b
