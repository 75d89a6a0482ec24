"""KITTI raw loader: the public KITTI_tiny drive (skipped when ../shared/data is absent) and malformed copies of
its small text files."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from simsplat_core.data import CorruptLogError
from simsplat_core.data.common import held_out_split
from simsplat_core.data.kitti import load_kitti_raw
from simsplat_core.data.kitti_oxts import read_oxts_packet
from simsplat_core.data.sparse_depth import project_to_depth, resize_sparse_depth
from simsplat_core.geometry import invert_transform
from simsplat_core.types import SceneLog, split_for_frame

DRIVE = Path("kitti/KITTI_tiny/2011_09_26/2011_09_26_drive_0023_sync")


def test_short_logs_hold_out_the_middle_frame_and_long_ones_every_tenth() -> None:
    assert [held_out_split(f, 7) for f in range(7)] == ["train"] * 3 + ["test"] + ["train"] * 3
    assert [held_out_split(f, 3) for f in range(3)] == ["train", "test", "train"]
    assert [held_out_split(f, 30) for f in range(30)] == [split_for_frame(f) for f in range(30)]
    assert all(held_out_split(f, 2) == "train" for f in range(2))


def test_sparse_depth_keeps_the_nearest_point_and_marks_gaps_nan() -> None:
    K = np.array([[10.0, 0.0, 2.0], [0.0, 10.0, 2.0], [0.0, 0.0, 1.0]])
    points = np.array([[0.0, 0.0, 5.0], [0.0, 0.0, 3.0], [0.1, 0.0, -1.0]])  # two on pixel (2, 2), one behind
    depth = project_to_depth(points, K, 4, 4)
    assert depth[2, 2] == 3.0 and np.isnan(depth).sum() == 15
    half = resize_sparse_depth(depth, 2, 2)
    assert half[1, 1] == 3.0 and np.isnan(half).sum() == 3


@pytest.fixture(scope="module")
def drive(shared_data: Path) -> Path:
    return shared_data / DRIVE


@pytest.fixture(scope="module")
def sample(drive: Path) -> SceneLog:
    return load_kitti_raw(drive, image_scale=0.5)


@pytest.mark.shared_data
def test_sample_holds_two_cameras_seven_frames_depth_and_no_boxes(sample: SceneLog) -> None:
    assert sample.source == "kitti-raw" and sample.num_frames == 7 and sample.cameras == ("image_02", "image_03")
    assert not sample.tracks and not sample.objects and not sample.map_features
    np.testing.assert_allclose(sample.ego_poses[0], np.eye(4))
    for img in sample.images:
        assert img.image is not None and img.image.shape == (188, 621, 3) and img.depth is not None
        measured = np.isfinite(img.depth)
        assert 0.01 < measured.mean() < 0.5 and np.all(img.depth[measured] > 0)
        assert img.split == ("test" if img.frame_idx == 3 else "train")


@pytest.mark.shared_data
def test_poses_move_forward_at_the_speed_the_imu_reports(sample: SceneLog, drive: Path) -> None:
    xyz = sample.ego_poses[:, :3, 3]
    step = np.diff(xyz, axis=0)
    assert np.all(step[:, 0] > 0)  # monotone along the ego's heading
    speed = np.linalg.norm(step, axis=1) / (np.diff(sample.timestamps_us) * 1e-6)
    forward = read_oxts_packet(drive / "oxts" / "data" / "0000000000.txt")[8]  # vf, m/s
    assert np.all(np.abs(speed - forward) < 0.15 * forward)
    for img in sample.images:  # cameras look along the ego's x axis, image_03 right of image_02
        assert img.cam_to_world[:3, 2] @ sample.ego_poses[img.frame_idx, :3, 0] > 0.99
    left, right = (next(i for i in sample.images_at(0) if i.camera == c) for c in ("image_02", "image_03"))
    baseline = invert_transform(left.cam_to_world) @ right.cam_to_world
    assert 0.5 < baseline[0, 3] < 0.56


@pytest.mark.shared_data
def test_left_lidar_depth_reprojects_onto_the_right_cameras_depth(sample: SceneLog) -> None:
    """Points of image_02's depth, moved through both cameras' calibration into image_03, land where image_03
    measured the same depth (the two maps come from one scan, so a wrong K or baseline breaks this)."""
    for frame in range(sample.num_frames):
        left, right = (next(i for i in sample.images_at(frame) if i.camera == c) for c in ("image_02", "image_03"))
        rows, cols = np.nonzero(np.isfinite(left.depth))
        z = left.depth[rows, cols].astype(np.float64)
        cam = np.stack([(cols + 0.5 - left.K[0, 2]) / left.K[0, 0] * z, (rows + 0.5 - left.K[1, 2]) / left.K[1, 1] * z,
                        z], axis=1)
        world = cam @ left.cam_to_world[:3, :3].T + left.cam_to_world[:3, 3]
        into_right = project_to_depth(world @ invert_transform(right.cam_to_world)[:3, :3].T
                                      + invert_transform(right.cam_to_world)[:3, 3], right.K, right.width, right.height)
        both = np.isfinite(into_right) & np.isfinite(right.depth)
        assert both.sum() > 1000
        relative = np.abs(into_right[both] - right.depth[both]) / right.depth[both]
        assert np.median(relative) < 0.02


def _copy_drive(drive: Path, tmp_path: Path) -> Path:
    """A copy of the sample with the calibration and OXTS text files; images and depth are symlinked."""
    date = tmp_path / drive.parent.name
    date.mkdir()
    for calib in drive.parent.glob("calib_*.txt"):
        shutil.copy(calib, date / calib.name)
    copy = date / drive.name
    shutil.copytree(drive / "oxts", copy / "oxts")
    for name in ("image_02", "image_03", "proj_depth"):
        (copy / name).symlink_to(drive / name)
    return copy


@pytest.mark.shared_data
def test_malformed_files_are_named_with_the_field(drive: Path, tmp_path: Path) -> None:
    copy = _copy_drive(drive, tmp_path)
    cam_to_cam = copy.parent / "calib_cam_to_cam.txt"
    text = cam_to_cam.read_text()
    cam_to_cam.write_text("\n".join(line for line in text.splitlines() if not line.startswith("P_rect_03")))
    with pytest.raises(CorruptLogError, match=r"calib_cam_to_cam\.txt: field 'P_rect_03': missing"):
        load_kitti_raw(copy)
    cam_to_cam.write_text(text.replace("R_rect_00: 9.999239e-01", "R_rect_00: nine"))
    with pytest.raises(CorruptLogError, match=r"calib_cam_to_cam\.txt: field 'R_rect_00': not numeric"):
        load_kitti_raw(copy)
    cam_to_cam.write_text(text)
    velo = copy.parent / "calib_velo_to_cam.txt"
    velo.write_text(velo.read_text().replace("T: -4.069766e-03 ", "T: "))
    with pytest.raises(CorruptLogError, match=r"calib_velo_to_cam\.txt: field 'T': expected 3 numbers, got 2"):
        load_kitti_raw(copy)
    shutil.copy(drive.parent / "calib_velo_to_cam.txt", velo)
    packet = copy / "oxts" / "data" / "0000000004.txt"
    packet.write_text("49.0 8.4 nan")
    with pytest.raises(CorruptLogError, match=r"0000000004\.txt: packet: expected 30 values, got 3"):
        load_kitti_raw(copy)
    packet.unlink()
    with pytest.raises(CorruptLogError, match=r"0000000004\.txt: file: missing"):
        load_kitti_raw(copy)
