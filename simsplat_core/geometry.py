"""Small rigid-body and camera helpers shared by loaders, the world generator and stages.

All functions are pure numpy; shapes are given in the docstrings.
"""

from __future__ import annotations

import numpy as np

#: Rotation taking OpenCV camera axes (x right, y down, z forward) to a "vehicle-style" sensor frame
#: (x forward, y left, z up): ``p_sensor = CV_TO_SENSOR @ p_cv``.
CV_TO_SENSOR = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


def yaw_matrix(yaw: float) -> np.ndarray:
    """``[3, 3]`` rotation about +z by ``yaw`` radians."""
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def make_transform(rotation: np.ndarray, translation: np.ndarray) -> np.ndarray:
    """``[4, 4]`` homogeneous transform from a ``[3, 3]`` rotation and a ``[3]`` translation."""
    out = np.eye(4)
    out[:3, :3] = rotation
    out[:3, 3] = translation
    return out


def pose_from_yaw(x: float, y: float, z: float, yaw: float) -> np.ndarray:
    """``[4, 4]`` transform of a frame at ``(x, y, z)`` rotated by ``yaw`` about +z."""
    return make_transform(yaw_matrix(yaw), np.array([x, y, z], dtype=np.float64))


def invert_transform(transform: np.ndarray) -> np.ndarray:
    """Inverse of a rigid ``[..., 4, 4]`` transform (no general matrix inverse)."""
    rot = transform[..., :3, :3]
    trans = transform[..., :3, 3]
    out = np.zeros_like(transform)
    rot_t = np.swapaxes(rot, -1, -2)
    out[..., :3, :3] = rot_t
    out[..., :3, 3] = -np.einsum("...ij,...j->...i", rot_t, trans)
    out[..., 3, 3] = 1.0
    return out


def transform_points(transform: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Apply a ``[4, 4]`` transform to ``[N, 3]`` points, returning ``[N, 3]``."""
    return points @ transform[:3, :3].T + transform[:3, 3]


def quat_wxyz_to_matrix(quat: np.ndarray) -> np.ndarray:
    """``[..., 4]`` unit quaternions (w, x, y, z) to ``[..., 3, 3]`` rotation matrices."""
    q = np.asarray(quat, dtype=np.float64)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], axis=-1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], axis=-1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=-1),
        ],
        axis=-2,
    )


def yaw_of_rotation(rotation: np.ndarray) -> np.ndarray:
    """Yaw (about +z) of ``[..., 3, 3]`` rotations, radians, shape ``[...]``."""
    return np.arctan2(rotation[..., 1, 0], rotation[..., 0, 0])


def wrap_angle(angle: np.ndarray | float) -> np.ndarray:
    """Wrap radians into ``(-pi, pi]``."""
    return np.pi - np.mod(np.pi - np.asarray(angle), 2.0 * np.pi)


def box_corners(center: np.ndarray, size: np.ndarray, heading: float) -> np.ndarray:
    """The 8 corners ``[8, 3]`` of a yaw-rotated 3D box.

    ``size`` is (length along heading, width, height); ``center`` is the box centre. Corners 0-3 are
    the bottom face, 4-7 the top face, both counter-clockwise seen from above starting front-left.
    """
    length, width, height = (float(v) for v in size)
    xs = np.array([1, -1, -1, 1]) * length / 2.0
    ys = np.array([1, 1, -1, -1]) * width / 2.0
    bottom = np.stack([xs, ys, np.full(4, -height / 2.0)], axis=1)
    top = bottom + np.array([0.0, 0.0, height])
    local = np.concatenate([bottom, top], axis=0)
    return local @ yaw_matrix(heading).T + np.asarray(center, dtype=np.float64)


def box_corners_batch(centers: np.ndarray, sizes: np.ndarray, headings: np.ndarray) -> np.ndarray:
    """Vectorised ``box_corners``: ``[M, 3]`` centres, ``[M, 3]`` sizes, ``[M]`` headings -> ``[M, 8, 3]``.

    Same corner order as ``box_corners``.
    """
    centers = np.asarray(centers, dtype=np.float64).reshape(-1, 3)
    half = 0.5 * np.asarray(sizes, dtype=np.float64).reshape(-1, 3)
    headings = np.asarray(headings, dtype=np.float64).reshape(-1)
    signs = np.array(
        [[1, 1, -1], [-1, 1, -1], [-1, -1, -1], [1, -1, -1], [1, 1, 1], [-1, 1, 1], [-1, -1, 1], [1, -1, 1]],
        dtype=np.float64,
    )
    local = signs[None] * half[:, None, :]  # [M, 8, 3]
    c, s = np.cos(headings)[:, None], np.sin(headings)[:, None]
    out = np.empty_like(local)
    out[..., 0] = c * local[..., 0] - s * local[..., 1]
    out[..., 1] = s * local[..., 0] + c * local[..., 1]
    out[..., 2] = local[..., 2]
    return out + centers[:, None, :]


#: Pairs of corner indices forming the 12 edges of a box from ``box_corners``.
BOX_EDGES: tuple[tuple[int, int], ...] = (
    (0, 1), (1, 2), (2, 3), (3, 0),
    (4, 5), (5, 6), (6, 7), (7, 4),
    (0, 4), (1, 5), (2, 6), (3, 7),
)


def project_points(points_world: np.ndarray, K: np.ndarray, cam_to_world: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Project ``[N, 3]`` world points into an OpenCV pinhole camera.

    Returns:
        uv: ``[N, 2]`` pixel coordinates (meaningless where ``depth <= 0``).
        depth: ``[N]`` camera z-depth in metres.
    """
    cam = transform_points(invert_transform(cam_to_world), points_world)
    depth = cam[:, 2]
    safe = np.where(np.abs(depth) < 1e-9, 1e-9, depth)
    uv = (cam[:, :2] / safe[:, None]) @ K[:2, :2].T + K[:2, 2]
    return uv, depth


def project_box_bounds(
    corners_world: np.ndarray, K: np.ndarray, cam_to_world: np.ndarray, width: int, height: int, near: float = 0.1
) -> tuple[float, float, float, float] | None:
    """Image-space bounding rectangle ``(x0, y0, x1, y1)`` of a box, clipped to the image.

    Edges crossing the near plane are clipped so boxes partly behind the camera still project
    correctly. Returns ``None`` when nothing of the box is in front of the camera or inside the image.
    """
    cam = transform_points(invert_transform(cam_to_world), corners_world)
    pts = [c for c in cam if c[2] > near]
    for a, b in BOX_EDGES:
        za, zb = cam[a, 2], cam[b, 2]
        if (za > near) != (zb > near):
            t = (near - za) / (zb - za)
            pts.append(cam[a] + t * (cam[b] - cam[a]))
    if not pts:
        return None
    pts_arr = np.asarray(pts)
    uv = (pts_arr[:, :2] / pts_arr[:, 2:3]) @ K[:2, :2].T + K[:2, 2]
    x0, y0 = np.clip(uv.min(axis=0), 0, [width, height])
    x1, y1 = np.clip(uv.max(axis=0), 0, [width, height])
    if x1 - x0 < 1e-6 or y1 - y0 < 1e-6:
        return None
    return float(x0), float(y0), float(x1), float(y1)
