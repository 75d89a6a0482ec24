"""Nearest-neighbour distances for the initial Gaussian scales.

Small clouds use exact brute force (torch ``cdist``); large ones use OpenCV's FLANN randomised k-d trees
(deterministic for a given input, approximate but more than accurate enough for an initial scale:
brute force over 60k points takes ~20 s on 2 cores, FLANN ~1 s).
"""

from __future__ import annotations

import cv2
import numpy as np
import torch

BRUTE_FORCE_MAX = 4096
_FLANN_KDTREE = 1


def knn_sq_distances(points: np.ndarray, k: int = 3) -> np.ndarray:
    """``[N, k]`` squared distances from each of ``points [N, 3]`` to its ``k`` nearest other points
    (ascending). Missing neighbours (``N <= k``) are filled with the largest distance found (or 1)."""
    pts = np.ascontiguousarray(points, dtype=np.float32).reshape(-1, 3)
    n = pts.shape[0]
    if n == 0:
        return np.zeros((0, k), np.float32)
    kk = min(k + 1, n)
    if n <= BRUTE_FORCE_MAX:
        t = torch.from_numpy(pts)
        d2 = torch.cdist(t, t).square()
        vals = torch.topk(d2, kk, dim=1, largest=False).values.numpy()
    else:
        index = cv2.flann.Index(pts, dict(algorithm=_FLANN_KDTREE, trees=4))
        _, vals = index.knnSearch(pts, kk, params=dict(checks=32))
    vals = np.asarray(vals, dtype=np.float32)[:, 1:]  # drop the point itself
    if vals.shape[1] < k:
        fill = float(vals.max()) if vals.size else 1.0
        vals = np.concatenate([vals, np.full((n, k - vals.shape[1]), fill, np.float32)], axis=1)
    return vals


def knn_scale(points: np.ndarray, k: int = 3, min_scale: float = 1e-3, max_scale: float = float("inf")) -> np.ndarray:
    """``[N]`` initial isotropic scale ``sqrt(mean of the k nearest squared distances)`` (3DGS), clamped."""
    d2 = knn_sq_distances(points, k)
    return np.clip(np.sqrt(d2.mean(axis=1)), min_scale, max_scale).astype(np.float32)
