"""KITTI raw calibration files -> rectified pinhole cameras and the camera-from-IMU chain.

A KITTI raw date folder holds three ``key: numbers`` text files:

* ``calib_cam_to_cam.txt``: per camera ``i`` the rectified projection ``P_rect_0i`` (``[3, 4]``, maps
  points of the *rectified camera 0* frame to pixels of the rectified image ``i``), the rectified size
  ``S_rect_0i`` and the rectifying rotation ``R_rect_00`` (unrectified camera 0 -> rectified camera 0);
* ``calib_velo_to_cam.txt``: ``R`` (``[3, 3]``), ``T`` (``[3]``): Velodyne -> unrectified camera 0;
* ``calib_imu_to_velo.txt``: ``R``, ``T``: IMU (OXTS) -> Velodyne.

The ``*_sync`` images are rectified, so camera ``i`` is a pinhole camera with ``K = P_rect_0i[:, :3]``
sitting at ``K^-1 P_rect_0i[:, 3]`` in rectified camera 0 (a pure translation along the stereo baseline),
with the OpenCV axes (x right, y down, z forward).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from simsplat_core.data.errors import CorruptLogError
from simsplat_core.geometry import make_transform

CAM_TO_CAM = "calib_cam_to_cam.txt"
VELO_TO_CAM = "calib_velo_to_cam.txt"
IMU_TO_VELO = "calib_imu_to_velo.txt"


def read_calib_file(path: Path) -> dict[str, str]:
    """``{key: value text}`` of a KITTI ``key: numbers`` file.

    Raises:
        CorruptLogError: the file is missing or a line has no ``key:`` (names the file and the line).
    """
    if not path.is_file():
        raise CorruptLogError(path, "file", "missing")
    fields: dict[str, str] = {}
    for number, line in enumerate(path.read_text(encoding="utf-8", errors="replace").splitlines(), start=1):
        if not line.strip():
            continue
        key, sep, value = line.partition(":")
        if not sep:
            raise CorruptLogError(path, f"line {number}", f"expected 'key: values', got {line[:60]!r}")
        fields[key.strip()] = value.strip()
    return fields


def calib_array(path: Path, fields: dict[str, str], key: str, shape: tuple[int, ...]) -> np.ndarray:
    """Field ``key`` of a parsed calibration file as a float64 array of ``shape``.

    Raises:
        CorruptLogError: the field is absent, not numeric, has the wrong count or non-finite values (names
            the file and the field).
    """
    if key not in fields:
        raise CorruptLogError(path, f"field {key!r}", "missing")
    try:
        values = np.array([float(v) for v in fields[key].split()], dtype=np.float64)
    except ValueError as exc:
        raise CorruptLogError(path, f"field {key!r}", f"not numeric: {exc}") from exc
    count = int(np.prod(shape))
    if values.size != count:
        raise CorruptLogError(path, f"field {key!r}", f"expected {count} numbers, got {values.size}")
    if not np.all(np.isfinite(values)):
        raise CorruptLogError(path, f"field {key!r}", "non-finite value")
    return values.reshape(shape)


def _rigid(path: Path, fields: dict[str, str]) -> np.ndarray:
    """``[4, 4]`` transform from a file's ``R`` / ``T`` fields."""
    return make_transform(calib_array(path, fields, "R", (3, 3)), calib_array(path, fields, "T", (3,)))


@dataclass(frozen=True)
class RectifiedCamera:
    """One rectified KITTI camera.

    Attributes:
        index: camera number (``2`` for ``image_02``).
        K: ``[3, 3]`` float64 intrinsics of the rectified image.
        width, height: rectified image size in pixels.
        cam_from_rect0: ``[4, 4]`` rectified camera 0 -> this camera (translation only).
    """

    index: int
    K: np.ndarray
    width: int
    height: int
    cam_from_rect0: np.ndarray


@dataclass(frozen=True)
class KittiCalibration:
    """The calibration of one KITTI raw date folder.

    Attributes:
        cameras: ``{camera index: RectifiedCamera}``.
        rect0_from_velo: ``[4, 4]`` Velodyne -> rectified camera 0 (``R_rect_00 @ velo_to_cam``).
        velo_from_imu: ``[4, 4]`` IMU -> Velodyne.
    """

    cameras: dict[int, RectifiedCamera]
    rect0_from_velo: np.ndarray
    velo_from_imu: np.ndarray

    def cam_from_imu(self, index: int) -> np.ndarray:
        """``[4, 4]`` IMU (ego) frame -> OpenCV frame of rectified camera ``index``."""
        return self.cameras[index].cam_from_rect0 @ self.rect0_from_velo @ self.velo_from_imu

    def cam_from_velo(self, index: int) -> np.ndarray:
        """``[4, 4]`` Velodyne -> OpenCV frame of rectified camera ``index``."""
        return self.cameras[index].cam_from_rect0 @ self.rect0_from_velo


def load_kitti_calibration(folder: Path, camera_indices: tuple[int, ...]) -> KittiCalibration:
    """Parse the three calibration files of a KITTI raw date folder for the cameras ``camera_indices``.

    Raises:
        CorruptLogError: a missing file or a missing / malformed field (names the file and the field).
    """
    cam_path, velo_path, imu_path = folder / CAM_TO_CAM, folder / VELO_TO_CAM, folder / IMU_TO_VELO
    cam_fields = read_calib_file(cam_path)
    r_rect = np.eye(4)
    r_rect[:3, :3] = calib_array(cam_path, cam_fields, "R_rect_00", (3, 3))
    cameras = {}
    for index in camera_indices:
        P = calib_array(cam_path, cam_fields, f"P_rect_{index:02d}", (3, 4))
        width, height = calib_array(cam_path, cam_fields, f"S_rect_{index:02d}", (2,))
        K = P[:, :3]
        if not (K[0, 0] > 0 and K[1, 1] > 0 and width >= 1 and height >= 1):
            raise CorruptLogError(cam_path, f"field 'P_rect_{index:02d}' / 'S_rect_{index:02d}'",
                                  "focal lengths and image size must be positive")
        cameras[index] = RectifiedCamera(index, K.copy(), int(round(width)), int(round(height)),
                                         make_transform(np.eye(3), np.linalg.solve(K, P[:, 3])))
    velo_to_cam = _rigid(velo_path, read_calib_file(velo_path))
    velo_from_imu = _rigid(imu_path, read_calib_file(imu_path))
    return KittiCalibration(cameras, r_rect @ velo_to_cam, velo_from_imu)
