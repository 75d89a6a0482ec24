"""Agent and map geometry in the ground plane: polygons, segment distances, oriented boxes.

Vectorised with numpy, metres, world (or any common) frame:

* polygon point tests, point-to-segment distances and convex hulls (used by ``map_context.py``);
* oriented-box overlap by the separating-axis test, vectorised over frames and agent pairs (``footprints_overlap``;
  the world's population step rejects candidates with it);
* signed distances of box corners to the drivable area's boundary (``corner_road_distances``,
  ``offroad``): positive inside the drivable area, negative outside;
* on maps with road edges but no drivable polygons (Waymo Open Motion), Waymax's definition
  (``waymax.metrics.roadgraph.compute_signed_distance_to_nearest_road_edge_point``): the distance to the
  nearest road-edge segment, signed by the side of that segment the point is on (``polyline_segments``,
  ``signed_road_edge_distance``, ``offroad_by_road_edges``). Waymax's sign is the opposite of ours
  (positive = off-road there); ours stays positive on the road like the polygon distances.
"""

from __future__ import annotations

import numpy as np

#: Side of a road edge's direction where the road is, in Waymo Open Motion's map (and Waymax): the
#: road lies to the LEFT of each road-edge polyline (Waymax: ``cross(point - edge, edge_dir) > 0``, the
#: point to the right, is off-road). Checked on the WOMD sample: logged vehicles are on the left.
ROAD_EDGE_ROAD_SIDE = "left"
_EDGE_CHUNK = 256  # query points per vectorised block of ``signed_road_edge_distance``


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


def polyline_segments(polylines: list[np.ndarray] | tuple[np.ndarray, ...]) -> tuple[np.ndarray, np.ndarray,
                                                                                 np.ndarray, np.ndarray]:
    """The segments of ``[P_k, 2+]`` polylines, with their neighbours along the same polyline.

    Returns:
        ``(seg_a [E, 2], seg_b [E, 2], next_seg [E], prev_seg [E])``: segment ``e`` runs ``seg_a[e] ->
        seg_b[e]`` (polyline order kept); ``next_seg`` / ``prev_seg`` index the segment that continues /
        precedes it on the same polyline, ``-1`` at the polyline's ends (a closed polyline, first point
        equal to the last, wraps around). Zero-length segments are dropped.
    """
    seg_a, seg_b, nxt, prv = [], [], [], []
    offset = 0
    for line in polylines:
        pts = np.asarray(line, dtype=np.float64)[:, :2]
        if len(pts) >= 2:
            keep = np.concatenate([[True], np.linalg.norm(np.diff(pts, axis=0), axis=1) > 1e-6])
            pts = pts[keep]
        if len(pts) < 2:
            continue
        n = len(pts) - 1
        idx = offset + np.arange(n)
        closed = n >= 3 and bool(np.linalg.norm(pts[0] - pts[-1]) <= 1e-6)
        nxt_k = np.append(idx[1:], idx[0] if closed else -1)
        prv_k = np.concatenate([[idx[-1] if closed else -1], idx[:-1]])
        seg_a.append(pts[:-1])
        seg_b.append(pts[1:])
        nxt.append(nxt_k)
        prv.append(prv_k)
        offset += n
    if not seg_a:
        return np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0, np.int64), np.zeros(0, np.int64)
    return (np.concatenate(seg_a), np.concatenate(seg_b), np.concatenate(nxt).astype(np.int64),
            np.concatenate(prv).astype(np.int64))


def signed_road_edge_distance(
    xy: np.ndarray,
    seg_a: np.ndarray,
    seg_b: np.ndarray,
    next_seg: np.ndarray | None = None,
    prev_seg: np.ndarray | None = None,
    road_side: str = ROAD_EDGE_ROAD_SIDE,
) -> np.ndarray:
    """``[N]`` signed distance of ``[N, 2]`` points to the nearest road-edge segment: positive on the road
    side (``road_side`` of the segment's direction, ``"left"`` or ``"right"``), negative off it, ``+inf``
    without segments (nothing is off-road on a map without edges).

    Where the nearest point is a vertex joining two segments of one polyline (``next_seg`` / ``prev_seg``
    from :func:`polyline_segments`), the side is taken against the sum of both unit directions (the
    vertex's bisector), which is right at convex and concave bends alike (Waymax compares the two
    half-planes instead, and calls a point beyond a convex corner on-road).
    """
    if road_side not in ("left", "right"):
        raise ValueError(f"road_side must be 'left' or 'right', got {road_side!r}")
    xy = np.atleast_2d(np.asarray(xy, dtype=np.float64))[:, :2]
    out = np.full(len(xy), np.inf)
    if len(seg_a) == 0 or len(xy) == 0:
        return out
    e = len(seg_a)
    next_seg = np.full(e, -1) if next_seg is None else np.asarray(next_seg, dtype=np.int64)
    prev_seg = np.full(e, -1) if prev_seg is None else np.asarray(prev_seg, dtype=np.int64)
    ab = seg_b - seg_a  # [E, 2]
    length2 = np.maximum((ab * ab).sum(-1), 1e-12)
    unit = ab / np.sqrt(length2)[:, None]
    side = 1.0 if road_side == "left" else -1.0
    seg_lo, seg_hi = np.minimum(seg_a, seg_b), np.maximum(seg_a, seg_b)  # [E, 2] segment bounding boxes
    for start in range(0, len(xy), _EDGE_CHUNK):
        p = xy[start:start + _EDGE_CHUNK]  # [n, 2]
        # Candidates: segments whose bounding box is no farther from the chunk's than some segment's far end
        # is from every corner of it (an upper bound of each point's nearest distance).
        lo, hi = p.min(axis=0), p.max(axis=0)
        box = np.array([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]])  # [4, 2]
        upper = np.sqrt(((box[None] - seg_a[:, None]) ** 2).sum(-1)).max(axis=1).min()
        gap = np.maximum(np.maximum(seg_lo - hi, lo - seg_hi), 0.0)  # [E, 2]
        cand = np.flatnonzero(np.sqrt((gap ** 2).sum(-1)) <= upper + 1e-9)  # [C], never empty
        rel = p[:, None, :] - seg_a[cand][None]  # [n, C, 2]
        t_c = np.clip((rel * ab[cand][None]).sum(-1) / length2[cand][None], 0.0, 1.0)  # [n, C]
        d2_c = ((rel - t_c[..., None] * ab[cand][None]) ** 2).sum(-1)
        best = np.argmin(d2_c, axis=1)  # [n]
        k = cand[best]
        rows = np.arange(len(p))
        tk = t_c[rows, best]
        nearest = seg_a[k] + tk[:, None] * ab[k]
        direction = unit[k].copy()
        at_end = (tk >= 1.0 - 1e-9) & (next_seg[k] >= 0)
        at_start = (tk <= 1e-9) & (prev_seg[k] >= 0)
        direction[at_end] += unit[next_seg[k[at_end]]]
        direction[at_start] += unit[prev_seg[k[at_start]]]
        flat = np.linalg.norm(direction, axis=1) < 1e-9  # a hairpin: the two directions cancel
        direction[flat] = unit[k[flat]]
        to_p = p - nearest
        cross = direction[:, 0] * to_p[:, 1] - direction[:, 1] * to_p[:, 0]  # > 0: left of the edge
        dist = np.sqrt(d2_c[rows, best])
        out[start:start + len(p)] = np.where(side * cross >= 0.0, dist, -dist)
    return out


def offroad_by_road_edges(
    center: np.ndarray,
    heading: np.ndarray,
    size: np.ndarray,
    seg_a: np.ndarray,
    seg_b: np.ndarray,
    next_seg: np.ndarray | None = None,
    prev_seg: np.ndarray | None = None,
    tolerance_m: float = 0.0,
    road_side: str = ROAD_EDGE_ROAD_SIDE,
) -> np.ndarray:
    """``[T]`` bool: some box corner lies more than ``tolerance_m`` on the non-road side of its nearest
    road edge (Waymax ``is_offroad``; see :func:`signed_road_edge_distance`).

    Args:
        center: ``[T, 2]`` box centres; heading: ``[T]``; size: ``(length, width)``.
        seg_a, seg_b, next_seg, prev_seg: road-edge segments (:func:`polyline_segments`).
    """
    corners = box_footprints(center, heading, size)  # [T, 4, 2]
    dist = signed_road_edge_distance(corners.reshape(-1, 2), seg_a, seg_b, next_seg, prev_seg, road_side)
    return np.asarray((dist.reshape(corners.shape[:-1]) < -tolerance_m).any(axis=-1))
