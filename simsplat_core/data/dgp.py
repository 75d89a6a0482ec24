"""TRI DGP scenes (the DDAD dataset's format) -> ``SceneLog``.

A scene folder (``scene_<hash>.json``, ``calibration/``, ``rgb/<camera>/``, ``point_cloud/<lidar>/``,
``bounding_box_3d/``, ``ontology/``) becomes one ``SceneLog``, one frame per sample. Conventions:

* ego pose of a sample = lidar datum pose @ inverse(lidar extrinsic); world frame = the first sample's ego
  pose (``ego_poses[0]`` is the identity);
* ``CameraImage.cam_to_world`` = world-from-global @ the camera datum's own pose (DGP camera frames are
  OpenCV's: x right, y down, z forward); ``timestamp_us`` is the camera datum's own time;
* ``K`` from the calibration's pinhole intrinsics (DDAD images are rectified), scaled with ``image_scale``
  (pixel-centre convention ``c' = (c + 0.5) * s - 0.5``);
* ``CameraImage.valid_mask`` is ``False`` on the ego car's body (``ego_mask.DDAD_EGO_BODY`` by default, or
  the caller's polygons);
* held-out views: frame ``f`` holds out the camera ``f mod 6`` of the name-sorted cameras (one test view
  per frame, each camera in turn), the others train;
* boxes: the 3D boxes of the lidar datum (lidar frame) moved to the world frame; heading = world yaw of
  the box x axis; speed by finite differences; ``visible`` = projects into a camera of that frame and has
  lidar points; categories by ``DGP_CATEGORIES`` on the ontology's class names (unknown -> ``"other"``);
* depth: each camera image carries the sparse z-depth of its sample's lidar sweep (``lidar_depth``): ``nan``
  where no point lands or on the ego body (no measurement, never sky); it initialises the background.
"""

from __future__ import annotations

import collections
import dataclasses
import json
import logging
import time
from collections.abc import Sequence
from pathlib import Path

import cv2
import numpy as np

from simsplat_core.data.common import BoxObservation, boxes_visible, build_track, loaded, safe_seq_id
from simsplat_core.data.dgp_format import (
    BOUNDING_BOX_3D,
    DgpDatum,
    DgpSample,
    DgpSensor,
    parse_boxes_3d,
    parse_calibration,
    parse_ontology,
    parse_scene,
)
from simsplat_core.data.ego_mask import DDAD_EGO_BODY, EgoPolygons, polygon_valid_mask
from simsplat_core.data.errors import CorruptLogError
from simsplat_core.data.sparse_depth import project_to_depth
from simsplat_core.geometry import invert_transform, transform_points, yaw_of_rotation
from simsplat_core.types import CameraImage, ObjectInfo, SceneLog, node_type_for_category

logger = logging.getLogger(__name__)

#: DDAD / DGP ontology class name -> shared category.
DGP_CATEGORIES: dict[str, str] = {
    **{name: "vehicle" for name in ("Car", "Truck", "Bus/RV/Caravan", "Train", "Trailer", "Towed Object")},
    "Person": "pedestrian",
    **{name: "cyclist" for name in ("Bicycle", "Motorcycle")},
    "Wheeled Slow": "other",
}


def find_scene_file(path: Path) -> Path | None:
    """The single ``scene_*.json`` of a DGP scene folder (or ``path`` itself when it is one), else ``None``."""
    if path.is_file():
        return path if path.name.startswith("scene_") and path.suffix == ".json" else None
    if not path.is_dir():
        return None
    found = sorted(path.glob("scene_*.json"))
    return found[0] if len(found) == 1 else None


def is_dgp_scene(path: Path) -> bool:
    """Whether ``path`` is a DGP scene folder (one ``scene_*.json`` beside ``calibration/``) or its scene file."""
    scene = find_scene_file(path)
    return scene is not None and (scene.parent / "calibration").is_dir()


def lidar_depth(points_world: np.ndarray, K: np.ndarray, cam_to_world: np.ndarray, width: int, height: int,
                near: float = 0.5) -> np.ndarray:
    """``[H, W]`` float32 z-depth of lidar points ``[N, 3]`` (world) seen by a pinhole camera.

    Each pixel keeps its nearest point (z-buffer); pixels no point lands on are ``nan`` (no measurement).
    Points closer than ``near`` metres or behind the camera are dropped.
    """
    cam = transform_points(invert_transform(cam_to_world), points_world)
    return project_to_depth(cam[cam[:, 2] > near], K, width, height)


def with_lidar_depth(image: CameraImage, points_world: np.ndarray) -> CameraImage:
    """``image`` with the sparse depth of ``points_world`` ``[N, 3]`` (``nan`` where no point lands or where the
    image's valid mask is off: the ego body is not scenery)."""
    depth = lidar_depth(points_world, image.K, image.cam_to_world, image.width, image.height)
    if image.valid_mask is not None:
        depth[~image.valid_mask] = np.nan
    return dataclasses.replace(image, depth=depth)


def read_lidar_points(path: Path) -> np.ndarray:
    """``[N, 3]`` float64 points of a DGP ``.npz`` point cloud (array ``data``: ``[N, >= 3]`` X, Y, Z, ...)."""
    try:
        with np.load(path) as npz:
            if "data" not in npz:
                raise CorruptLogError(path, "array 'data'", f"missing (arrays: {sorted(npz.files)})")
            data = np.asarray(npz["data"], dtype=np.float64)
    except (OSError, ValueError) as exc:
        raise CorruptLogError(path, "file", f"not a readable .npz: {exc}") from exc
    if data.ndim != 2 or data.shape[1] < 3:
        raise CorruptLogError(path, "array 'data'", f"expected [N, >= 3] points, got shape {data.shape}")
    return data[:, :3]


def _scaled_K(K: np.ndarray, sx: float, sy: float) -> np.ndarray:
    out = K.copy()
    out[0, 0], out[0, 1], out[1, 1] = K[0, 0] * sx, K[0, 1] * sx, K[1, 1] * sy
    out[0, 2], out[1, 2] = (K[0, 2] + 0.5) * sx - 0.5, (K[1, 2] + 0.5) * sy - 0.5
    return out


def _read_image(path: Path, datum: DgpDatum, size: tuple[int, int]) -> np.ndarray:
    """``[H, W, 3]`` float32 RGB of a camera datum, resized to ``size`` = (width, height)."""
    bgr = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if bgr is None:
        raise CorruptLogError(path, "file", "missing or not a decodable image")
    if (bgr.shape[1], bgr.shape[0]) != (datum.width, datum.height):
        raise CorruptLogError(path, "image size", f"{bgr.shape[1]}x{bgr.shape[0]}, the scene file says "
                              f"{datum.width}x{datum.height}")
    if size != (datum.width, datum.height):
        bgr = cv2.resize(bgr, size, interpolation=cv2.INTER_AREA)
    return cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB).astype(np.float32) * np.float32(1.0 / 255.0)


def _lidar_datum(scene_file: Path, index: int, sample: DgpSample) -> DgpDatum:
    lidars = [d for d in sample.datums if d.kind == "point_cloud"]
    if not lidars:
        raise CorruptLogError(scene_file, f"field 'scene.samples[{index}].datum_keys'", "no point_cloud datum")
    return sorted(lidars, key=lambda d: d.sensor)[0]


def _sensor(calibration: dict[str, DgpSensor], path: Path, name: str) -> DgpSensor:
    if name not in calibration:
        raise CorruptLogError(path, "field 'calibration.names'", f"no calibration for sensor {name!r}")
    return calibration[name]


def _ontology(root: Path) -> dict[int, str]:
    files = sorted((root / "ontology").glob("*.json"))
    return parse_ontology(files[0]) if files else {}


def _camera_image(root: Path, datum: DgpDatum, sensor: DgpSensor, frame_idx: int, world_from_global: np.ndarray,
                  image_scale: float, split: str, ego_polygons: Sequence[Sequence[tuple[float, float]]]
                  ) -> CameraImage:
    """The calibrated, resized, ego-masked ``CameraImage`` of one camera datum."""
    size = (max(1, round(datum.width * image_scale)), max(1, round(datum.height * image_scale)))
    return CameraImage(
        frame_idx=frame_idx,
        timestamp_us=datum.timestamp_us,
        camera=datum.sensor,
        K=_scaled_K(sensor.K, size[0] / datum.width, size[1] / datum.height),
        cam_to_world=world_from_global @ datum.world_from_sensor,
        width=size[0],
        height=size[1],
        image=_read_image(root / datum.filename, datum, size),
        split=split,
        valid_mask=polygon_valid_mask(ego_polygons, *size),
    )


def _frame_boxes(root: Path, lidar: DgpDatum, frame_idx: int, world_from_global: np.ndarray,
                 frame_images: list[CameraImage]) -> list[tuple[str, BoxObservation, int]]:
    """``(object id, world-frame observation, class id)`` of every 3D box annotated on the lidar datum."""
    box_file = lidar.annotations.get(BOUNDING_BOX_3D)
    if box_file is None:
        return []
    boxes = parse_boxes_3d(root / box_file)
    world_from_lidar = world_from_global @ lidar.world_from_sensor
    poses = [world_from_lidar @ b.sensor_from_box for b in boxes]
    centers = np.array([p[:3, 3] for p in poses]).reshape(-1, 3)
    headings = np.array([float(yaw_of_rotation(p[:3, :3])) for p in poses])
    sizes = np.array([b.size for b in boxes]).reshape(-1, 3)
    in_view = boxes_visible(centers, sizes, headings, frame_images)
    return [
        (str(box.instance_id),
         BoxObservation(frame_idx, centers[i], sizes[i], headings[i], float("nan"),
                        bool(in_view[i]) and box.num_points != 0),
         box.class_id)
        for i, box in enumerate(boxes)
    ]


def load_dgp_scene(path: str | Path, image_scale: float = 1.0, seq_id: str | None = None,
                   ego_polygons: EgoPolygons | None = None) -> SceneLog:
    """Load a DGP scene folder (or its ``scene_*.json``) as one ``SceneLog`` (see module docstring).

    Args:
        path: the scene folder or its scene file.
        image_scale: resize factor for images and ``K``; must be > 0.
        seq_id: sequence id; default: ``dgp_`` + the scene folder's name, directory-safe.
        ego_polygons: ego-body polygons per camera (``ego_mask``); default ``DDAD_EGO_BODY``.

    Raises:
        CorruptLogError: a missing or malformed file or field (named), a missing calibration or image.
    """
    if not image_scale > 0:
        raise ValueError(f"image_scale must be > 0, got {image_scale}")
    t0 = time.perf_counter()
    scene_file = find_scene_file(Path(path))
    if scene_file is None:
        raise CorruptLogError(path, "folder", "no single scene_*.json: not a DGP scene")
    root = scene_file.parent
    samples = parse_scene(scene_file)
    polygons = DDAD_EGO_BODY if ego_polygons is None else ego_polygons
    ontology = _ontology(root)
    calibrations: dict[str, dict[str, DgpSensor]] = {}

    def calibration_of(sample: DgpSample) -> tuple[Path, dict[str, DgpSensor]]:
        cal_path = root / "calibration" / f"{sample.calibration_key}.json"
        if sample.calibration_key not in calibrations:
            if not cal_path.is_file():
                raise CorruptLogError(scene_file, "field 'scene.samples[].calibration_key'",
                                      f"calibration file {cal_path.name} is missing")
            calibrations[sample.calibration_key] = parse_calibration(cal_path)
        return cal_path, calibrations[sample.calibration_key]

    global_from_ego = []
    for i, sample in enumerate(samples):
        cal_path, calibration = calibration_of(sample)
        lidar = _lidar_datum(scene_file, i, sample)
        sensor = _sensor(calibration, cal_path, lidar.sensor)
        global_from_ego.append(lidar.world_from_sensor @ invert_transform(sensor.ego_from_sensor))
    world_from_global = invert_transform(global_from_ego[0])
    ego_poses = np.stack([world_from_global @ pose for pose in global_from_ego])
    ego_poses[0] = np.eye(4)
    timestamps = np.array([s.timestamp_us for s in samples], dtype=np.int64)
    dup = np.flatnonzero(np.diff(timestamps) <= 0)
    if dup.size:
        raise CorruptLogError(scene_file, f"field 'scene.samples[{int(dup[0]) + 1}].id.timestamp'",
                              f"duplicate timestamp {timestamps[dup[0]]}")

    camera_names = sorted({d.sensor for s in samples for d in s.datums if d.kind == "image"})
    images: list[CameraImage] = []
    observations: dict[str, list[BoxObservation]] = collections.defaultdict(list)
    class_votes: dict[str, collections.Counter[int]] = collections.defaultdict(collections.Counter)
    for frame_idx, sample in enumerate(samples):
        cal_path, calibration = calibration_of(sample)
        held_out = camera_names[frame_idx % len(camera_names)] if camera_names else ""
        frame_images = [
            _camera_image(root, datum, _sensor(calibration, cal_path, datum.sensor), frame_idx, world_from_global,
                          image_scale, "test" if datum.sensor == held_out else "train",
                          polygons.get(datum.sensor, ()))
            for datum in sorted((d for d in sample.datums if d.kind == "image"), key=lambda d: d.sensor)
        ]
        lidar = _lidar_datum(scene_file, frame_idx, sample)
        sweep = transform_points(world_from_global @ lidar.world_from_sensor,
                                 read_lidar_points(root / lidar.filename))
        frame_images = [with_lidar_depth(image, sweep) for image in frame_images]
        images.extend(frame_images)
        for oid, observation, class_id in _frame_boxes(root, lidar, frame_idx, world_from_global, frame_images):
            observations[oid].append(observation)
            class_votes[oid][class_id] += 1

    order = sorted(observations, key=lambda oid: (observations[oid][0].frame_idx, oid))
    tracks = tuple(build_track(oid, observations[oid], timestamps) for oid in order)
    objects = []
    for instance_id, oid in enumerate(order, start=1):
        class_id = class_votes[oid].most_common(1)[0][0]
        name = ontology.get(class_id, str(class_id))
        category = DGP_CATEGORIES.get(name, "other")
        objects.append(ObjectInfo(object_id=oid, category=category, node_type=node_type_for_category(category),
                                  instance_id=instance_id, attributes={"dgp_class": name}))
    metadata = {
        "source_file": str(scene_file),
        "num_samples": str(len(samples)),
        "image_scale": repr(float(image_scale)),
        "held_out_views": "frame f: camera f mod N of the name-sorted cameras",
        "ego_mask": json.dumps({cam: len(polygons.get(cam, ())) for cam in camera_names}, sort_keys=True),
    }
    log = SceneLog(
        seq_id=seq_id if seq_id is not None else safe_seq_id(f"dgp_{root.name}"),
        source="dgp",
        timestamps_us=timestamps,
        ego_poses=ego_poses,
        images=tuple(images),
        tracks=tracks,
        objects=tuple(objects),
        metadata=metadata,
    )
    return loaded(log, scene_file, t0)


def sweep_points_world(path: str | Path, frame_idx: int) -> np.ndarray:
    """``[N, 3]`` world points of the lidar sweep of ``frame_idx`` of a scene loaded from ``path``."""
    scene_file = find_scene_file(Path(path))
    if scene_file is None:
        raise CorruptLogError(path, "folder", "no single scene_*.json: not a DGP scene")
    samples = parse_scene(scene_file)
    lidar = _lidar_datum(scene_file, frame_idx, samples[frame_idx])
    world_from_global = invert_transform(parse_calibration_pose(scene_file, samples[0]))
    return transform_points(world_from_global @ lidar.world_from_sensor,
                            read_lidar_points(scene_file.parent / lidar.filename))


def parse_calibration_pose(scene_file: Path, sample: DgpSample) -> np.ndarray:
    """``[4, 4]`` global-from-ego pose of ``sample`` (lidar datum pose @ inverse lidar extrinsic)."""
    cal_path = scene_file.parent / "calibration" / f"{sample.calibration_key}.json"
    lidar = _lidar_datum(scene_file, 0, sample)
    sensor = _sensor(parse_calibration(cal_path), cal_path, lidar.sensor)
    return lidar.world_from_sensor @ invert_transform(sensor.ego_from_sensor)
