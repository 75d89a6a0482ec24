"""KITTI OXTS packets (GPS/IMU, one text line per frame) -> ego poses.

Each ``oxts/data/<frame>.txt`` holds 30 numbers; the first six are latitude, longitude (degrees),
altitude (metres), roll, pitch, yaw (radians; yaw 0 = east, counter-clockwise). Positions go to a local
metric plane by the Mercator projection of the KITTI devkit: with ``s = cos(lat_0)`` of the first packet
and the earth radius ``r = 6378137`` m,

    x = s * r * lon * pi / 180,    y = s * r * ln(tan(pi * (90 + lat) / 360)),    z = alt,

and the IMU orientation is ``Rz(yaw) @ Ry(pitch) @ Rx(roll)``. The IMU frame is x forward, y left, z up,
the ego frame of ``SceneLog``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from simsplat_core.data.errors import CorruptLogError
from simsplat_core.geometry import make_transform

EARTH_RADIUS_M = 6378137.0
#: Values per OXTS packet line.
OXTS_FIELDS = 30
_FIELD_NAMES = ("lat", "lon", "alt", "roll", "pitch", "yaw")


def read_oxts_packet(path: Path) -> np.ndarray:
    """``[30]`` float64 values of one OXTS packet file.

    Raises:
        CorruptLogError: missing file, non-numeric values, a wrong count, or a non-finite pose value
            (names the file and the field).
    """
    if not path.is_file():
        raise CorruptLogError(path, "file", "missing")
    text = path.read_text(encoding="utf-8", errors="replace").split()
    try:
        values = np.array([float(v) for v in text], dtype=np.float64)
    except ValueError as exc:
        raise CorruptLogError(path, "packet", f"not numeric: {exc}") from exc
    if values.size != OXTS_FIELDS:
        raise CorruptLogError(path, "packet", f"expected {OXTS_FIELDS} values, got {values.size}")
    for k, name in enumerate(_FIELD_NAMES):
        if not np.isfinite(values[k]):
            raise CorruptLogError(path, f"field {name!r}", f"non-finite value {values[k]}")
    return values


def rotation_rpy(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """``[3, 3]`` ``Rz(yaw) @ Ry(pitch) @ Rx(roll)``."""
    cr, sr, cp, sp, cy, sy = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    return rz @ ry @ rx


def oxts_poses(packets: np.ndarray) -> np.ndarray:
    """``[F, 4, 4]`` float64 IMU-to-world poses of ``[F, 30]`` packets, world = the first IMU pose.

    ``poses[0]`` is the identity; the Mercator scale comes from the first packet's latitude.
    """
    lat, lon, alt = packets[:, 0], packets[:, 1], packets[:, 2]
    scale = np.cos(np.deg2rad(lat[0]))
    x = scale * EARTH_RADIUS_M * np.deg2rad(lon)
    y = scale * EARTH_RADIUS_M * np.log(np.tan(np.pi * (90.0 + lat) / 360.0))
    mercator = np.stack([
        make_transform(rotation_rpy(*packets[k, 3:6]), np.array([x[k], y[k], alt[k]]))
        for k in range(packets.shape[0])
    ])
    first_inv = np.linalg.inv(mercator[0])
    poses = first_inv[None] @ mercator
    poses[0] = np.eye(4)
    return poses
