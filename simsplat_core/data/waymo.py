"""Waymo Open Dataset ``Frame`` TFRecords -> ``SceneLog``.

One file of N ``Frame`` records (usually one segment) becomes one ``SceneLog`` of N frames, sorted by
``timestamp_micros``. Conventions of the result:

* world frame = vehicle pose of the first frame (``ego_poses[0]`` is the identity);
* ``CameraImage.cam_to_world`` is OpenCV-style:
  ``inv(pose_0) @ vehicle_to_global @ extrinsic @ [[CV_TO_SENSOR, 0], [0, 1]]`` where
  ``vehicle_to_global`` is the image's own ``CameraImage.pose`` (the vehicle pose at capture time)
  when present, else ``Frame.pose``; ``timestamp_us`` of every image is the frame's timestamp;
* ``K`` is the pinhole part of Waymo's intrinsics (``f_u, f_v, c_u, c_v``). Lens distortion is
  *not* removed from the pixels: the coefficients go to ``metadata["distortion"]`` as JSON
  ``{camera: {"k1", "k2", "p1", "p2", "k3"}}`` (OpenCV's model). Near the image corners the
  pinhole projection is off by a few pixels;
* with ``image_scale != 1`` images are resized with ``cv2.INTER_AREA`` and ``K`` scaled with it
  (pixel-centre convention: ``c' = (c + 0.5) * s - 0.5``);
* boxes: laser labels (vehicle frame of their frame) moved to the world frame; heading is the yaw
  of the box x-axis in the world frame; ``speed`` is ``|metadata.speed_x, speed_y|`` when present,
  else finite differences over frames (0 for a single observation);
* ``Track.visible`` = the box projects into at least one camera image of that frame (occlusion
  ignored) *and* the label has ``num_lidar_points_in_box > 0`` (when that field is present);
* categories: VEHICLE -> vehicle, PEDESTRIAN -> pedestrian, SIGN -> sign, CYCLIST -> cyclist,
  UNKNOWN -> other; ``instance_id`` 1..N by first appearance (frame, then tracking id).
"""

from __future__ import annotations

import collections
import json
import logging
import os
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import cv2
import numpy as np

from simsplat_core.data.common import (
    BoxObservation,
    boxes_visible,
    build_track,
    first_record_has,
    loaded,
    parse_tfrecords,
    safe_seq_id,
)
from simsplat_core.data.errors import CorruptLogError
from simsplat_core.data.waymo_proto import (
    CAMERA_NAMES,
    FRAME_SIGNATURE,
    LABEL_TYPES,
    WaymoCalibration,
    WaymoFrame,
    parse_frame,
)
from simsplat_core.geometry import CV_TO_SENSOR, invert_transform, make_transform, yaw_matrix, yaw_of_rotation
from simsplat_core.types import CameraImage, ObjectInfo, SceneLog, Track, node_type_for_category, split_for_frame

logger = logging.getLogger(__name__)

#: ``Label.Type`` enum -> shared category.
WAYMO_CATEGORIES: dict[int, str] = {0: "other", 1: "vehicle", 2: "pedestrian", 3: "sign", 4: "cyclist"}

_CV_TO_SENSOR_4 = make_transform(CV_TO_SENSOR, np.zeros(3))


def is_waymo_frame_file(path: Path) -> bool:
    """Whether ``path`` is a TFRecord file whose first record is a Waymo ``Frame`` (log-source detection)."""
    return path.is_file() and first_record_has(path, FRAME_SIGNATURE, "timestamp_micros")


def scaled_intrinsics(intrinsic: np.ndarray, sx: float, sy: float) -> np.ndarray:
    """``[3, 3]`` pinhole K from Waymo's ``[9]`` intrinsic, scaled by ``(sx, sy)`` (pixel centres kept)."""
    fu, fv, cu, cv = (float(v) for v in intrinsic[:4])
    return np.array([[fu * sx, 0.0, (cu + 0.5) * sx - 0.5], [0.0, fv * sy, (cv + 0.5) * sy - 0.5], [0.0, 0.0, 1.0]])


def decode_jpeg(jpeg: bytes, expected_size: tuple[int, int], out_size: tuple[int, int]) -> np.ndarray:
    """JPEG bytes -> ``[H, W, 3]`` float32 RGB in [0, 1].

    Args:
        jpeg: encoded image.
        expected_size: ``(width, height)`` the calibration promises for the encoded image.
        out_size: ``(width, height)`` of the result; resized with ``cv2.INTER_AREA`` when different.

    Raises:
        ValueError: the bytes do not decode, or decode to another size than ``expected_size``.
    """
    bgr = cv2.imdecode(np.frombuffer(jpeg, dtype=np.uint8), cv2.IMREAD_COLOR)
    if bgr is None:
        raise ValueError(f"{len(jpeg)} bytes do not decode as an image")
    if (bgr.shape[1], bgr.shape[0]) != tuple(expected_size):
        raise ValueError(
            f"image is {bgr.shape[1]}x{bgr.shape[0]}, calibration says {expected_size[0]}x{expected_size[1]}"
        )
    if tuple(out_size) != tuple(expected_size):
        bgr = cv2.resize(bgr, tuple(out_size), interpolation=cv2.INTER_AREA)
    rgb = cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)
    return rgb.astype(np.float32) * np.float32(1.0 / 255.0)


def _camera_images(
    path: Path,
    record_index: int,
    frame_idx: int,
    frame: WaymoFrame,
    world_from_global: np.ndarray,
    image_scale: float,
    pool: ThreadPoolExecutor,
) -> list[CameraImage]:
    """Decoded, calibrated ``CameraImage`` s of one frame in camera-enum order.

    ``world_from_global`` is ``[4, 4]``; JPEGs are decoded in parallel on ``pool`` (OpenCV releases
    the GIL while decoding).
    """
    camera_rank = {name: rank for rank, name in enumerate(CAMERA_NAMES.values())}
    jobs = []
    for i, img in sorted(enumerate(frame.images), key=lambda item: camera_rank[item[1].name]):
        where = f"record {record_index}, field 'Frame.images[{i}]"
        cal: WaymoCalibration | None = frame.calibrations.get(img.name)
        if cal is None:
            raise CorruptLogError(
                path, f"{where}.name'", f"no camera calibration for camera {img.name!r}", record_index=record_index
            )
        size = (max(1, int(round(cal.width * image_scale))), max(1, int(round(cal.height * image_scale))))
        jobs.append((where, img, cal, size, pool.submit(decode_jpeg, img.jpeg, (cal.width, cal.height), size)))
    images = []
    for where, img, cal, (width, height), future in jobs:
        try:
            pixels = future.result()
        except ValueError as exc:
            raise CorruptLogError(path, f"{where}.image'", str(exc), record_index=record_index) from exc
        vehicle_to_global = img.pose if img.pose is not None else frame.pose
        images.append(
            CameraImage(
                frame_idx=frame_idx,
                timestamp_us=frame.timestamp_us,
                camera=img.name,
                K=scaled_intrinsics(cal.intrinsic, width / cal.width, height / cal.height),
                cam_to_world=world_from_global @ vehicle_to_global @ cal.extrinsic @ _CV_TO_SENSOR_4,
                width=width,
                height=height,
                image=pixels,
                split=split_for_frame(frame_idx),
            )
        )
    return images


def _world_box(world_from_vehicle: np.ndarray, center: np.ndarray, heading: float) -> tuple[np.ndarray, float]:
    """World centre ``[3]`` and world yaw of a box given in a vehicle frame (``[4, 4]`` pose)."""
    center_w = world_from_vehicle[:3, :3] @ center + world_from_vehicle[:3, 3]
    heading_w = float(yaw_of_rotation(world_from_vehicle[:3, :3] @ yaw_matrix(heading)))
    return center_w, heading_w


class _LabelCollector:
    """Accumulates laser labels frame by frame, then builds tracks and objects."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.observations: dict[str, list[BoxObservation]] = collections.defaultdict(list)
        self.type_votes: dict[str, collections.Counter[int]] = collections.defaultdict(collections.Counter)
        self.max_points: dict[str, int] = {}
        self.first_seen: dict[str, tuple[int, str]] = {}

    def add_frame(
        self,
        record_index: int,
        frame_idx: int,
        frame: WaymoFrame,
        world_from_vehicle: np.ndarray,
        cameras: list[CameraImage],
    ) -> None:
        """Add the labels of one frame; ``world_from_vehicle`` is its ``[4, 4]`` ego pose."""
        world_boxes = [_world_box(world_from_vehicle, label.center, label.heading) for label in frame.labels]
        in_view = boxes_visible(
            np.array([c for c, _ in world_boxes]).reshape(-1, 3),
            np.array([label.size for label in frame.labels]).reshape(-1, 3),
            np.array([h for _, h in world_boxes]),
            cameras,
        )
        seen_here: set[str] = set()
        for i, label in enumerate(frame.labels):
            oid = label.object_id
            if oid in seen_here:
                raise CorruptLogError(
                    self.path,
                    f"record {record_index}, field 'Frame.laser_labels[{i}].id'",
                    f"tracking id {oid!r} appears twice in one frame",
                    record_index=record_index,
                )
            seen_here.add(oid)
            visible = bool(in_view[i])
            if label.num_lidar_points is not None:
                visible = visible and label.num_lidar_points > 0
                self.max_points[oid] = max(self.max_points.get(oid, 0), label.num_lidar_points)
            speed = float(np.hypot(*label.speed_xy)) if label.speed_xy is not None else float("nan")
            center_w, heading_w = world_boxes[i]
            self.observations[oid].append(BoxObservation(frame_idx, center_w, label.size, heading_w, speed, visible))
            self.type_votes[oid][label.type_id] += 1
            self.first_seen.setdefault(oid, (frame_idx, oid))

    def finish(self, timestamps_us: np.ndarray) -> tuple[tuple[Track, ...], tuple[ObjectInfo, ...]]:
        """Tracks and objects, ``instance_id`` 1..N by first appearance (frame, then id)."""
        order = sorted(self.first_seen, key=lambda oid: self.first_seen[oid])
        tracks = tuple(build_track(oid, self.observations[oid], timestamps_us) for oid in order)
        objects = []
        for instance_id, oid in enumerate(order, start=1):
            votes = self.type_votes[oid]
            type_id = votes.most_common(1)[0][0]
            if len(votes) > 1:
                logger.warning(
                    "%s: object %s changes type across frames %s; using %s", self.path, oid, dict(votes), type_id
                )
            category = WAYMO_CATEGORIES.get(type_id, "other")
            attributes = {"waymo_type": LABEL_TYPES.get(type_id, str(type_id))}
            if oid in self.max_points:
                attributes["num_lidar_points_max"] = str(self.max_points[oid])
            objects.append(
                ObjectInfo(
                    object_id=oid,
                    category=category,
                    node_type=node_type_for_category(category),
                    instance_id=instance_id,
                    attributes=attributes,
                )
            )
        return tracks, tuple(objects)


def load_waymo_frames(path: str | Path, image_scale: float = 1.0, seq_id: str | None = None) -> SceneLog:
    """Load a Waymo Open Dataset ``Frame`` TFRecord file as one ``SceneLog`` (see module docstring).

    Args:
        path: TFRecord file of N ``Frame`` records of one segment.
        image_scale: resize factor for images (and ``K``), e.g. 0.5; must be > 0.
        seq_id: sequence id; default: the segment's ``context.name`` made directory-safe.

    Returns:
        A validated ``SceneLog`` of N frames (``source="waymo"``), images decoded to float32 RGB.
        Memory: about 29 MB per full-size 1920x1280 image.

    Raises:
        CorruptLogError: truncated file, CRC mismatch, malformed proto, missing required field,
            undecodable JPEG, mixed segments or duplicate timestamps; names file, record and field.
    """
    if not image_scale > 0:
        raise ValueError(f"image_scale must be > 0, got {image_scale}")
    path = Path(path)
    t0 = time.perf_counter()
    records = parse_tfrecords(path, parse_frame)
    names = {frame.context_name for _, frame in records}
    if len(names) > 1:
        raise CorruptLogError(path, "field 'Frame.context.name'", f"records mix segments {sorted(names)}")
    records.sort(key=lambda rf: rf[1].timestamp_us)
    timestamps = np.array([frame.timestamp_us for _, frame in records], dtype=np.int64)
    dup = np.flatnonzero(np.diff(timestamps) <= 0)
    if dup.size:
        rec = records[int(dup[0]) + 1][0]
        raise CorruptLogError(
            path,
            f"record {rec}, field 'Frame.timestamp_micros'",
            f"duplicate timestamp {timestamps[dup[0]]}",
            record_index=rec,
        )
    world_from_global = invert_transform(records[0][1].pose)
    ego_poses = np.stack([world_from_global @ frame.pose for _, frame in records])
    ego_poses[0] = np.eye(4)

    images: list[CameraImage] = []
    labels = _LabelCollector(path)
    with ThreadPoolExecutor(max_workers=min(8, os.cpu_count() or 1), thread_name_prefix="waymo-jpeg") as pool:
        for frame_idx, (record_index, frame) in enumerate(records):
            frame_images = _camera_images(path, record_index, frame_idx, frame, world_from_global, image_scale, pool)
            images.extend(frame_images)
            labels.add_frame(record_index, frame_idx, frame, ego_poses[frame_idx], frame_images)
    tracks, objects = labels.finish(timestamps)

    first = records[0][1]
    distortion = {
        name: dict(zip(("k1", "k2", "p1", "p2", "k3"), (float(v) for v in cal.intrinsic[4:9])))
        for name, cal in sorted(first.calibrations.items())
    }
    metadata = {
        "source_file": str(path),
        "context_name": first.context_name,
        "num_records": str(len(records)),
        "image_scale": repr(float(image_scale)),
        "distortion": json.dumps(distortion, sort_keys=True),
        "distortion_model": "opencv (k1, k2, p1, p2, k3); pixels are not undistorted",
        "camera_pose": "CameraImage.pose (vehicle pose at capture) when present, else Frame.pose",
        **{f"waymo_{key}": value for key, value in sorted(first.stats.items())},
    }
    log = SceneLog(
        seq_id=seq_id if seq_id is not None else safe_seq_id(first.context_name),
        source="waymo",
        timestamps_us=timestamps,
        ego_poses=ego_poses,
        images=tuple(images),
        tracks=tracks,
        objects=objects,
        metadata=metadata,
    )
    return loaded(log, path, t0)
