"""Point queries against a log's road map (``MapFeature`` s), for the motion/location labeller and encoder.

Works with any source: the synthetic world (lanes, crosswalks, sidewalks, one drivable area) and
Argoverse 2 (lanes, crosswalks, drivable areas; no sidewalks). What is missing is reported by the
``has_*`` flags, and the labeller falls back to geometry alone.

Intersections are not a map kind in the shared model, so they are inferred: crosswalks whose
centroids lie within ``cluster_m`` of each other are grouped, and a group of at least two is an
intersection whose area is the convex hull of its crosswalks grown by ``margin_m`` (stop lines sit
1-2 m behind the crosswalks), restricted to the drivable area when one is known. A lone mid-block
crosswalk is not an intersection.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from simsplat_core.scenario.geometry import (
    ROAD_EDGE_ROAD_SIDE,
    convex_hull,
    points_in_polygon,
    polygon_edges,
    polyline_segments,
    segment_distances,
    signed_road_edge_distance,
)
from simsplat_core.types import MapFeature

_CHUNK = 512  # points per vectorised block (bounds the [points, segments] temporaries)


def _clusters(centroids: np.ndarray, max_dist: float) -> list[list[int]]:
    """Single-linkage groups of ``[N, 2]`` centroids closer than ``max_dist``."""
    n = len(centroids)
    parent = list(range(n))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for i in range(n):
        for j in range(i + 1, n):
            if np.linalg.norm(centroids[i] - centroids[j]) <= max_dist:
                parent[find(i)] = find(j)
    groups: dict[int, list[int]] = {}
    for i in range(n):
        groups.setdefault(find(i), []).append(i)
    return list(groups.values())


@dataclass(frozen=True)
class MapFacts:
    """Per-point map facts of ``N`` query points.

    Attributes:
        on_drivable: ``[N]`` inside a drivable-area polygon (all ``False`` when the map has none).
        on_sidewalk: ``[N]`` inside a sidewalk polygon.
        in_crosswalk: ``[N]`` inside a crosswalk polygon.
        at_intersection: ``[N]`` inside an inferred intersection area (see the module docstring).
        lane_dist: ``[N]`` distance to the nearest lane centre line, metres (``inf`` without lanes).
        lane_offset: ``[N]`` signed distance (positive = left) from the centre line of the nearest lane
            segment roughly aligned with the query heading (within ``align_deg``, either way round),
            the segment's direction taken to agree with the heading; ``nan`` where no such lane is
            within ``aligned_lane_m``. It jumps by about a lane width when the nearest lane switches.
    """

    on_drivable: np.ndarray
    on_sidewalk: np.ndarray
    in_crosswalk: np.ndarray
    at_intersection: np.ndarray
    lane_dist: np.ndarray
    lane_offset: np.ndarray

    def take(self, rows: np.ndarray | slice) -> MapFacts:
        """The facts of a subset of rows."""
        return MapFacts(*(getattr(self, f)[rows] for f in self.__dataclass_fields__))


@dataclass(frozen=True)
class MapContext:
    """A log's map prepared for point queries; build with ``MapContext.from_features``.

    Attributes:
        drivable, sidewalks, crosswalks: polygons ``[P, 2]``.
        intersections: inferred intersection hulls ``[H, 2]``.
        lane_a, lane_b: ``[S, 2]`` lane centre-line segments (in the direction of travel).
        margin_m: growth of the intersection hulls.
        aligned_lane_m, align_deg: search radius and angular tolerance of ``MapFacts.lane_offset``.
        edge_a, edge_b: ``[E, 2]`` road-edge segments (polyline order kept: the road is on their
            ``road_side``), edge_next / edge_prev ``[E]`` the neighbouring segment on the same polyline
            (``-1`` at ends); see ``geometry.polyline_segments``.
        road_side: side of the road-edge direction where the road is (``"left"`` in Waymo Open Motion).
    """

    drivable: tuple[np.ndarray, ...] = ()
    sidewalks: tuple[np.ndarray, ...] = ()
    crosswalks: tuple[np.ndarray, ...] = ()
    intersections: tuple[np.ndarray, ...] = ()
    lane_a: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    lane_b: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    margin_m: float = 1.5
    aligned_lane_m: float = 4.0
    align_deg: float = 35.0
    edge_a: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    edge_b: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    edge_next: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    edge_prev: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    road_side: str = ROAD_EDGE_ROAD_SIDE

    @classmethod
    def from_features(cls, features: tuple[MapFeature, ...] | list[MapFeature], cluster_m: float = 40.0,
                      margin_m: float = 1.5) -> MapContext:
        """Index ``features``; crosswalk groups within ``cluster_m`` become intersections."""
        by_kind: dict[str, list[np.ndarray]] = {}
        for feat in features:
            by_kind.setdefault(feat.kind, []).append(np.asarray(feat.points, dtype=np.float64)[:, :2])
        crosswalks = tuple(p for p in by_kind.get("crosswalk", []) if len(p) >= 3)
        intersections = []
        if crosswalks:
            centroids = np.stack([p.mean(axis=0) for p in crosswalks])
            for group in _clusters(centroids, cluster_m):
                if len(group) >= 2:
                    intersections.append(convex_hull(np.concatenate([crosswalks[i] for i in group])))
        lanes = [p for p in by_kind.get("lane", []) if len(p) >= 2]
        lane_a = np.concatenate([p[:-1] for p in lanes]) if lanes else np.zeros((0, 2))
        lane_b = np.concatenate([p[1:] for p in lanes]) if lanes else np.zeros((0, 2))
        keep = np.linalg.norm(lane_b - lane_a, axis=1) > 1e-6
        edge_a, edge_b, edge_next, edge_prev = polyline_segments(by_kind.get("road_edge", []))
        return cls(
            drivable=tuple(p for p in by_kind.get("drivable_area", []) if len(p) >= 3),
            sidewalks=tuple(p for p in by_kind.get("sidewalk", []) if len(p) >= 3),
            crosswalks=crosswalks,
            intersections=tuple(intersections),
            lane_a=lane_a[keep],
            lane_b=lane_b[keep],
            margin_m=margin_m,
            edge_a=edge_a,
            edge_b=edge_b,
            edge_next=edge_next,
            edge_prev=edge_prev,
        )

    @property
    def has_drivable(self) -> bool:
        return bool(self.drivable)

    @property
    def has_sidewalks(self) -> bool:
        return bool(self.sidewalks)

    @property
    def has_lanes(self) -> bool:
        return len(self.lane_a) > 0

    @property
    def has_road_edges(self) -> bool:
        return len(self.edge_a) > 0

    @property
    def road_edges(self) -> np.ndarray:
        """``[E, 2, 2]`` road-edge segments ``(a, b)`` (``MotionMap.road_edges``)."""
        return np.stack([self.edge_a, self.edge_b], axis=1) if self.has_road_edges else np.zeros((0, 2, 2))

    def road_edge_distance(self, xy: np.ndarray) -> np.ndarray:
        """``[N]`` signed distance of ``[N, 2]`` points to the nearest road edge: positive on the road side,
        ``+inf`` without road edges (``geometry.signed_road_edge_distance``)."""
        return signed_road_edge_distance(np.asarray(xy, dtype=np.float64).reshape(-1, 2), self.edge_a, self.edge_b,
                                         self.edge_next, self.edge_prev, self.road_side)

    def _inside_any(self, xy: np.ndarray, polygons: tuple[np.ndarray, ...]) -> np.ndarray:
        out = np.zeros(len(xy), dtype=bool)
        for poly in polygons:
            lo, hi = poly.min(axis=0), poly.max(axis=0)
            near = np.all((xy >= lo) & (xy <= hi), axis=1)
            if near.any():
                out[near] |= points_in_polygon(xy[near], poly)
        return out

    def _in_intersection(self, xy: np.ndarray) -> np.ndarray:
        out = np.zeros(len(xy), dtype=bool)
        for hull in self.intersections:
            inside = points_in_polygon(xy, hull) if len(hull) >= 3 else np.zeros(len(xy), dtype=bool)
            a, b = polygon_edges(hull)
            out |= inside | (segment_distances(xy, a, b).min(axis=1) <= self.margin_m)
        return out

    def _lanes(self, xy: np.ndarray, heading: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``([N] distance to the nearest lane, [N] signed offset from the nearest aligned lane)``."""
        n = len(xy)
        dist = np.full(n, np.inf)
        offset = np.full(n, np.nan)
        if not self.has_lanes:
            return dist, offset
        seg_dir = self.lane_b - self.lane_a
        seg_dir /= np.linalg.norm(seg_dir, axis=1, keepdims=True)
        cos_tol = np.cos(np.deg2rad(self.align_deg))
        for start in range(0, n, _CHUNK):
            rows = slice(start, start + _CHUNK)
            p = xy[rows]
            d = segment_distances(p, self.lane_a, self.lane_b)  # [n, S]
            dist[rows] = d.min(axis=1)
            h = np.stack([np.cos(heading[rows]), np.sin(heading[rows])], axis=1)  # [n, 2]
            cos = h @ seg_dir.T  # [n, S]
            d_aligned = np.where(np.abs(cos) >= cos_tol, d, np.inf)
            best = np.argmin(d_aligned, axis=1)
            idx = np.arange(len(best))
            ok = d_aligned[idx, best] <= self.aligned_lane_m
            direction = seg_dir[best] * np.sign(cos[idx, best])[:, None]  # [n, 2], agrees with the heading
            rel = p - self.lane_a[best]
            signed = direction[:, 0] * rel[:, 1] - direction[:, 1] * rel[:, 0]  # left of the lane = positive
            offset[rows] = np.where(ok, signed, np.nan)
        return dist, offset

    def facts(self, xy: np.ndarray, heading: np.ndarray) -> MapFacts:
        """Map facts of ``[N, 2]`` world points with ``[N]`` headings (radians)."""
        xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        heading = np.asarray(heading, dtype=np.float64).reshape(-1)
        on_drivable = self._inside_any(xy, self.drivable)
        at_intersection = self._in_intersection(xy)
        if self.has_drivable:
            at_intersection &= on_drivable
        lane_dist, lane_offset = self._lanes(xy, heading)
        return MapFacts(
            on_drivable=on_drivable,
            on_sidewalk=self._inside_any(xy, self.sidewalks),
            in_crosswalk=self._inside_any(xy, self.crosswalks),
            at_intersection=at_intersection,
            lane_dist=lane_dist,
            lane_offset=lane_offset,
        )
