"""Argoverse 2 sensor log directory -> ``SceneLog`` (annotations, poses, calibration, vector map).

Inputs (inside ``log_dir``): ``annotations.feather``, ``city_SE3_egovehicle.feather``,
``calibration/intrinsics.feather``, ``calibration/egovehicle_SE3_sensor.feather`` and
``map/log_map_archive*.json``. Images and lidar are not read.

Conventions of the result:

* frames = the sorted unique annotation (lidar sweep) timestamps; ``timestamp_us = ns // 1000``;
* ego pose of a frame = ``city_SE3_egovehicle`` row at that timestamp (exact, else the nearest
  within ``MAX_POSE_GAP_NS``); world frame = first frame's ego pose (``ego_poses[0]`` = identity);
* cameras: one ``CameraImage`` with ``image=None`` per ring camera and frame. AV2 camera frames are
  already OpenCV (x right, y down, z forward; checked on ``ring_front_center``: its z axis is ego +x),
  so ``cam_to_world = world_from_ego(frame) @ egovehicle_SE3_sensor``. The poses use the *lidar
  sweep* timestamps (camera shutter times differ by up to ~50 ms); ``K`` is pinhole, the radial
  coefficients are in ``metadata["distortion"]`` (JSON, ``p1 = p2 = 0``);
* boxes: annotation cuboids (ego frame of their sweep) moved to the world frame; heading = world yaw
  of the box x-axis; speed = horizontal finite differences of the world centres over time;
  ``visible`` = projects into a ring camera (occlusion ignored) and ``num_interior_pts > 0``;
* categories mapped by ``AV2_CATEGORIES`` (unknown names -> ``"other"``), the AV2 name kept in
  ``attributes["av2_category"]``; ``instance_id`` 1..N by first appearance (frame, then uuid);
* map: see ``av2_map``.
"""

from __future__ import annotations

import collections
import json
import logging
import re
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from simsplat_core.data.arrow_columns import read_columns
from simsplat_core.data.av2_map import find_map_archive, load_av2_map
from simsplat_core.data.common import BoxObservation, boxes_visible, build_track, loaded, safe_seq_id
from simsplat_core.data.errors import CorruptLogError
from simsplat_core.geometry import invert_transform, quat_wxyz_to_matrix, yaw_of_rotation
from simsplat_core.types import CameraImage, ObjectInfo, SceneLog, Track, node_type_for_category, split_for_frame

logger = logging.getLogger(__name__)

RING_CAMERAS: tuple[str, ...] = (
    "ring_front_center",
    "ring_front_left",
    "ring_front_right",
    "ring_side_left",
    "ring_side_right",
    "ring_rear_left",
    "ring_rear_right",
)
#: Largest accepted gap between an annotation sweep and the nearest ego pose.
MAX_POSE_GAP_NS = 50_000_000

_VEHICLES = (
    "REGULAR_VEHICLE LARGE_VEHICLE BUS BOX_TRUCK TRUCK TRUCK_CAB VEHICULAR_TRAILER SCHOOL_BUS "
    "ARTICULATED_BUS MESSAGE_BOARD_TRAILER RAILED_VEHICLE"
)
#: AV2 annotation category -> shared category.
AV2_CATEGORIES: dict[str, str] = {
    **{name: "vehicle" for name in _VEHICLES.split()},
    "PEDESTRIAN": "pedestrian",
    "OFFICIAL_SIGNALER": "pedestrian",
    **{name: "cyclist" for name in ("BICYCLIST", "BICYCLE", "MOTORCYCLIST", "MOTORCYCLE", "WHEELED_RIDER")},
    **{name: "static" for name in ("BOLLARD", "CONSTRUCTION_CONE", "CONSTRUCTION_BARREL")},
    **{name: "sign" for name in ("SIGN", "STOP_SIGN", "MOBILE_PEDESTRIAN_CROSSING_SIGN")},
    **{name: "other" for name in ("WHEELED_DEVICE", "WHEELCHAIR", "STROLLER", "DOG", "ANIMAL")},
}

_POSE_COLUMNS = ("qw", "qx", "qy", "qz", "tx_m", "ty_m", "tz_m")
_MAP_NAME = re.compile(r"log_map_archive_(?P<log>.+?)____(?P<city>[A-Za-z]+)_city_(?P<city_id>\d+)\.json$")


def is_av2_sensor_log(path: Path) -> bool:
    """Whether ``path`` is an AV2 sensor-log directory (``annotations.feather`` and ``city_SE3_egovehicle.feather``
    in it; log-source detection)."""
    return (path / "annotations.feather").is_file() and (path / "city_SE3_egovehicle.feather").is_file()


def poses_from_columns(cols: dict[str, np.ndarray]) -> np.ndarray:
    """``[N, 4, 4]`` transforms from quaternion ``qw..qz`` and ``tx_m..tz_m`` columns (``[N]`` each)."""
    quat = np.stack([cols["qw"], cols["qx"], cols["qy"], cols["qz"]], axis=1)
    out = np.tile(np.eye(4), (quat.shape[0], 1, 1))
    out[:, :3, :3] = quat_wxyz_to_matrix(quat)
    out[:, :3, 3] = np.stack([cols["tx_m"], cols["ty_m"], cols["tz_m"]], axis=1)
    return out


def _check_quaternions(path: Path, cols: dict[str, np.ndarray]) -> None:
    norm = np.sqrt(sum(cols[c] ** 2 for c in ("qw", "qx", "qy", "qz")))
    bad = np.flatnonzero(np.abs(norm - 1.0) > 1e-3)
    if bad.size:
        raise CorruptLogError(path, "column 'qw'", f"quaternion in row {bad[0]} has norm {norm[bad[0]]:.6f}, not 1")


def _ego_poses_at(path: Path, timestamps_ns: np.ndarray) -> np.ndarray:
    """``[F, 4, 4]`` city_SE3_egovehicle at each of the ``[F]`` timestamps (nearest row)."""
    cols = read_columns(path, float_columns=_POSE_COLUMNS, int_columns=("timestamp_ns",))
    _check_quaternions(path, cols)
    order = np.argsort(cols["timestamp_ns"], kind="stable")
    pose_ts = cols["timestamp_ns"][order]
    if pose_ts.size == 0:
        raise CorruptLogError(path, "column 'timestamp_ns'", "no ego poses")
    right = np.clip(np.searchsorted(pose_ts, timestamps_ns), 0, pose_ts.size - 1)
    left = np.clip(right - 1, 0, pose_ts.size - 1)
    nearest = np.where(np.abs(pose_ts[left] - timestamps_ns) <= np.abs(pose_ts[right] - timestamps_ns), left, right)
    gap = np.abs(pose_ts[nearest] - timestamps_ns)
    worst = int(np.argmax(gap))
    if gap[worst] > MAX_POSE_GAP_NS:
        raise CorruptLogError(
            path,
            "column 'timestamp_ns'",
            f"no ego pose within {MAX_POSE_GAP_NS / 1e6:.0f} ms of sweep {timestamps_ns[worst]}",
        )
    return poses_from_columns(cols)[order[nearest]]


@dataclass(frozen=True)
class RingCamera:
    """Calibration of one AV2 camera.

    Attributes:
        K: ``[3, 3]`` pinhole intrinsics.
        ego_from_cam: ``[4, 4]`` camera (OpenCV axes) -> ego vehicle transform.
        width, height: image size in pixels.
        distortion: ``k1, k2, p1, p2, k3`` (AV2 has radial terms only, so ``p1 = p2 = 0``).
    """

    K: np.ndarray
    ego_from_cam: np.ndarray
    width: int
    height: int
    distortion: dict[str, float]


def read_ring_cameras(calib_dir: str | Path) -> dict[str, RingCamera]:
    """The 7 ring cameras of ``calibration/intrinsics.feather`` + ``egovehicle_SE3_sensor.feather``.

    Raises:
        CorruptLogError: a file, column or ring-camera row is missing or malformed.
    """
    calib_dir = Path(calib_dir)
    intr_path = calib_dir / "intrinsics.feather"
    intr = read_columns(
        intr_path,
        float_columns=("fx_px", "fy_px", "cx_px", "cy_px", "k1", "k2", "k3"),
        int_columns=("width_px", "height_px"),
        str_columns=("sensor_name",),
    )
    extr_path = calib_dir / "egovehicle_SE3_sensor.feather"
    extr = read_columns(extr_path, float_columns=_POSE_COLUMNS, str_columns=("sensor_name",))
    _check_quaternions(extr_path, extr)
    intr_row = {name: i for i, name in enumerate(intr["sensor_name"])}
    extr_row = {name: i for i, name in enumerate(extr["sensor_name"])}
    extr_poses = poses_from_columns(extr)
    cameras = {}
    for cam in RING_CAMERAS:
        if cam not in intr_row:
            raise CorruptLogError(intr_path, "column 'sensor_name'", f"no row for camera {cam!r}")
        if cam not in extr_row:
            raise CorruptLogError(extr_path, "column 'sensor_name'", f"no row for camera {cam!r}")
        i = intr_row[cam]
        fx, fy, cx, cy = (float(intr[c][i]) for c in ("fx_px", "fy_px", "cx_px", "cy_px"))
        width, height = int(intr["width_px"][i]), int(intr["height_px"][i])
        if width <= 0 or height <= 0 or fx <= 0 or fy <= 0:
            raise CorruptLogError(intr_path, "column 'fx_px'", f"camera {cam!r} has a bad size or focal length")
        cameras[cam] = RingCamera(
            K=np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]]),
            ego_from_cam=extr_poses[extr_row[cam]],
            width=width,
            height=height,
            distortion={
                "k1": float(intr["k1"][i]),
                "k2": float(intr["k2"][i]),
                "p1": 0.0,
                "p2": 0.0,
                "k3": float(intr["k3"][i]),
            },
        )
    return cameras


def _tracks_and_objects(
    ann_path: Path,
    ann: dict[str, np.ndarray],
    row_frame: np.ndarray,
    centers: np.ndarray,
    sizes: np.ndarray,
    headings: np.ndarray,
    visible: np.ndarray,
    timestamps_us: np.ndarray,
) -> tuple[tuple[Track, ...], tuple[ObjectInfo, ...]]:
    """Group the ``[N]`` annotation rows (world ``centers [N, 3]``, ``sizes [N, 3]``, ``headings [N]``,
    ``visible [N]``, frame of each row ``row_frame [N]``) into tracks; ``instance_id`` by first appearance."""
    by_track: dict[str, list[int]] = collections.defaultdict(list)
    for row, uuid in enumerate(ann["track_uuid"]):
        by_track[uuid].append(row)
    first_seen = {uuid: (int(row_frame[rows].min()), uuid) for uuid, rows in by_track.items()}
    order = sorted(by_track, key=lambda uuid: first_seen[uuid])
    tracks, objects = [], []
    for instance_id, uuid in enumerate(order, start=1):
        rows = np.array(by_track[uuid])
        frames = row_frame[rows]
        if np.unique(frames).size != frames.size:
            raise CorruptLogError(ann_path, "column 'track_uuid'", f"track {uuid} has two cuboids at one timestamp")
        obs = [
            BoxObservation(int(row_frame[r]), centers[r], sizes[r], float(headings[r]), float("nan"), bool(visible[r]))
            for r in rows
        ]
        tracks.append(build_track(uuid, obs, timestamps_us))
        votes = collections.Counter(ann["category"][rows])
        av2_category = votes.most_common(1)[0][0]
        if len(votes) > 1:
            logger.warning("%s: track %s has categories %s; using %s", ann_path, uuid, dict(votes), av2_category)
        category = AV2_CATEGORIES.get(av2_category, "other")
        objects.append(
            ObjectInfo(
                object_id=uuid,
                category=category,
                node_type=node_type_for_category(category),
                instance_id=instance_id,
                attributes={
                    "av2_category": av2_category,
                    "num_interior_pts_max": str(int(ann["num_interior_pts"][rows].max())),
                },
            )
        )
    return tuple(tracks), tuple(objects)


def _camera_images(rig: dict[str, RingCamera], ego_poses: np.ndarray, timestamps_us: np.ndarray) -> list[CameraImage]:
    """Image-less ``CameraImage`` s, frame-major then ``RING_CAMERAS`` order; ``ego_poses`` is ``[F, 4, 4]``."""
    images = []
    for f in range(timestamps_us.size):
        for cam in RING_CAMERAS:
            images.append(
                CameraImage(
                    frame_idx=f,
                    timestamp_us=int(timestamps_us[f]),
                    camera=cam,
                    K=rig[cam].K,
                    cam_to_world=ego_poses[f] @ rig[cam].ego_from_cam,
                    width=rig[cam].width,
                    height=rig[cam].height,
                    split=split_for_frame(f),
                )
            )
    return images


def load_av2_log(log_dir: str | Path, seq_id: str | None = None) -> SceneLog:
    """Load one Argoverse 2 sensor log directory as a ``SceneLog`` (see module docstring).

    Args:
        log_dir: directory holding ``annotations.feather``, ``city_SE3_egovehicle.feather``,
            ``calibration/`` and ``map/``.
        seq_id: sequence id; default: the directory name made directory-safe.

    Returns:
        A validated ``SceneLog`` (``source="av2"``) with image-less ``CameraImage`` s for the 7 ring
        cameras at every annotated sweep.

    Raises:
        CorruptLogError: a file is missing or unreadable, a required column / JSON field is missing
            or malformed; the message names the file and the column or field.
    """
    log_dir = Path(log_dir)
    if not log_dir.is_dir():
        raise FileNotFoundError(f"AV2 log directory not found: {log_dir}")
    t0 = time.perf_counter()
    ann_path = log_dir / "annotations.feather"
    ann = read_columns(
        ann_path,
        float_columns=("length_m", "width_m", "height_m", *_POSE_COLUMNS),
        int_columns=("timestamp_ns", "num_interior_pts"),
        str_columns=("track_uuid", "category"),
    )
    _check_quaternions(ann_path, ann)
    if ann["timestamp_ns"].size == 0:
        raise CorruptLogError(ann_path, "column 'timestamp_ns'", "no annotations")
    sizes = np.stack([ann["length_m"], ann["width_m"], ann["height_m"]], axis=1)  # [N, 3]
    bad_row, bad_col = np.nonzero(sizes <= 0)
    if bad_row.size:
        column = ("length_m", "width_m", "height_m")[int(bad_col[0])]
        raise CorruptLogError(ann_path, f"column {column!r}", f"non-positive box size in row {int(bad_row[0])}")
    frame_ts_ns, row_frame = np.unique(ann["timestamp_ns"], return_inverse=True)
    timestamps_us = frame_ts_ns // 1000

    city_from_ego = _ego_poses_at(log_dir / "city_SE3_egovehicle.feather", frame_ts_ns)  # [F, 4, 4]
    world_from_city = invert_transform(city_from_ego[0])
    ego_poses = world_from_city @ city_from_ego
    ego_poses[0] = np.eye(4)

    # Boxes in the world frame, vectorised over all rows.
    world_from_box = ego_poses[row_frame] @ poses_from_columns(ann)  # [N, 4, 4]
    centers = world_from_box[:, :3, 3]
    headings = yaw_of_rotation(world_from_box[:, :3, :3])

    rig = read_ring_cameras(log_dir / "calibration")
    images = _camera_images(rig, ego_poses, timestamps_us)
    visible = np.zeros(row_frame.size, dtype=bool)
    for f in range(frame_ts_ns.size):
        rows = np.flatnonzero(row_frame == f)
        visible[rows] = boxes_visible(
            centers[rows], sizes[rows], headings[rows], images[f * len(RING_CAMERAS) : (f + 1) * len(RING_CAMERAS)]
        )
    visible &= ann["num_interior_pts"] > 0

    tracks, objects = _tracks_and_objects(ann_path, ann, row_frame, centers, sizes, headings, visible, timestamps_us)

    map_path = find_map_archive(log_dir / "map")
    map_features = load_av2_map(map_path, world_from_city)
    metadata = {
        "source_dir": str(log_dir),
        "log_id": log_dir.name,
        "map_file": map_path.name,
        "distortion": json.dumps({cam: rig[cam].distortion for cam in RING_CAMERAS}, sort_keys=True),
        "distortion_model": "opencv (k1, k2, p1, p2, k3); AV2 gives radial k1, k2, k3 only; not undistorted",
        "camera_pose": "ego pose at the lidar sweep timestamp (not the camera shutter time)",
        "city_SE3_world": json.dumps(city_from_ego[0].round(9).tolist()),
    }
    match = _MAP_NAME.search(map_path.name)
    if match:
        metadata["log_id"] = match.group("log")
        metadata["city_name"] = match.group("city")
        metadata["city_id"] = match.group("city_id")
    log = SceneLog(
        seq_id=seq_id if seq_id is not None else safe_seq_id(log_dir.name),
        source="av2",
        timestamps_us=timestamps_us.astype(np.int64),
        ego_poses=ego_poses,
        images=tuple(images),
        tracks=tracks,
        objects=objects,
        map_features=tuple(map_features),
        metadata=metadata,
    )
    return loaded(log, log_dir, t0)
