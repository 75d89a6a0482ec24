"""The subset of Waymo Open Dataset's ``Frame`` proto (``dataset.proto`` / ``label.proto``) we read.

Field numbers follow the public protos (proto2). Decoded with ``protowire``; no TensorFlow and no
generated ``*_pb2`` modules. Lidar range images (``Frame.lasers``, field 5), camera/projected 2D
labels, no-label zones and map features are skipped without being parsed.

Units and frames: transforms are 4x4 row-major; ``Frame.pose`` maps the vehicle frame (x forward,
y left, z up) to the global frame; ``CameraCalibration.extrinsic`` maps the camera frame (also
x forward, y left, z up, *not* OpenCV) to the vehicle frame; label boxes are in the vehicle frame of
``Frame.pose``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from simsplat_core.data.protowire import Field, MessageSchema, ProtoDecodeError, decode_message

#: ``CameraName.Name`` enum -> our lower-case camera names.
CAMERA_NAMES: dict[int, str] = {
    1: "front",
    2: "front_left",
    3: "front_right",
    4: "side_left",
    5: "side_right",
    6: "rear_left",
    7: "rear",
    8: "rear_right",
}
#: ``Label.Type`` enum -> Waymo's type name.
LABEL_TYPES: dict[int, str] = {
    0: "TYPE_UNKNOWN",
    1: "TYPE_VEHICLE",
    2: "TYPE_PEDESTRIAN",
    3: "TYPE_SIGN",
    4: "TYPE_CYCLIST",
}

TRANSFORM = MessageSchema("Transform", (Field(1, "transform", "double", repeated=True),))
VELOCITY = MessageSchema(
    "Velocity",
    (
        Field(1, "v_x", "float"),
        Field(2, "v_y", "float"),
        Field(3, "v_z", "float"),
        Field(4, "w_x", "double"),
        Field(5, "w_y", "double"),
        Field(6, "w_z", "double"),
    ),
)
CAMERA_CALIBRATION = MessageSchema(
    "CameraCalibration",
    (
        Field(1, "name", "enum"),
        Field(2, "intrinsic", "double", repeated=True),
        Field(3, "extrinsic", "message", message=TRANSFORM),
        Field(4, "width", "int32"),
        Field(5, "height", "int32"),
        Field(6, "rolling_shutter_direction", "enum"),
    ),
)
STATS = MessageSchema(
    "Stats",
    (Field(2, "time_of_day", "string"), Field(3, "location", "string"), Field(4, "weather", "string")),
)
CONTEXT = MessageSchema(
    "Context",
    (
        Field(1, "name", "string"),
        Field(2, "camera_calibrations", "message", repeated=True, message=CAMERA_CALIBRATION),
        Field(4, "stats", "message", message=STATS),
    ),
)
CAMERA_IMAGE = MessageSchema(
    "CameraImage",
    (
        Field(1, "name", "enum"),
        Field(2, "image", "bytes"),
        Field(3, "pose", "message", message=TRANSFORM),
        Field(4, "velocity", "message", message=VELOCITY),
        Field(5, "pose_timestamp", "double"),
        Field(6, "shutter", "double"),
        Field(7, "camera_trigger_time", "double"),
        Field(8, "camera_readout_done_time", "double"),
    ),
)
BOX = MessageSchema(
    "Box",
    (
        Field(1, "center_x", "double"),
        Field(2, "center_y", "double"),
        Field(3, "center_z", "double"),
        Field(4, "width", "double"),
        Field(5, "length", "double"),
        Field(6, "height", "double"),
        Field(7, "heading", "double"),
    ),
)
LABEL_METADATA = MessageSchema(
    "Metadata",
    (
        Field(1, "speed_x", "double"),
        Field(2, "speed_y", "double"),
        Field(3, "accel_x", "double"),
        Field(4, "accel_y", "double"),
        Field(5, "speed_z", "double"),
        Field(6, "accel_z", "double"),
    ),
)
LABEL = MessageSchema(
    "Label",
    (
        Field(1, "box", "message", message=BOX),
        Field(2, "metadata", "message", message=LABEL_METADATA),
        Field(3, "type", "enum"),
        Field(4, "id", "string"),
        Field(5, "detection_difficulty_level", "enum"),
        Field(6, "tracking_difficulty_level", "enum"),
        Field(7, "num_lidar_points_in_box", "int32"),
        Field(11, "most_visible_camera_name", "string"),
        Field(13, "num_top_lidar_points_in_box", "int32"),
    ),
)
FRAME = MessageSchema(
    "Frame",
    (
        Field(1, "context", "message", message=CONTEXT),
        Field(2, "timestamp_micros", "int64"),
        Field(3, "pose", "message", message=TRANSFORM),
        Field(4, "images", "message", repeated=True, message=CAMERA_IMAGE),
        Field(6, "laser_labels", "message", repeated=True, message=LABEL),
    ),
)
#: The top-level fields that tell a ``Frame`` from a ``Scenario`` by wire type (``timestamp_micros`` is a varint
#: where ``Scenario.tracks`` is a message); for source detection with ``common.first_record_has``.
FRAME_SIGNATURE = MessageSchema(
    "Frame",
    (Field(1, "context", "message", message=MessageSchema("Context", ())), Field(2, "timestamp_micros", "int64")),
)


@dataclass(frozen=True)
class WaymoCalibration:
    """One camera's calibration.

    Attributes:
        name: lower-case camera name (``"front"``, ``"side_left"``, ...).
        intrinsic: ``[9]`` float64 ``f_u, f_v, c_u, c_v, k1, k2, p1, p2, k3``.
        extrinsic: ``[4, 4]`` float64 camera (x fwd, y left, z up) -> vehicle transform.
        width, height: image size in pixels.
    """

    name: str
    intrinsic: np.ndarray
    extrinsic: np.ndarray
    width: int
    height: int


@dataclass(frozen=True)
class WaymoImage:
    """One camera image record. ``pose`` is the ``[4, 4]`` vehicle->global pose at capture (or None)."""

    name: str
    jpeg: bytes
    pose: np.ndarray | None
    pose_timestamp: float | None


@dataclass(frozen=True)
class WaymoLabel:
    """One 3D laser label, box in the vehicle frame of its frame.

    Attributes:
        object_id: tracking id (stable across frames of a segment).
        type_id: ``Label.Type`` enum value.
        center: ``[3]`` float64 box centre (vehicle frame).
        size: ``[3]`` float64 length (x), width (y), height (z).
        heading: yaw in the vehicle frame, radians.
        speed_xy: ``[2]`` float64 ``metadata.speed_x/y`` in m/s, or ``None`` when absent.
        num_lidar_points: ``num_lidar_points_in_box``, or ``None`` when absent.
    """

    object_id: str
    type_id: int
    center: np.ndarray
    size: np.ndarray
    heading: float
    speed_xy: np.ndarray | None
    num_lidar_points: int | None


@dataclass(frozen=True)
class WaymoFrame:
    """The decoded subset of one ``Frame``.

    Attributes:
        context_name: segment name shared by all frames of a run.
        timestamp_us: ``timestamp_micros``.
        pose: ``[4, 4]`` float64 vehicle -> global.
        calibrations: per camera, keyed by camera name.
        images: camera images in file order.
        labels: laser labels in file order.
        stats: ``time_of_day`` / ``location`` / ``weather`` strings where present.
    """

    context_name: str
    timestamp_us: int
    pose: np.ndarray
    calibrations: dict[str, WaymoCalibration]
    images: tuple[WaymoImage, ...]
    labels: tuple[WaymoLabel, ...]
    stats: dict[str, str] = field(default_factory=dict)


def _require(value: Any, path: str) -> Any:
    if value is None:
        raise ProtoDecodeError(path, -1, "required field is missing")
    return value


def _transform(msg: dict[str, Any] | None, path: str) -> np.ndarray:
    values = _require(msg, path)["transform"]
    if values.shape != (16,):
        raise ProtoDecodeError(f"{path}.transform", -1, f"expected 16 values, got {values.shape[0]}")
    if not np.all(np.isfinite(values)):
        raise ProtoDecodeError(f"{path}.transform", -1, "non-finite values")
    return values.reshape(4, 4).copy()


def _camera_name(value: int | None, path: str) -> str:
    name = CAMERA_NAMES.get(_require(value, path))
    if name is None:
        raise ProtoDecodeError(path, -1, f"unknown camera enum {value}")
    return name


def _calibration(msg: dict[str, Any], path: str) -> WaymoCalibration:
    intrinsic = msg["intrinsic"]
    if intrinsic.shape != (9,):
        raise ProtoDecodeError(f"{path}.intrinsic", -1, f"expected 9 values, got {intrinsic.shape[0]}")
    width, height = _require(msg["width"], f"{path}.width"), _require(msg["height"], f"{path}.height")
    if width <= 0 or height <= 0:
        raise ProtoDecodeError(f"{path}.width", -1, f"bad image size {width}x{height}")
    return WaymoCalibration(
        name=_camera_name(msg["name"], f"{path}.name"),
        intrinsic=intrinsic.copy(),
        extrinsic=_transform(msg["extrinsic"], f"{path}.extrinsic"),
        width=int(width),
        height=int(height),
    )


def _label(msg: dict[str, Any], path: str) -> WaymoLabel:
    box = _require(msg["box"], f"{path}.box")
    values = []
    for key in ("center_x", "center_y", "center_z", "length", "width", "height", "heading"):
        values.append(float(_require(box[key], f"{path}.box.{key}")))
    if not np.all(np.isfinite(values)):
        raise ProtoDecodeError(f"{path}.box", -1, f"non-finite box values {values}")
    meta = msg["metadata"]
    speed = None
    if meta is not None and meta["speed_x"] is not None and meta["speed_y"] is not None:
        speed = np.array([meta["speed_x"], meta["speed_y"]], dtype=np.float64)
    object_id = _require(msg["id"], f"{path}.id")
    if not object_id:
        raise ProtoDecodeError(f"{path}.id", -1, "empty tracking id")
    return WaymoLabel(
        object_id=object_id,
        type_id=int(msg["type"] or 0),
        center=np.array(values[:3]),
        size=np.array(values[3:6]),
        heading=values[6],
        speed_xy=speed,
        num_lidar_points=msg["num_lidar_points_in_box"],
    )


def parse_frame(data: bytes) -> WaymoFrame:
    """Decode one serialized ``Frame``.

    Raises:
        ProtoDecodeError: malformed bytes or a required field (context name, pose, calibration,
            box) missing; ``field_path`` names it.
    """
    msg = decode_message(data, FRAME)
    context = _require(msg["context"], "Frame.context")
    calibrations: dict[str, WaymoCalibration] = {}
    for i, cal_msg in enumerate(context["camera_calibrations"]):
        cal = _calibration(cal_msg, f"Frame.context.camera_calibrations[{i}]")
        calibrations[cal.name] = cal
    images = []
    for i, img in enumerate(msg["images"]):
        path = f"Frame.images[{i}]"
        images.append(
            WaymoImage(
                name=_camera_name(img["name"], f"{path}.name"),
                jpeg=_require(img["image"], f"{path}.image"),
                pose=_transform(img["pose"], f"{path}.pose") if img["pose"] is not None else None,
                pose_timestamp=img["pose_timestamp"],
            )
        )
    stats = {k: v for k, v in (context["stats"] or {}).items() if v}
    return WaymoFrame(
        context_name=_require(context["name"], "Frame.context.name"),
        timestamp_us=int(_require(msg["timestamp_micros"], "Frame.timestamp_micros")),
        pose=_transform(msg["pose"], "Frame.pose"),
        calibrations=calibrations,
        images=tuple(images),
        labels=tuple(_label(m, f"Frame.laser_labels[{i}]") for i, m in enumerate(msg["laser_labels"])),
        stats=stats,
    )
