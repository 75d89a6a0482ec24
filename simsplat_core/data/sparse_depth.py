"""Sparse metric depth maps (projected lidar): ``nan`` where nothing was measured.

Dense renders mark empty sky with ``inf``; a sparse lidar map cannot tell sky from an unmeasured pixel,
so it uses ``nan`` (see ``CameraImage.depth``). Where several points land in one pixel the nearest wins.
"""

from __future__ import annotations

import numpy as np


def splat_nearest_depth(u: np.ndarray, v: np.ndarray, z: np.ndarray, width: int, height: int) -> np.ndarray:
    """``[H, W]`` float32 depth map of points at continuous pixel coordinates.

    Args:
        u, v: ``[N]`` pixel coordinates (pixel ``(i, j)`` covers ``[j, j+1) x [i, i+1)``).
        z: ``[N]`` positive depths; points outside the image or with ``z <= 0`` are dropped.
        width, height: map size.

    Returns:
        the smallest ``z`` per pixel, ``nan`` where no point falls.
    """
    col, row = np.floor(u).astype(np.int64), np.floor(v).astype(np.int64)
    keep = (z > 0) & np.isfinite(z) & (col >= 0) & (col < width) & (row >= 0) & (row < height)
    flat = np.full(width * height, np.inf)
    np.minimum.at(flat, row[keep] * width + col[keep], z[keep])
    flat[np.isinf(flat)] = np.nan
    return flat.reshape(height, width).astype(np.float32)


def depth_from_measured_map(depth: np.ndarray, missing: float = 0.0) -> np.ndarray:
    """``[H, W]`` float32 map with ``missing`` (and non-positive / non-finite) entries set to ``nan``."""
    out = np.asarray(depth, dtype=np.float32).copy()
    out[~(np.isfinite(out) & (out > 0)) | (out == missing)] = np.nan
    return out


def resize_sparse_depth(depth: np.ndarray, width: int, height: int) -> np.ndarray:
    """``[height, width]`` sparse map from ``[H, W]`` ``depth`` (``nan`` = no measurement): each measured
    pixel centre is moved to the new grid and the nearest depth per new pixel kept (no averaging across
    surfaces)."""
    rows, cols = np.nonzero(np.isfinite(depth))
    sx, sy = width / depth.shape[1], height / depth.shape[0]
    return splat_nearest_depth((cols + 0.5) * sx, (rows + 0.5) * sy, depth[rows, cols].astype(np.float64),
                               width, height)


def project_to_depth(points_cam: np.ndarray, K: np.ndarray, width: int, height: int) -> np.ndarray:
    """``[H, W]`` sparse depth of ``[N, 3]`` points in an OpenCV camera frame with intrinsics ``K``."""
    z = points_cam[:, 2]
    safe = np.where(z > 1e-6, z, 1.0)
    u = K[0, 0] * points_cam[:, 0] / safe + K[0, 2]
    v = K[1, 1] * points_cam[:, 1] / safe + K[1, 2]
    return splat_nearest_depth(u, v, np.where(z > 1e-6, z, -1.0), width, height)
