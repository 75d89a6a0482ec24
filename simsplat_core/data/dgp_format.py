"""Parsing of TRI's DGP scene files (the format of the DDAD dataset) into plain records.

A DGP scene folder holds ``scene_<hash>.json`` (samples, each a list of datum keys; every datum with its
sensor's world pose), ``calibration/<key>.json`` (per sensor: pinhole intrinsics and the sensor-to-ego
extrinsic) and per datum ``bounding_box_3d/<sensor>/<time>.json`` annotations. All are JSON (protobuf's
JSON mapping); every read here names the file and the field path when something is missing or malformed.

Poses are ``{"rotation": {"qw", "qx", "qy", "qz"}, "translation": {"x", "y", "z"}}``; a missing key of a
protobuf-JSON message means its default (0, or the identity rotation ``qw = 1``).
"""

from __future__ import annotations

import datetime
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from simsplat_core.data.errors import CorruptLogError
from simsplat_core.geometry import make_transform, quat_wxyz_to_matrix

_EPOCH = datetime.datetime(1970, 1, 1, tzinfo=datetime.UTC)


def read_json(path: Path) -> dict[str, Any]:
    """The JSON object in ``path``.

    Raises:
        CorruptLogError: unreadable JSON or not an object (names the file and the parse position).
        FileNotFoundError: ``path`` does not exist.
    """
    try:
        value = json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise CorruptLogError(path, f"line {exc.lineno} column {exc.colno}", f"not valid JSON: {exc.msg}") from exc
    if not isinstance(value, dict):
        raise CorruptLogError(path, "document", f"expected a JSON object, got {type(value).__name__}")
    return value


def field(path: Path, obj: Any, where: str, key: str, kind: type | tuple[type, ...] = object) -> Any:
    """``obj[key]``, checked to be a ``kind``; errors name ``path`` and the field ``where.key``."""
    if not isinstance(obj, dict):
        raise CorruptLogError(path, f"field {where!r}", f"expected an object, got {type(obj).__name__}")
    if key not in obj:
        raise CorruptLogError(path, f"field '{where}.{key}'", "missing")
    value = obj[key]
    if not isinstance(value, kind) or (isinstance(value, bool) and kind in (int, float, (int, float))):
        raise CorruptLogError(path, f"field '{where}.{key}'", f"expected {_kind_name(kind)}, got {value!r:.60}")
    return value


def _kind_name(kind: type | tuple[type, ...]) -> str:
    return " or ".join(k.__name__ for k in kind) if isinstance(kind, tuple) else kind.__name__


def _number(path: Path, obj: dict, where: str, key: str, default: float) -> float:
    """A protobuf-JSON number field (absent = ``default``; numbers may be JSON strings)."""
    if key not in obj:
        return default
    value = obj[key]
    try:
        if isinstance(value, bool):
            raise ValueError
        number = float(value)
    except (TypeError, ValueError):
        raise CorruptLogError(path, f"field '{where}.{key}'", f"expected a number, got {value!r:.60}") from None
    if not np.isfinite(number):
        raise CorruptLogError(path, f"field '{where}.{key}'", f"not finite: {value!r}")
    return number


def parse_pose(path: Path, obj: Any, where: str) -> np.ndarray:
    """``[4, 4]`` float64 transform of a DGP ``Pose`` message at ``where`` in ``path``."""
    if not isinstance(obj, dict):
        raise CorruptLogError(path, f"field {where!r}", f"expected a pose object, got {obj!r:.60}")
    rotation = obj.get("rotation", {})
    translation = obj.get("translation", {})
    for name, part in (("rotation", rotation), ("translation", translation)):
        if not isinstance(part, dict):
            raise CorruptLogError(path, f"field '{where}.{name}'", f"expected an object, got {part!r:.60}")
    quat = np.array([_number(path, rotation, f"{where}.rotation", k, 1.0 if k == "qw" else 0.0)
                     for k in ("qw", "qx", "qy", "qz")])
    norm = float(np.linalg.norm(quat))
    if abs(norm - 1.0) > 1e-3:
        raise CorruptLogError(path, f"field '{where}.rotation'", f"quaternion norm {norm:.6f}, expected 1")
    xyz = np.array([_number(path, translation, f"{where}.translation", k, 0.0) for k in ("x", "y", "z")])
    return make_transform(quat_wxyz_to_matrix(quat / norm), xyz)


def parse_timestamp_us(path: Path, value: Any, where: str) -> int:
    """Microseconds since the epoch of an RFC 3339 timestamp (protobuf ``Timestamp`` JSON), exactly."""
    if not isinstance(value, str):
        raise CorruptLogError(path, f"field {where!r}", f"expected an RFC 3339 timestamp string, got {value!r:.60}")
    try:
        stamp = datetime.datetime.fromisoformat(value.replace("Z", "+00:00"))
    except ValueError:
        raise CorruptLogError(path, f"field {where!r}", f"not an RFC 3339 timestamp: {value!r}") from None
    if stamp.tzinfo is None:
        stamp = stamp.replace(tzinfo=datetime.UTC)
    delta = stamp - _EPOCH
    return (delta.days * 86_400 + delta.seconds) * 1_000_000 + delta.microseconds


@dataclass(frozen=True)
class DgpSensor:
    """Calibration of one sensor.

    Attributes:
        name: sensor name (``"CAMERA_01"``, ``"LIDAR"``).
        K: ``[3, 3]`` float64 pinhole intrinsics (zeros for a lidar).
        ego_from_sensor: ``[4, 4]`` float64 extrinsic (sensor frame -> ego frame).
    """

    name: str
    K: np.ndarray
    ego_from_sensor: np.ndarray


def parse_calibration(path: Path) -> dict[str, DgpSensor]:
    """``{sensor name: DgpSensor}`` of a ``calibration/<key>.json`` file (parallel ``names``, ``intrinsics``,
    ``extrinsics`` lists)."""
    doc = read_json(path)
    names = field(path, doc, "calibration", "names", list)
    intrinsics = field(path, doc, "calibration", "intrinsics", list)
    extrinsics = field(path, doc, "calibration", "extrinsics", list)
    if not len(names) == len(intrinsics) == len(extrinsics):
        raise CorruptLogError(path, "field 'calibration.names'", f"{len(names)} names, {len(intrinsics)} intrinsics "
                              f"and {len(extrinsics)} extrinsics: the lists must be parallel")
    sensors = {}
    for i, (name, intr) in enumerate(zip(names, intrinsics)):
        where = f"calibration.intrinsics[{i}]"
        if not isinstance(name, str):
            raise CorruptLogError(path, f"field 'calibration.names[{i}]'", f"expected a string, got {name!r:.60}")
        if not isinstance(intr, dict):
            raise CorruptLogError(path, f"field {where!r}", f"expected an object, got {intr!r:.60}")
        fx, fy, cx, cy, skew = (_number(path, intr, where, k, 0.0) for k in ("fx", "fy", "cx", "cy", "skew"))
        K = np.array([[fx, skew, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])
        sensors[name] = DgpSensor(name, K, parse_pose(path, extrinsics[i], f"calibration.extrinsics[{i}]"))
    return sensors


@dataclass(frozen=True)
class DgpDatum:
    """One sensor reading of a sample.

    Attributes:
        key: the datum key.
        sensor: sensor name.
        kind: ``"image"`` or ``"point_cloud"``.
        timestamp_us: capture time.
        filename: data file, relative to the scene folder.
        world_from_sensor: ``[4, 4]`` float64 sensor pose in the scene's world frame.
        annotations: ``{annotation type id: file relative to the scene folder}`` (``"1"`` = 3D boxes).
        width, height: image size (0 for point clouds).
    """

    key: str
    sensor: str
    kind: str
    timestamp_us: int
    filename: str
    world_from_sensor: np.ndarray
    annotations: dict[str, str]
    width: int = 0
    height: int = 0


@dataclass(frozen=True)
class DgpSample:
    """One sample (frame): its time, its calibration key and its datums in file order."""

    timestamp_us: int
    calibration_key: str
    datums: tuple[DgpDatum, ...]


#: Annotation type id of 3D boxes in a datum's ``annotations`` map.
BOUNDING_BOX_3D = "1"
#: Annotation type id of 2D boxes.
BOUNDING_BOX_2D = "0"


def _parse_datum(path: Path, entry: Any, where: str) -> DgpDatum:
    key = field(path, entry, where, "key", str)
    ident = field(path, entry, where, "id", dict)
    datum = field(path, entry, where, "datum", dict)
    kinds = [k for k in ("image", "point_cloud") if k in datum]
    if len(kinds) != 1:
        raise CorruptLogError(path, f"field '{where}.datum'", f"expected one of image / point_cloud, got {list(datum)}")
    kind = kinds[0]
    body = field(path, datum, f"{where}.datum", kind, dict)
    inner = f"{where}.datum.{kind}"
    annotations = body.get("annotations", {})
    if not isinstance(annotations, dict) or not all(isinstance(v, str) for v in annotations.values()):
        raise CorruptLogError(path, f"field '{inner}.annotations'", "expected a map of type id -> file name")
    width = height = 0
    if kind == "image":
        width = int(_number(path, body, inner, "width", 0))
        height = int(_number(path, body, inner, "height", 0))
        if width <= 0 or height <= 0:
            raise CorruptLogError(path, f"field '{inner}.width'", f"image size {width}x{height} is not positive")
    return DgpDatum(
        key=key,
        sensor=field(path, ident, f"{where}.id", "name", str),
        kind=kind,
        timestamp_us=parse_timestamp_us(path, ident.get("timestamp"), f"{where}.id.timestamp"),
        filename=field(path, body, inner, "filename", str),
        world_from_sensor=parse_pose(path, field(path, body, inner, "pose", dict), f"{inner}.pose"),
        annotations={str(k): v for k, v in annotations.items()},
        width=width,
        height=height,
    )


def parse_scene(path: Path) -> list[DgpSample]:
    """The samples of a ``scene_<hash>.json`` file, sorted by time, each with its datums resolved.

    Raises:
        CorruptLogError: a missing or malformed field, a datum key a sample names but ``data`` lacks, or no
            samples (names the file and the field path).
    """
    doc = read_json(path)
    entries = field(path, doc, "scene", "data", list)
    datums = {}
    for i, entry in enumerate(entries):
        datum = _parse_datum(path, entry, f"scene.data[{i}]")
        datums[datum.key] = datum
    samples = []
    for i, sample in enumerate(field(path, doc, "scene", "samples", list)):
        where = f"scene.samples[{i}]"
        keys = field(path, sample, where, "datum_keys", list)
        missing = [k for k in keys if k not in datums]
        if missing:
            raise CorruptLogError(path, f"field '{where}.datum_keys'", f"datum {missing[0]!r} is not in scene.data")
        ident = field(path, sample, where, "id", dict)
        samples.append(DgpSample(
            timestamp_us=parse_timestamp_us(path, ident.get("timestamp"), f"{where}.id.timestamp"),
            calibration_key=field(path, sample, where, "calibration_key", str),
            datums=tuple(datums[k] for k in keys),
        ))
    if not samples:
        raise CorruptLogError(path, "field 'scene.samples'", "no samples")
    samples.sort(key=lambda s: s.timestamp_us)
    return samples


@dataclass(frozen=True)
class DgpBox:
    """One 3D box annotation in its sensor's frame.

    Attributes:
        instance_id: tracking id, stable across the scene's samples.
        class_id: ontology class id.
        sensor_from_box: ``[4, 4]`` float64 box pose (box x along its length).
        size: ``[3]`` float64 length, width, height.
        num_points: lidar points inside the box (``-1`` when absent).
    """

    instance_id: int
    class_id: int
    sensor_from_box: np.ndarray
    size: np.ndarray
    num_points: int


def parse_boxes_3d(path: Path) -> list[DgpBox]:
    """The boxes of a ``bounding_box_3d/<sensor>/<time>.json`` file."""
    doc = read_json(path)
    boxes = []
    for i, ann in enumerate(field(path, doc, "annotations", "annotations", list)):
        where = f"annotations[{i}]"
        box = field(path, ann, where, "box", dict)
        size = np.array([_number(path, box, f"{where}.box", k, 0.0) for k in ("length", "width", "height")])
        if not (size > 0).all():
            raise CorruptLogError(path, f"field '{where}.box'", f"box size {size.tolist()} is not positive")
        boxes.append(DgpBox(
            instance_id=int(_number(path, ann, where, "instance_id", -1)),
            class_id=int(_number(path, ann, where, "class_id", -1)),
            sensor_from_box=parse_pose(path, field(path, box, f"{where}.box", "pose", dict), f"{where}.box.pose"),
            size=size,
            num_points=int(_number(path, ann, where, "num_points", -1)),
        ))
    return boxes


def parse_boxes_2d(path: Path) -> list[tuple[int, np.ndarray]]:
    """``(instance id, [4] x0, y0, x1, y1 pixels)`` of a ``bounding_box_2d/<camera>/<time>.json`` file."""
    doc = read_json(path)
    boxes = []
    for i, ann in enumerate(field(path, doc, "annotations", "annotations", list)):
        where = f"annotations[{i}]"
        box = field(path, ann, where, "box", dict)
        x, y, w, h = (_number(path, box, f"{where}.box", k, 0.0) for k in ("x", "y", "w", "h"))
        boxes.append((int(_number(path, ann, where, "instance_id", -1)), np.array([x, y, x + w, y + h])))
    return boxes


def parse_ontology(path: Path) -> dict[int, str]:
    """``{class id: class name}`` of an ``ontology/<key>.json`` file."""
    doc = read_json(path)
    names = {}
    for i, item in enumerate(field(path, doc, "ontology", "items", list)):
        names[int(_number(path, item, f"ontology.items[{i}]", "id", -1))] = field(
            path, item, f"ontology.items[{i}]", "name", str)
    return names
