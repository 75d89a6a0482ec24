"""Novel-view cameras: shifts are in the ego frame, orientation is kept, bad frames/cameras are named."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.geometry import pose_from_yaw
from simsplat_core.scene_view import ego_pose_moved, reposed_cameras, shift_in_ego_frame, shifted_cameras, side_by_side
from simsplat_core.types import CameraImage, SceneLog


def _log() -> SceneLog:
    ego = np.stack([np.eye(4), pose_from_yaw(5.0, 2.0, 0.0, np.pi / 2)])
    images = tuple(
        CameraImage(frame_idx=f, timestamp_us=f * 100_000, camera=cam, K=np.diag([100.0, 100.0, 1.0]),
                    cam_to_world=ego[f] @ pose_from_yaw(1.5, 0.0, 1.6, yaw), width=16 + 8 * i, height=12)
        for f in range(2)
        for i, (cam, yaw) in enumerate((("front", 0.0), ("left", 0.9)))
    )
    return SceneLog("s", "synthetic", np.array([0, 100_000]), ego, images=images).validate()


def test_shift_left_moves_along_ego_y_and_keeps_orientation() -> None:
    log = _log()
    (front,) = shifted_cameras(log, 1, ["front"], shift_left=1.0, shift_forward=2.0)
    original = log.images_at(1)[0].cam_to_world
    # ego yawed +90 deg: ego forward = world +y, ego left = world -x
    assert np.allclose(front.cam_to_world[:3, 3] - original[:3, 3], [-1.0, 2.0, 0.0])
    assert np.array_equal(front.cam_to_world[:3, :3], original[:3, :3])
    assert np.array_equal(shift_in_ego_frame(original, log.ego_poses[1]), original)


def test_cameras_carried_by_a_moved_ego_keep_their_mounting() -> None:
    log = _log()
    same = reposed_cameras(log, 1, log.ego_poses[1])
    assert all(np.allclose(v.cam_to_world, w.cam_to_world) for v, w in zip(same, shifted_cameras(log, 1)))
    # the ego 3 m further along its heading (world +y) and turned 0.2 rad left
    moved = ego_pose_moved(log.ego_poses[1], log.ego_poses[1][:2, 3] + [0.0, 3.0], np.pi / 2 + 0.2)
    assert np.allclose(moved[2, 3], log.ego_poses[1][2, 3])
    assert np.isclose(np.arctan2(moved[1, 0], moved[0, 0]), np.pi / 2 + 0.2)
    for view, image in zip(reposed_cameras(log, 1, moved), log.images_at(1)):
        mount = np.linalg.inv(log.ego_poses[1]) @ image.cam_to_world  # camera in the ego frame
        assert np.allclose(np.linalg.inv(moved) @ view.cam_to_world, mount)


def test_default_is_every_camera_in_log_order_with_sizes() -> None:
    views = shifted_cameras(_log(), 0)
    assert [(v.camera, v.width, v.height) for v in views] == [("front", 16, 12), ("left", 24, 12)]
    assert [v.camera for v in shifted_cameras(_log(), 0, ["left", "front"])] == ["left", "front"]


def test_bad_frame_or_camera_is_named() -> None:
    with pytest.raises(ValueError, match=r"frame 2 outside \[0, 2\)"):
        shifted_cameras(_log(), 2)
    with pytest.raises(ValueError, match=r"no camera\(s\) \['rear'\]; cameras: \['front', 'left'\]"):
        shifted_cameras(_log(), 0, ["rear"])


def test_side_by_side_pads_and_converts() -> None:
    panel = side_by_side([np.ones((4, 5, 3), np.float32), np.zeros((6, 2, 3), np.float32)], gap=1)
    assert panel.shape == (6, 8, 3) and panel.dtype == np.uint8
    assert panel[0, 0, 0] == 255 and panel[5, 0, 0] == 0
