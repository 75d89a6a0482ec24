"""Contact sheets: every camera of one frame with projected 3D boxes, plus a bird's-eye view.

Used to *look at* a log and check that boxes sit on the objects. Pure numpy + OpenCV; returns
uint8 RGB images ``[H, W, 3]``.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Sequence

import cv2
import numpy as np

from simsplat_core.geometry import BOX_EDGES, box_corners, invert_transform, transform_points
from simsplat_core.types import CameraImage, MapFeature, SceneLog
from simsplat_core.viz.images import to_uint8

logger = logging.getLogger(__name__)

#: RGB colour per object category.
CATEGORY_COLORS: dict[str, tuple[int, int, int]] = {
    "vehicle": (255, 64, 64),
    "pedestrian": (64, 255, 64),
    "cyclist": (255, 200, 0),
    "static": (255, 128, 255),
    "sign": (0, 200, 255),
    "other": (200, 200, 200),
}
MAP_COLORS: dict[str, tuple[int, int, int]] = {
    "drivable_area": (70, 70, 70),
    "sidewalk": (110, 100, 90),
    "crosswalk": (200, 200, 200),
    "lane": (80, 120, 255),
    "road_edge": (255, 255, 255),
    "lane_marking": (230, 230, 120),
}
_NEAR = 0.05


def _to_uint8(image: np.ndarray | None, width: int, height: int) -> np.ndarray:
    if image is None:
        canvas = np.full((height, width, 3), 48, np.uint8)
        cv2.putText(canvas, "no pixels in this log", (10, height // 2), cv2.FONT_HERSHEY_SIMPLEX,
                    max(width / 1200, 0.4), (160, 160, 160), 1, cv2.LINE_AA)
        return canvas
    return to_uint8(image)


def _project_edge(a_cam: np.ndarray, b_cam: np.ndarray, K: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Clip a camera-space segment to ``z > near`` and project both ends; ``None`` if fully behind."""
    if a_cam[2] <= _NEAR and b_cam[2] <= _NEAR:
        return None
    if a_cam[2] <= _NEAR or b_cam[2] <= _NEAR:
        t = (_NEAR - a_cam[2]) / (b_cam[2] - a_cam[2])
        clipped = a_cam + t * (b_cam - a_cam)
        if a_cam[2] <= _NEAR:
            a_cam = clipped
        else:
            b_cam = clipped
    ends = np.stack([a_cam, b_cam])
    uv = (ends[:, :2] / ends[:, 2:3]) @ K[:2, :2].T + K[:2, 2]
    return uv[0], uv[1]


def camera_panel(log: SceneLog, image: CameraImage, scale: float = 1.0) -> np.ndarray:
    """One camera image (or a grey canvas) with every present object's 3D box drawn, ``[h, w, 3]`` uint8."""
    canvas = _to_uint8(image.image, image.width, image.height)
    if scale != 1.0:
        canvas = cv2.resize(canvas, (round(image.width * scale), round(image.height * scale)),
                            interpolation=cv2.INTER_AREA)
    K = np.asarray(image.K, dtype=np.float64).copy()
    K[:2] *= scale
    world_to_cam = invert_transform(np.asarray(image.cam_to_world, dtype=np.float64))
    thickness = max(1, round(canvas.shape[1] / 500))
    categories = {obj.object_id: obj.category for obj in log.objects}
    for track in log.tracks:
        row = track.index_of(image.frame_idx)
        if row is None:
            continue
        corners = transform_points(world_to_cam, box_corners(track.center[row], track.size[row], track.heading[row]))
        color = CATEGORY_COLORS.get(categories.get(track.object_id, "other"), CATEGORY_COLORS["other"])
        drawn = False
        for a, b in BOX_EDGES:
            seg = _project_edge(corners[a], corners[b], K)
            if seg is None:
                continue
            p, q = (tuple(int(round(v)) for v in np.clip(end, -1e5, 1e5)) for end in seg)
            cv2.line(canvas, p, q, color, thickness, cv2.LINE_AA)
            drawn = True
        if drawn and corners[:, 2].max() > _NEAR:
            front = corners[corners[:, 2] > _NEAR]
            uv = (front[:, :2] / front[:, 2:3]) @ K[:2, :2].T + K[:2, 2]
            x, y = uv.min(axis=0)
            if 0 <= x < canvas.shape[1] and 0 <= y < canvas.shape[0]:
                cv2.putText(canvas, track.object_id[:10], (int(x), max(int(y) - 3, 8)), cv2.FONT_HERSHEY_SIMPLEX,
                            0.3 * thickness, color, 1, cv2.LINE_AA)
    cv2.putText(canvas, f"{image.camera} f{image.frame_idx}", (4, 14 * thickness), cv2.FONT_HERSHEY_SIMPLEX,
                0.45 * thickness, (255, 255, 0), 1, cv2.LINE_AA)
    return canvas


#: Map kinds filled as polygons (the others are drawn as polylines), and the drawing order.
POLYGON_KINDS: tuple[str, ...] = ("drivable_area", "sidewalk", "crosswalk")
MAP_DRAW_ORDER: tuple[str, ...] = ("drivable_area", "sidewalk", "crosswalk", "lane", "lane_marking", "road_edge")


def draw_map(canvas: np.ndarray, map_features: Sequence[MapFeature], to_px: Callable[[np.ndarray], np.ndarray]
             ) -> None:
    """Draw ``map_features`` on ``canvas`` (uint8 ``[H, W, 3]``, in place) in :data:`MAP_COLORS`: areas filled,
    lines as polylines. ``to_px`` maps ``[P, 3]`` world points to ``[P, 2]`` int32 pixels."""
    for kind in MAP_DRAW_ORDER:
        for feature in map_features:
            if feature.kind != kind or len(feature.points) < 2:
                continue
            pts = to_px(feature.points)
            if kind in POLYGON_KINDS:
                cv2.fillPoly(canvas, [pts], MAP_COLORS[kind])
            else:
                cv2.polylines(canvas, [pts], False, MAP_COLORS[kind], 1, cv2.LINE_AA)


#: Colour of highlighted objects and their paths in the bird's-eye view (RGB).
HIGHLIGHT_COLOR = (255, 0, 255)


def bev_panel(log: SceneLog, frame_idx: int, size: int = 480, extent_m: float = 60.0,
              highlight: tuple[str, ...] = (), window: tuple[int, int] | None = None,
              highlight_ego: bool = False) -> np.ndarray:
    """Bird's-eye view in the ego frame of ``frame_idx`` (ego at centre, x up), ``[size, size, 3]`` uint8.

    ``highlight``: object ids drawn filled-outlined in ``HIGHLIGHT_COLOR`` with their centre paths over ``window``
    (``(first, last)`` frames, inclusive; default: the frame alone); ``highlight_ego`` draws the ego's path too.
    """
    canvas = np.full((size, size, 3), 20, np.uint8)
    world_to_ego = invert_transform(log.ego_poses[frame_idx])
    px_per_m = size / (2.0 * extent_m)

    def to_px(points_world: np.ndarray) -> np.ndarray:
        ego = transform_points(world_to_ego, points_world)
        u = size / 2.0 - ego[:, 1] * px_per_m
        v = size / 2.0 - ego[:, 0] * px_per_m
        return np.round(np.stack([u, v], axis=1)).astype(np.int32)

    draw_map(canvas, log.map_features, to_px)
    categories = {obj.object_id: obj.category for obj in log.objects}
    for track in log.tracks:
        row = track.index_of(frame_idx)
        if row is None:
            continue
        footprint = to_px(box_corners(track.center[row], track.size[row], track.heading[row])[:4])
        color = CATEGORY_COLORS.get(categories.get(track.object_id, "other"), CATEGORY_COLORS["other"])
        marked = track.object_id in highlight
        cv2.polylines(canvas, [footprint], True, HIGHLIGHT_COLOR if marked else color, 3 if marked else 1,
                      cv2.LINE_AA)
        # front edge
        cv2.line(canvas, tuple(int(v) for v in footprint[0]), tuple(int(v) for v in footprint[3]), (255, 255, 255), 1)
    ego_box = to_px(box_corners(log.ego_poses[frame_idx][:3, 3] + [0, 0, 0.8], np.array([4.6, 1.9, 1.6]),
                                math.atan2(log.ego_poses[frame_idx][1, 0], log.ego_poses[frame_idx][0, 0]))[:4])
    cv2.fillPoly(canvas, [ego_box], (255, 255, 0))
    first, last = window if window is not None else (frame_idx, frame_idx)
    paths = [track.center[(track.frame_idx >= first) & (track.frame_idx <= last)] for track in log.tracks
             if track.object_id in highlight]
    if highlight_ego:
        paths.append(log.ego_poses[max(first, 0): last + 1, :3, 3])
    for path in paths:
        if len(path) > 1:
            cv2.polylines(canvas, [to_px(path)], False, HIGHLIGHT_COLOR, 2, cv2.LINE_AA)
    cv2.putText(canvas, f"BEV f{frame_idx} ({extent_m:.0f} m)", (4, 14), cv2.FONT_HERSHEY_SIMPLEX, 0.45,
                (255, 255, 0), 1, cv2.LINE_AA)
    return canvas


def contact_sheet(log: SceneLog, frame_idx: int, panel_width: int = 480, columns: int = 3) -> np.ndarray:
    """All cameras of ``frame_idx`` with boxes, then a bird's-eye view, tiled ``columns`` wide.

    Returns:
        ``[H, W, 3]`` uint8 RGB.
    """
    if not 0 <= frame_idx < log.num_frames:
        raise ValueError(f"{log.seq_id}: frame {frame_idx} outside [0, {log.num_frames})")
    panels = []
    for image in log.images_at(frame_idx):
        panels.append(camera_panel(log, image, scale=panel_width / image.width))
    panels.append(bev_panel(log, frame_idx, size=panel_width))
    cell_h = max(p.shape[0] for p in panels)
    rows = []
    for start in range(0, len(panels), columns):
        row = [np.pad(p, ((0, cell_h - p.shape[0]), (0, 0), (0, 0))) for p in panels[start:start + columns]]
        row += [np.zeros((cell_h, panel_width, 3), np.uint8)] * (columns - len(row))
        rows.append(np.concatenate(row, axis=1))
    return np.concatenate(rows, axis=0)
