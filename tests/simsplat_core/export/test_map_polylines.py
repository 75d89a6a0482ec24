"""The vectorised local map against a per-feature reference."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.export.dataset_arrays import densify_polylines
from simsplat_core.export.map_polylines import local_polylines


def _reference(points, feature, num_features, radius, max_polylines, num_points, ties):
    """One feature at a time: the run of points within ``radius`` around the nearest, resampled by arc length."""
    distance = np.hypot(points[:, 0], points[:, 1])
    nearest = np.array([distance[feature == f].min() for f in range(num_features)])
    chosen = [f for f in sorted(range(num_features), key=lambda f: (nearest[f], ties[f])) if nearest[f] <= radius]
    out, valid = [], []
    for f in chosen[:max_polylines]:
        pts, dist = points[feature == f], distance[feature == f]
        lo = hi = int(np.argmin(dist))
        while lo > 0 and dist[lo - 1] <= radius:
            lo -= 1
        while hi + 1 < len(pts) and dist[hi + 1] <= radius:
            hi += 1
        run = pts[lo:hi + 1]
        along = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(run, axis=0), axis=1))])
        targets = np.linspace(0.0, along[-1], num_points)
        out.append(np.stack([np.interp(targets, along, run[:, k]) for k in range(3)], -1))
        valid.append(np.ones(num_points, bool) if len(run) > 1 else np.arange(num_points) == 0)
    return chosen[:max_polylines], np.array(out).reshape(-1, num_points, 3), np.array(valid).reshape(-1, num_points)


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("max_polylines", [3, 64])
def test_local_polylines_match_the_reference(seed, max_polylines):
    rng = np.random.default_rng(seed)
    shapes = []
    for _ in range(25):  # random curvy polylines, some single points, some leaving and re-entering the radius
        count = int(rng.integers(1, 8))
        shapes.append(np.cumsum(rng.normal(0, 15, (count, 3)), axis=0) + rng.uniform(-40, 40, 3))
    offsets = np.concatenate([[0], np.cumsum([len(s) for s in shapes])])
    dense, feature = densify_polylines(np.concatenate(shapes), offsets, rng.random(25) < 0.2, 1.0)
    dense = dense.astype(np.float64)
    ties = rng.permutation(25)
    got = local_polylines(dense, feature, 25, 30.0, max_polylines, 12, tie_break=ties)
    chosen, points, valid = _reference(dense, feature, 25, 30.0, max_polylines, 12, ties)
    assert got.features.tolist() == chosen
    np.testing.assert_allclose(got.points, points, atol=1e-6)
    np.testing.assert_array_equal(got.valid, valid)
    assert np.all(np.hypot(got.points[..., 0], got.points[..., 1]) <= 30.0 + 1e-9)


def test_no_features_or_none_near():
    empty = local_polylines(np.zeros((0, 3)), np.zeros(0, np.int64), 0, 10.0, 5, 4)
    assert empty.points.shape == (0, 4, 3) and empty.valid.shape == (0, 4)
    far = local_polylines(np.array([[100.0, 0, 0]]), np.zeros(1, np.int64), 1, 10.0, 5, 4)
    assert len(far.features) == 0
    one = local_polylines(np.array([[3.0, 4, 0]]), np.zeros(1, np.int64), 1, 10.0, 5, 4)
    assert one.valid.tolist() == [[True, False, False, False]]
    np.testing.assert_allclose(one.points[0], [[3.0, 4, 0]] * 4)
