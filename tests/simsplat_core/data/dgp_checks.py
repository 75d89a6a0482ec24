"""Checks of a loaded DGP scene against its own annotations, shared by the loader tests and the benchmark."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from simsplat_core.data.dgp import find_scene_file
from simsplat_core.data.dgp_format import BOUNDING_BOX_2D, parse_boxes_2d, parse_scene
from simsplat_core.geometry import box_corners, project_box_bounds
from simsplat_core.types import SceneLog


def box_iou(a: np.ndarray, b: np.ndarray) -> float:
    """IoU of two ``[4]`` x0, y0, x1, y1 rectangles."""
    w = max(0.0, min(a[2], b[2]) - max(a[0], b[0]))
    h = max(0.0, min(a[3], b[3]) - max(a[1], b[1]))
    union = (a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - w * h
    return w * h / union if union > 0 else 0.0


def projected_box_ious(scene_dir: Path, log: SceneLog, image_scale: float) -> list[float]:
    """IoU of every annotated 2D box (full-size pixels, scaled by ``image_scale``) with the projected rectangle of
    the same instance's 3D track box in ``log`` (loaded from ``scene_dir``)."""
    samples = parse_scene(find_scene_file(scene_dir))
    tracks = {t.object_id: t for t in log.tracks}
    images = {(img.frame_idx, img.camera): img for img in log.images}
    ious = []
    for frame_idx, sample in enumerate(samples):
        for datum in sample.datums:
            if datum.kind != "image" or BOUNDING_BOX_2D not in datum.annotations:
                continue
            img = images[(frame_idx, datum.sensor)]
            for instance_id, box2d in parse_boxes_2d(scene_dir / datum.annotations[BOUNDING_BOX_2D]):
                track = tracks.get(str(instance_id))
                if track is None or frame_idx not in track.frame_idx:
                    continue
                i = int(np.flatnonzero(track.frame_idx == frame_idx)[0])
                corners = box_corners(track.center[i], track.size[i], float(track.heading[i]))
                bounds = project_box_bounds(corners, img.K, img.cam_to_world, img.width, img.height)
                ious.append(0.0 if bounds is None else box_iou(np.array(bounds), box2d * image_scale))
    return ious
