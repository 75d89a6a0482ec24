"""The map around one point: the nearest features' parts within a radius, resampled to fixed-size polylines.

Vectorised over every feature of a scenario (no per-feature Python loop). A feature's part is the run of its
consecutive (densified) points within the radius that holds its point nearest to the centre, so a long lane
gives its local stretch, not its whole length; the run is resampled to ``P`` points evenly along its length. The
points are expected at most about a metre apart (``dataset_arrays.densify_polylines``): a feature passing within
the radius between two points farther apart may be missed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class LocalPolylines:
    """``M`` polylines of ``P`` points around the centre, nearest feature first.

    Attributes:
        features: ``[M]`` int64 the features (index into the feature arrays) the polylines come from.
        points: ``[M, P, 3]`` float64 the resampled points (the input's frame and units).
        valid: ``[M, P]`` bool; a one-point run (a stop sign, a feature touching the radius) has only point 0.
    """

    features: np.ndarray
    points: np.ndarray
    valid: np.ndarray


def _first_nearest(distance: np.ndarray, point_feature: np.ndarray, starts: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Per feature: the smallest distance ``[F]`` and the first point index holding it ``[F]``."""
    nearest = np.minimum.reduceat(distance, starts[:-1])
    hits = np.flatnonzero(distance == nearest[point_feature])
    features, first = np.unique(point_feature[hits], return_index=True)
    at = np.zeros(len(nearest), np.int64)
    at[features] = hits[first]
    return nearest, at


def local_polylines(points: np.ndarray, point_feature: np.ndarray, num_features: int, radius: float,
                    max_polylines: int, num_points: int, tie_break: np.ndarray | None = None) -> LocalPolylines:
    """The nearest ``max_polylines`` features within ``radius`` (ground-plane distance from the origin).

    Args:
        points: ``[Q, 3]`` every feature's points, centred on the origin (metres), grouped by feature in order.
        point_feature: ``[Q]`` int64 the feature of each point, non-decreasing; every feature has a point.
        num_features: ``F``.
        radius: metres.
        max_polylines: at most this many features.
        num_points: ``P``, the points of each resampled polyline.
        tie_break: ``[F]`` sort key among features at the same distance (their ids); default the feature index.

    Returns:
        the polylines (``LocalPolylines``), features ordered by distance then ``tie_break``.
    """
    empty = LocalPolylines(np.zeros(0, np.int64), np.zeros((0, num_points, 3)), np.zeros((0, num_points), bool))
    if num_features == 0:
        return empty
    points = np.asarray(points, np.float64)
    distance = np.hypot(points[:, 0], points[:, 1])
    starts = np.searchsorted(point_feature, np.arange(num_features + 1))
    nearest, at = _first_nearest(distance, point_feature, starts)
    chosen = np.flatnonzero(nearest <= radius)
    ties = np.arange(num_features) if tie_break is None else tie_break
    chosen = chosen[np.lexsort([ties[chosen], nearest[chosen]])][:max_polylines]
    if len(chosen) == 0:
        return empty
    inside = distance <= radius
    new_run = inside & np.concatenate([[True], ~inside[:-1] | (point_feature[1:] != point_feature[:-1])])
    run_of = np.cumsum(new_run) - 1  # [Q], meaningful where inside
    slot = np.full(int(run_of[-1]) + 1, -1)
    slot[run_of[at[chosen]]] = np.arange(len(chosen))
    members = np.flatnonzero(inside & (slot[run_of.clip(0)] >= 0))
    polyline = slot[run_of[members]]  # [K] which output polyline, non-decreasing along a run
    order = np.argsort(polyline, kind="stable")
    members, polyline = members[order], polyline[order]
    resampled, counts = _resample_runs(points[members], polyline, len(chosen), num_points)
    valid = np.where((counts > 1)[:, None], True, np.arange(num_points)[None] == 0)
    return LocalPolylines(chosen.astype(np.int64), resampled, valid)


def _resample_runs(points: np.ndarray, run: np.ndarray, num_runs: int, num_points: int
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Runs of points (``[K, 3]`` grouped by ``run`` ``[K]``, ``0..num_runs-1`` each present) -> ``[R, P, 3]``
    points evenly spaced along each run's length, and ``[R]`` the points each run had."""
    counts = np.bincount(run, minlength=num_runs)
    first = np.concatenate([[0], np.cumsum(counts)[:-1]])
    step = np.linalg.norm(np.diff(points, axis=0), axis=1)
    step = np.concatenate([[0.0], np.where(run[1:] == run[:-1], step, 0.0)])
    along = np.cumsum(step)
    along -= along[first][run]  # arc length from the run's first point
    length = along[first + counts - 1]  # [R]
    gap = float(length.max()) + 1.0  # runs side by side on one increasing axis, for one np.interp
    xp = along + run * gap
    fractions = np.linspace(0.0, 1.0, num_points) if num_points > 1 else np.zeros(1)
    targets = (length[:, None] * fractions[None] + (np.arange(num_runs) * gap)[:, None]).reshape(-1)
    out = np.stack([np.interp(targets, xp, points[:, k]) for k in range(3)], -1)
    return out.reshape(num_runs, num_points, 3), counts
