"""Agent and map geometry in the ground plane: polygons, segment distances, oriented boxes.

Vectorised with numpy, metres, world (or any common) frame:

* polygon point tests, point-to-segment distances and convex hulls (used by ``map_context.py``);
* oriented-box overlap by the separating-axis test, vectorised over frames and agent pairs (``footprints_overlap``;
  the world's population step rejects candidates with it);
* signed distances of box corners to the drivable area's boundary (``corner_road_distances``,
  ``offroad``): positive inside the drivable area, negative outside.
"""

from __future__ import annotations

import numpy as np


def points_in_polygon(xy: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """``[N]`` bool: even-odd test of ``[N, 2]`` points against a closed ``[P, 2]`` polygon."""
    xy = np.atleast_2d(xy)
    a = polygon[:, :2]
    b = np.roll(a, -1, axis=0)
    x, y = xy[:, 0:1], xy[:, 1:2]  # [N, 1]
    straddle = (a[None, :, 1] > y) != (b[None, :, 1] > y)  # [N, P]
    with np.errstate(divide="ignore", invalid="ignore"):
        slope = (b[None, :, 0] - a[None, :, 0]) / (b[None, :, 1] - a[None, :, 1])
        x_cross = a[None, :, 0] + (y - a[None, :, 1]) * slope
    return np.count_nonzero(straddle & (x < x_cross), axis=1) % 2 == 1


def segment_distances(xy: np.ndarray, seg_a: np.ndarray, seg_b: np.ndarray) -> np.ndarray:
    """``[N, S]`` distances from ``[N, 2]`` points to ``[S, 2]`` segments ``a -> b``."""
    ab = seg_b - seg_a  # [S, 2]
    rel = xy[:, None, :] - seg_a[None]  # [N, S, 2]
    t = np.clip((rel * ab[None]).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-12)[None], 0.0, 1.0)
    return np.linalg.norm(rel - t[..., None] * ab[None], axis=-1)


def polygon_edges(polygon: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Edges ``([P, 2], [P, 2])`` of a closed polygon."""
    a = polygon[:, :2]
    return a, np.roll(a, -1, axis=0)


def convex_hull(points: np.ndarray) -> np.ndarray:
    """Counter-clockwise convex hull ``[H, 2]`` of ``[N, 2]`` points (Andrew's monotone chain)."""
    pts = np.unique(np.asarray(points, dtype=np.float64)[:, :2], axis=0)
    if len(pts) < 3:
        return pts

    def half(seq: np.ndarray) -> list[np.ndarray]:
        out: list[np.ndarray] = []
        for p in seq:
            while len(out) >= 2 and np.cross(out[-1] - out[-2], p - out[-2]) <= 0:
                out.pop()
            out.append(p)
        return out

    lower, upper = half(pts), half(pts[::-1])
    return np.array(lower[:-1] + upper[:-1])


def footprints_overlap(
    center_a: np.ndarray,
    heading_a: np.ndarray,
    size_a: tuple[float, float] | np.ndarray,
    center_b: np.ndarray,
    heading_b: np.ndarray,
    size_b: tuple[float, float] | np.ndarray,
    margin: float = 0.0,
) -> np.ndarray:
    """Per-frame overlap of two oriented rectangles (separating-axis test), broadcasting over leading axes.

    Args:
        center_a, center_b: ``[..., 2]`` footprint centres (e.g. ``[T, 2]``, or ``[A, 1, T, 2]`` against
            ``[1, B, T, 2]`` for every pair).
        heading_a, heading_b: ``[...]`` yaw of the length axis.
        size_a, size_b: ``(length, width)``, or ``[..., 2]`` arrays broadcasting like the headings.
        margin: clearance added to both half extents of ``a``.

    Returns:
        ``[...]`` bool (the broadcast shape), true where the rectangles (``a`` grown by ``margin``) intersect.
    """
    size_a = np.asarray(size_a, dtype=np.float64)
    size_b = np.asarray(size_b, dtype=np.float64)
    la, wa = size_a[..., 0] / 2.0 + margin, size_a[..., 1] / 2.0 + margin
    lb, wb = size_b[..., 0] / 2.0, size_b[..., 1] / 2.0
    ua = np.stack([np.cos(heading_a), np.sin(heading_a)], axis=-1)
    va = np.stack([-np.sin(heading_a), np.cos(heading_a)], axis=-1)
    ub = np.stack([np.cos(heading_b), np.sin(heading_b)], axis=-1)
    vb = np.stack([-np.sin(heading_b), np.cos(heading_b)], axis=-1)
    delta = np.asarray(center_b, dtype=np.float64) - np.asarray(center_a, dtype=np.float64)
    separated = np.zeros(np.broadcast_shapes(delta.shape[:-1], ua.shape[:-1], ub.shape[:-1]), dtype=bool)
    for axis in (ua, va, ub, vb):
        ra = la * np.abs(np.sum(ua * axis, -1)) + wa * np.abs(np.sum(va * axis, -1))
        rb = lb * np.abs(np.sum(ub * axis, -1)) + wb * np.abs(np.sum(vb * axis, -1))
        separated |= np.abs(np.sum(delta * axis, -1)) > ra + rb
    return ~separated


def box_footprints(center: np.ndarray, heading: np.ndarray, size: np.ndarray) -> np.ndarray:
    """``[..., 4, 2]`` counter-clockwise corners of oriented rectangles.

    Args:
        center: ``[..., 2]`` centres.
        heading: ``[...]`` yaw of the length axis, radians.
        size: ``[..., 2]`` (or ``[2]``) ``(length, width)``.
    """
    center = np.asarray(center, dtype=np.float64)
    heading = np.asarray(heading, dtype=np.float64)
    half = 0.5 * np.broadcast_to(np.asarray(size, dtype=np.float64)[..., :2], center.shape)  # [..., 2]
    u = np.stack([np.cos(heading), np.sin(heading)], axis=-1)  # [..., 2]
    v = np.stack([-np.sin(heading), np.cos(heading)], axis=-1)
    signs = np.array([[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]])  # [4, 2] (along, across)
    hl = half[..., None, 0:1] * signs[:, 0:1]  # [..., 4, 1]
    hw = half[..., None, 1:2] * signs[:, 1:2]
    return center[..., None, :] + hl * u[..., None, :] + hw * v[..., None, :]


def signed_polygon_distance(xy: np.ndarray, polygons: tuple[np.ndarray, ...] | list[np.ndarray]) -> np.ndarray:
    """``[N]`` signed distance of ``[N, 2]`` points to the union of closed polygons ``[P_k, 2]``.

    Positive inside some polygon (distance to the nearest edge), negative outside (minus the distance
    to the nearest edge), ``-inf`` without polygons. Edges shared by two adjacent polygons (a drivable
    area cut into tiles) count as boundary too, so a point just inside a tile seam is reported close to
    the edge, never outside.
    """
    xy = np.atleast_2d(np.asarray(xy, dtype=np.float64))[:, :2]
    if not polygons:
        return np.full(len(xy), -np.inf)
    inside = np.zeros(len(xy), dtype=bool)
    dist = np.full(len(xy), np.inf)
    for poly in polygons:
        poly = np.asarray(poly, dtype=np.float64)[:, :2]
        inside |= points_in_polygon(xy, poly)
        a, b = polygon_edges(poly)
        dist = np.minimum(dist, segment_distances(xy, a, b).min(axis=1))
    return np.where(inside, dist, -dist)


def corner_road_distances(
    center: np.ndarray, heading: np.ndarray, size: np.ndarray, drivable: tuple[np.ndarray, ...] | list[np.ndarray]
) -> np.ndarray:
    """``[T, 4]`` signed distance of each box corner to the drivable area (positive inside, metres).

    Args:
        center: ``[T, 2]`` box centres; heading: ``[T]``; size: ``(length, width)``.
        drivable: drivable-area polygons ``[P_k, 2]``.
    """
    corners = box_footprints(center, heading, size)  # [T, 4, 2]
    return signed_polygon_distance(corners.reshape(-1, 2), drivable).reshape(corners.shape[:-1])


def offroad(
    center: np.ndarray,
    heading: np.ndarray,
    size: np.ndarray,
    drivable: tuple[np.ndarray, ...] | list[np.ndarray],
    tolerance_m: float = 0.0,
) -> np.ndarray:
    """``[T]`` bool: some corner of the box lies more than ``tolerance_m`` outside the drivable area.

    Same answer as ``corner_road_distances(...).min(axis=-1) < -tolerance_m``; edge distances are computed
    only for corners outside every polygon (polygons are skipped by their bounding boxes).
    """
    corners = box_footprints(center, heading, size)  # [T, 4, 2]
    flat = corners.reshape(-1, 2)
    outside = np.ones(len(flat), dtype=bool)
    polys = [np.asarray(p, dtype=np.float64)[:, :2] for p in drivable]
    for poly in polys:
        near = outside & np.all((flat >= poly.min(axis=0)) & (flat <= poly.max(axis=0)), axis=1)
        if near.any():
            outside[near] &= ~points_in_polygon(flat[near], poly)
    if tolerance_m > 0.0 and outside.any() and polys:
        rows = np.flatnonzero(outside)
        dist = np.full(len(rows), np.inf)
        for poly in polys:
            a, b = polygon_edges(poly)
            dist = np.minimum(dist, segment_distances(flat[rows], a, b).min(axis=1))
        outside[rows] = dist > tolerance_m
    return np.asarray(outside.reshape(corners.shape[:-1]).any(axis=-1))
