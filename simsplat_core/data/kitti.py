"""KITTI raw drive (``<date>/<date>_drive_<n>_sync``) -> ``SceneLog``.

Layout read (the date folder holds the calibration, see ``kitti_calib``)::

    <date>/calib_cam_to_cam.txt, calib_velo_to_cam.txt, calib_imu_to_velo.txt
    <date>/<drive>_sync/image_0{2,3}/data/<frame>.png, image_0{2,3}/timestamps.txt
    <date>/<drive>_sync/oxts/data/<frame>.txt
    <date>/<drive>_sync/velodyne_points/data/<frame>.bin     (optional: raw lidar, float32 x, y, z, r)
    <date>/<drive>_sync/proj_depth/velodyne/image_0{2,3}/<frame>.npz   (optional: lidar depth, 0 = none)

Conventions of the result:

* frames are the PNG names of the first colour camera (every camera and ``oxts`` must have each);
  ``timestamps_us`` are that camera's ``timestamps.txt`` times (Unix microseconds), each image keeps its
  own camera's time;
* ego = the OXTS IMU (x forward, y left, z up); world = the first IMU pose (``kitti_oxts``);
* cameras ``image_02`` / ``image_03`` (the colour pair) are rectified pinholes:
  ``cam_to_world = ego_pose @ inv(cam_from_imu)``, ``K`` from ``P_rect`` (no distortion left);
* depth: sparse metric z-depth (``nan`` = no measurement): the raw Velodyne points projected through the
  calibration when ``velodyne_points`` exists, else the ``proj_depth`` maps;
* with ``image_scale != 1`` images are resized with ``cv2.INTER_AREA``, ``K`` scaled keeping pixel
  centres, depth resampled by nearest point per pixel;
* no boxes (raw drives carry none; tracklet files are not read), no map;
* split: ``common.held_out_split`` (the middle frame of a short drive is the test frame).
"""

from __future__ import annotations

import logging
import time
from pathlib import Path

import cv2
import numpy as np

from simsplat_core.data.common import held_out_split, loaded, safe_seq_id
from simsplat_core.data.errors import CorruptLogError
from simsplat_core.data.kitti_calib import CAM_TO_CAM, KittiCalibration, load_kitti_calibration
from simsplat_core.data.kitti_oxts import oxts_poses, read_oxts_packet
from simsplat_core.data.sparse_depth import depth_from_measured_map, project_to_depth, resize_sparse_depth
from simsplat_core.geometry import invert_transform, transform_points
from simsplat_core.types import CameraImage, SceneLog

logger = logging.getLogger(__name__)

#: Colour cameras of a KITTI raw drive (folder ``image_0<i>``).
KITTI_CAMERAS: tuple[int, ...] = (2, 3)
#: Key of the depth array in a ``proj_depth`` ``.npz``.
PROJ_DEPTH_KEY = "velodyne_depth"


def camera_name(index: int) -> str:
    """Folder and ``CameraImage.camera`` name of camera ``index`` (``image_02``)."""
    return f"image_{index:02d}"


def is_kitti_raw_drive(path: Path) -> bool:
    """Whether ``path`` is a KITTI raw drive folder (``oxts/data``, ``image_02/data`` and the date folder's
    ``calib_cam_to_cam.txt``) (log-source detection; never raises)."""
    try:
        return (path.is_dir() and (path / "oxts" / "data").is_dir()
                and (path / camera_name(KITTI_CAMERAS[0]) / "data").is_dir() and (path.parent / CAM_TO_CAM).is_file())
    except OSError:
        return False


def read_timestamps_us(path: Path) -> np.ndarray:
    """``[N]`` int64 Unix microseconds of a KITTI ``timestamps.txt`` (``YYYY-MM-DD hh:mm:ss.fffffffff``).

    Raises:
        CorruptLogError: missing file or a line that is not such a time (names the line).
    """
    if not path.is_file():
        raise CorruptLogError(path, "file", "missing")
    times = []
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        if not line.strip():
            continue
        try:
            times.append(np.datetime64(line.strip().replace(" ", "T"), "ns").astype(np.int64) // 1000)
        except ValueError as exc:
            raise CorruptLogError(path, f"line {number}", f"not a time: {line[:40]!r}") from exc
    return np.array(times, dtype=np.int64)


def _frame_names(drive: Path) -> list[str]:
    """Frame names (PNG stems of the first colour camera), sorted."""
    names = sorted(p.stem for p in (drive / camera_name(KITTI_CAMERAS[0]) / "data").glob("*.png"))
    if not names:
        raise CorruptLogError(drive / camera_name(KITTI_CAMERAS[0]) / "data", "folder", "no PNG images")
    return names


def _frame_time(times: np.ndarray, path: Path, name: str) -> int:
    """The time of frame ``name`` (its number indexes the lines of ``timestamps.txt`` at ``path``)."""
    k = int(name)
    if k >= times.shape[0]:
        raise CorruptLogError(path, f"line {k + 1}", f"missing (frame {name}; the file has {times.shape[0]} lines)")
    return int(times[k])


def read_png(path: Path, size: tuple[int, int], out_size: tuple[int, int]) -> np.ndarray:
    """``[H, W, 3]`` float32 RGB in [0, 1] of a PNG whose size must be ``size`` (``(width, height)``), resized
    to ``out_size`` with ``cv2.INTER_AREA``.

    Raises:
        CorruptLogError: missing, undecodable, or of another size than the calibration's.
    """
    if not path.is_file():
        raise CorruptLogError(path, "file", "missing")
    bgr = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if bgr is None:
        raise CorruptLogError(path, "file", "does not decode as an image")
    if (bgr.shape[1], bgr.shape[0]) != size:
        raise CorruptLogError(path, "image size",
                              f"{bgr.shape[1]}x{bgr.shape[0]}, calibration says {size[0]}x{size[1]}")
    if out_size != size:
        bgr = cv2.resize(bgr, out_size, interpolation=cv2.INTER_AREA)
    return cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB).astype(np.float32) * np.float32(1.0 / 255.0)


def read_projected_depth(path: Path, size: tuple[int, int]) -> np.ndarray:
    """``[H, W]`` float32 sparse depth (``nan`` = none) of a ``proj_depth`` ``.npz`` of ``size`` (w, h).

    Raises:
        CorruptLogError: unreadable, without ``PROJ_DEPTH_KEY``, or of the wrong shape.
    """
    try:
        with np.load(path) as archive:
            if PROJ_DEPTH_KEY not in archive.files:
                raise CorruptLogError(path, f"array {PROJ_DEPTH_KEY!r}", f"missing (has {archive.files})")
            depth = archive[PROJ_DEPTH_KEY]
    except (OSError, ValueError) as exc:
        if isinstance(exc, CorruptLogError):
            raise
        raise CorruptLogError(path, "file", f"unreadable: {exc}") from exc
    if depth.shape != (size[1], size[0]):
        raise CorruptLogError(path, f"array {PROJ_DEPTH_KEY!r}", f"shape {depth.shape}, image is {size[1]}x{size[0]}")
    return depth_from_measured_map(depth)


def read_velodyne_depth(path: Path, cam_from_velo: np.ndarray, K: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """``[H, W]`` sparse depth of a raw Velodyne scan (``[N, 4]`` float32 ``x, y, z, reflectance``).

    Raises:
        CorruptLogError: a byte count that is not a multiple of 16.
    """
    raw = np.fromfile(path, dtype=np.float32)
    if raw.size % 4:
        raise CorruptLogError(path, "file", f"{raw.size * 4} bytes is not a whole number of 16-byte points")
    points = transform_points(cam_from_velo, raw.reshape(-1, 4)[:, :3].astype(np.float64))
    return project_to_depth(points, K, size[0], size[1])


def _scaled_K(K: np.ndarray, sx: float, sy: float) -> np.ndarray:
    """``K`` of an image resized by ``(sx, sy)`` (pixel centres kept: ``c' = (c + 0.5) s - 0.5``)."""
    out = K.copy()
    out[0, 0], out[1, 1] = K[0, 0] * sx, K[1, 1] * sy
    out[0, 2], out[1, 2] = (K[0, 2] + 0.5) * sx - 0.5, (K[1, 2] + 0.5) * sy - 0.5
    return out


def _camera_depth(drive: Path, calib: KittiCalibration, index: int, name: str, size: tuple[int, int],
                  out_size: tuple[int, int]) -> np.ndarray | None:
    """Sparse depth of camera ``index`` at frame ``name`` (raw scan first, then ``proj_depth``), or ``None``."""
    scan = drive / "velodyne_points" / "data" / f"{name}.bin"
    projected = drive / "proj_depth" / "velodyne" / camera_name(index) / f"{name}.npz"
    if scan.is_file():
        depth = read_velodyne_depth(scan, calib.cam_from_velo(index), calib.cameras[index].K, size)
    elif projected.is_file():
        depth = read_projected_depth(projected, size)
    else:
        return None
    return depth if out_size == size else resize_sparse_depth(depth, *out_size)


def load_kitti_raw(path: str | Path, image_scale: float = 1.0, seq_id: str | None = None) -> SceneLog:
    """Load a KITTI raw drive folder (see the module docstring).

    Args:
        path: the ``<date>_drive_<n>_sync`` folder (calibration files in its parent).
        image_scale: resize factor for images, depth and ``K``; must be > 0.
        seq_id: defaults to the drive folder's name.

    Raises:
        FileNotFoundError: ``path`` does not exist.
        CorruptLogError: a missing or malformed file (names the file and the field or line).
    """
    started = time.perf_counter()
    drive = Path(path)
    if not image_scale > 0:
        raise ValueError(f"image_scale must be > 0, got {image_scale}")
    if not drive.exists():
        raise FileNotFoundError(f"{drive}: KITTI raw drive folder does not exist")
    if not is_kitti_raw_drive(drive):
        raise CorruptLogError(drive, "folder", f"not a KITTI raw drive (needs oxts/data, image_02/data and "
                                               f"{drive.parent / CAM_TO_CAM})")
    calib = load_kitti_calibration(drive.parent, KITTI_CAMERAS)
    names = _frame_names(drive)
    packets = np.stack([read_oxts_packet(drive / "oxts" / "data" / f"{name}.txt") for name in names])
    ego_poses = oxts_poses(packets)
    images = []
    frame_times: np.ndarray | None = None
    for index in KITTI_CAMERAS:
        cam = calib.cameras[index]
        folder = drive / camera_name(index)
        stamp_path = folder / "timestamps.txt"
        stamps = read_timestamps_us(stamp_path)
        times = np.array([_frame_time(stamps, stamp_path, name) for name in names], dtype=np.int64)
        if frame_times is None:
            frame_times = times
        size = (cam.width, cam.height)
        out_size = (max(1, round(cam.width * image_scale)), max(1, round(cam.height * image_scale)))
        K = _scaled_K(cam.K, out_size[0] / cam.width, out_size[1] / cam.height)
        imu_from_cam = invert_transform(calib.cam_from_imu(index))
        for frame_idx, name in enumerate(names):
            images.append(CameraImage(
                frame_idx=frame_idx, timestamp_us=int(times[frame_idx]), camera=camera_name(index), K=K,
                cam_to_world=ego_poses[frame_idx] @ imu_from_cam, width=out_size[0], height=out_size[1],
                image=read_png(folder / "data" / f"{name}.png", size, out_size),
                depth=_camera_depth(drive, calib, index, name, size, out_size),
                split=held_out_split(frame_idx, len(names))))
    log = SceneLog(
        seq_id=seq_id or safe_seq_id(drive.name), source="kitti-raw",
        timestamps_us=frame_times if frame_times is not None else np.zeros(0, np.int64),
        ego_poses=ego_poses, images=tuple(images),
        metadata={"source_file": str(drive), "image_scale": repr(float(image_scale)),
                  "frames": f"{names[0]}..{names[-1]}", "depth": "sparse lidar (nan = no measurement)"})
    return loaded(log, drive, started)
