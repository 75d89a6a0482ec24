"""Render a reconstructed scene from a log's cameras at one frame, optionally from a shifted ego pose.

Novel views for driving: move the whole camera rig by ``(forward, left)`` metres *in the ego frame*
(x forward, y left, z up; see ``simsplat_core.types``), i.e. a lane change of the ego car, and render
every camera of that frame. Pure numpy + torch; no I/O.

    views = shifted_cameras(log, frame_idx=20, shift_left=1.0)
    images = render_views(graph, 20, views)          # [H, W, 3] float32 per camera
    panel = side_by_side(images)                      # [H, sum(W), 3] uint8
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from simsplat_core.types import SceneLog
from simsplat_core.viz.images import to_uint8

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class CameraView:
    """One camera to render.

    Attributes:
        camera: camera name.
        K: ``[3, 3]`` float64 intrinsics.
        cam_to_world: ``[4, 4]`` float64 OpenCV camera-to-world.
        width, height: image size in pixels.
    """

    camera: str
    K: np.ndarray
    cam_to_world: np.ndarray
    width: int
    height: int


def shift_in_ego_frame(cam_to_world: np.ndarray, ego_to_world: np.ndarray, shift_forward: float = 0.0,
                       shift_left: float = 0.0) -> np.ndarray:
    """Translate a ``[4, 4]`` camera pose by ``(forward, left, 0)`` metres expressed in the ego frame.

    The orientation is unchanged; the world-frame offset is ``R_ego @ [forward, left, 0]``.
    """
    out = np.array(cam_to_world, dtype=np.float64, copy=True)
    offset_ego = np.array([shift_forward, shift_left, 0.0])
    out[:3, 3] += np.asarray(ego_to_world, dtype=np.float64)[:3, :3] @ offset_ego
    return out


def ego_pose_moved(ego_to_world: np.ndarray, xy: np.ndarray, heading: float) -> np.ndarray:
    """``[4, 4]`` ego pose ``ego_to_world`` moved to ground position ``xy [2]`` and yaw ``heading`` (radians);
    height, roll and pitch are kept (the yaw changes by ``heading`` minus the pose's own yaw)."""
    pose = np.array(ego_to_world, dtype=np.float64, copy=True)
    dyaw = float(heading) - float(np.arctan2(pose[1, 0], pose[0, 0]))
    c, s = np.cos(dyaw), np.sin(dyaw)
    pose[:3, :3] = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ pose[:3, :3]
    pose[:2, 3] = np.asarray(xy, dtype=np.float64)[:2]
    return pose


def reposed_cameras(log: SceneLog, frame_idx: int, ego_to_world: np.ndarray) -> list[CameraView]:
    """The log's cameras at ``frame_idx`` carried by the ego to the pose ``ego_to_world [4, 4]`` (the rig keeps
    its mounting: ``cam' = ego' @ inv(ego_log) @ cam``)."""
    views = shifted_cameras(log, frame_idx)
    move = np.asarray(ego_to_world, dtype=np.float64) @ np.linalg.inv(log.ego_poses[frame_idx])
    return [CameraView(v.camera, v.K, move @ v.cam_to_world, v.width, v.height) for v in views]


def shifted_cameras(log: SceneLog, frame_idx: int, cameras: Sequence[str] | None = None, shift_left: float = 0.0,
                    shift_forward: float = 0.0) -> list[CameraView]:
    """The log's cameras at ``frame_idx``, moved by ``(shift_forward, shift_left)`` metres in the ego frame.

    Args:
        cameras: camera names to keep, in this order (default: every camera of the frame, log order).

    Raises:
        ValueError: ``frame_idx`` outside the log, or a camera the frame does not have (the message
            lists the valid ones).
    """
    if not 0 <= frame_idx < log.num_frames:
        raise ValueError(f"{log.seq_id}: frame {frame_idx} outside [0, {log.num_frames})")
    images = {img.camera: img for img in log.images_at(frame_idx)}
    names = list(cameras) if cameras else list(images)
    unknown = [c for c in names if c not in images]
    if unknown or not names:
        raise ValueError(f"{log.seq_id}: frame {frame_idx} has no camera(s) {unknown}; cameras: {sorted(images)}")
    ego = log.ego_poses[frame_idx]
    return [
        CameraView(
            camera=name,
            K=np.asarray(images[name].K, dtype=np.float64),
            cam_to_world=shift_in_ego_frame(images[name].cam_to_world, ego, shift_forward, shift_left),
            width=int(images[name].width),
            height=int(images[name].height),
        )
        for name in names
    ]


def render_views(graph: Any, frame_idx: int, views: Sequence[CameraView]) -> list[np.ndarray]:
    """Render ``graph`` (a ``simsplat_core.scene.SceneGraph``) at ``frame_idx`` for each view.

    Views of equal size are rendered in one batch. Returns one ``[H, W, 3]`` float32 RGB per view,
    in order.
    """
    import torch  # noqa: PLC0415  # slow: the module is torch-free except for rendering

    out: list[np.ndarray | None] = [None] * len(views)
    sizes = dict.fromkeys((v.width, v.height) for v in views)
    for width, height in sizes:
        batch = [i for i, v in enumerate(views) if (v.width, v.height) == (width, height)]
        c2w = torch.tensor(np.stack([views[i].cam_to_world for i in batch]), dtype=torch.float32)  # [C, 4, 4]
        Ks = torch.tensor(np.stack([views[i].K for i in batch]), dtype=torch.float32)  # [C, 3, 3]
        with torch.no_grad():
            rendered = graph.render(frame_idx, c2w, Ks, width, height, with_node_ids=False)
        rgb = rendered.rgb.detach().cpu().numpy().astype(np.float32)  # [C, H, W, 3]
        for j, i in enumerate(batch):
            out[i] = rgb[j]
    return [img for img in out if img is not None]


def side_by_side(images: Sequence[np.ndarray], gap: int = 4) -> np.ndarray:
    """``[H, W, 3]`` float images in ``[0, 1]`` side by side as one uint8 RGB image (bottom-padded)."""
    if not images:
        raise ValueError("side_by_side: no images")
    height = max(img.shape[0] for img in images)
    width = sum(img.shape[1] for img in images) + gap * (len(images) - 1)
    canvas = np.zeros((height, width, 3), np.uint8)
    x = 0
    for img in images:
        h, w = img.shape[:2]
        canvas[:h, x : x + w] = to_uint8(img)
        x += w + gap
    return canvas
