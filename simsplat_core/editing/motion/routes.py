"""Where an edited agent goes: routes (arc-length paths with headings) for the motion controller.

A :class:`Route` is a ``scenario.path.Path`` plus the agent's heading at each path point (the path's own
tangent, or a log's box headings); positions beyond either end extrapolate straight (``Path.position``),
headings hold the end values. Routes are built from:

* a log trajectory (:func:`log_route`: the agent's own path, its headings kept);
* the lane graph (:func:`lane_route`: ``LaneGraph.follow`` through the next intersection with a manoeuvre);
* a straight line through a pose (:func:`straight_route`), or any polyline (:func:`polyline_route`);
* :func:`merge_onto`: drive one route up to a point, then continue on another, the lateral gap between the
  two closed by a quintic ramp along the new route (turns from a log path onto the lane graph, lane
  changes, sideways shifts), so positions, headings and curvature stay continuous.

Also: :func:`next_area_s` (where a route first enters a crosswalk / intersection ahead),
:func:`curvature_caps` (curve speed bounds for ``editing.motion.speed_profile``), :func:`crosswalk_ends` and
:func:`nearest_lane_segment` (map geometry the controller and the placement share).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from simsplat_core.editing.motion.speed_profile import SpeedCaps
from simsplat_core.scenario.geometry import segment_distances
from simsplat_core.scenario.lane_graph import LaneGraph, LanePath
from simsplat_core.scenario.map_context import MapContext
from simsplat_core.scenario.path import Path

#: Resampling step of baked route parts, metres.
STEP_M = 0.5


def quintic(u: np.ndarray) -> np.ndarray:
    """``[...]`` smooth ramp 0 -> 1 on ``u`` in [0, 1] (zero slope and curvature at both ends), clamped."""
    u = np.clip(u, 0.0, 1.0)
    return u ** 3 * (10.0 - 15.0 * u + 6.0 * u * u)


def quintic_slope(u: np.ndarray) -> np.ndarray:
    """``[...]`` derivative of :func:`quintic` with respect to ``u`` (0 outside [0, 1])."""
    inside = (u >= 0.0) & (u <= 1.0)
    return np.where(inside, 30.0 * u * u * (1.0 - u) ** 2, 0.0)


@dataclass(frozen=True)
class Route:
    """A path with the agent's heading at each of its points.

    Attributes:
        path: world path, arc length ``path.s``.
        headings: ``[N]`` unwrapped yaw at ``path.points`` (radians).
        marks: named arc lengths (``"join"``: where a merged route leaves its first part; ``"turn"``: where the
            turning lane begins).
    """

    path: Path
    headings: np.ndarray
    marks: dict[str, float] = field(default_factory=dict)

    @property
    def length(self) -> float:
        return self.path.length

    def position(self, s: np.ndarray | float) -> np.ndarray:
        """``[..., 2]`` world xy at arc lengths ``s``."""
        return self.path.position(s)

    def heading(self, s: np.ndarray | float) -> np.ndarray:
        """``[...]`` heading at arc lengths ``s`` (held beyond the ends)."""
        return np.interp(np.asarray(s, dtype=np.float64), self.path.s, self.headings)

    def project(self, xy: np.ndarray) -> tuple[float, float]:
        """``(s, lateral)`` of world point ``xy [2]``: arc length of its closest path point and its signed offset
        from the path there (positive = left of the heading), with straight extrapolation before the start."""
        p = np.asarray(xy, dtype=np.float64)[:2]
        s = self.path.project(p)
        if s <= 1e-9:  # before the start: along the first tangent, possibly negative
            s = float(np.dot(p - self.path.points[0], _unit(float(self.heading(0.0)))))
        elif s >= self.length - 1e-9:
            s = self.length + float(np.dot(p - self.path.points[-1], _unit(float(self.heading(self.length)))))
        h = float(self.heading(s))
        return s, float(np.dot(p - self.position(s), np.array([-np.sin(h), np.cos(h)])))


def _unit(yaw: float) -> np.ndarray:
    return np.array([np.cos(yaw), np.sin(yaw)])


def polyline_route(points: np.ndarray, headings: np.ndarray | None = None, smooth: int = 0) -> Route:
    """Route over ``[N, 2]`` points (N >= 2, distinct), headings ``[N]`` or the path's tangents; ``smooth``
    Chaikin corner-cutting passes round the corners first (``headings`` must then be ``None``)."""
    pts = np.asarray(points, dtype=np.float64)[:, :2]
    for _ in range(smooth):
        q = 0.75 * pts[:-1] + 0.25 * pts[1:]
        r = 0.25 * pts[:-1] + 0.75 * pts[1:]
        pts = np.concatenate([pts[:1], np.stack([q, r], axis=1).reshape(-1, 2), pts[-1:]])
    keep = np.concatenate([[True], np.linalg.norm(np.diff(pts, axis=0), axis=1) > 1e-6])
    path = Path.from_points(pts[keep])
    if headings is None:
        return Route(path, np.asarray(path.heading(path.s), dtype=np.float64))
    return Route(path, np.unwrap(np.asarray(headings, dtype=np.float64)[keep]))


def smooth_route(path: Path, window_m: float = 4.0, passes: int = 2) -> Route:
    """``path`` resampled every ``STEP_M`` and smoothed by ``passes`` moving averages over ``window_m``
    (straight extrapolation beyond the ends), tangent headings: rounds off the small steps where lane
    centre lines of a map meet (a connector ending beside the lane it joins) and keeps curves within a few
    centimetres."""
    half = int(round(window_m / STEP_M / 2.0))
    pad = half * passes
    s = np.arange(-pad * STEP_M, path.length + (pad + 1) * STEP_M, STEP_M)
    pts = path.position(s)
    kernel = np.ones(2 * half + 1) / (2 * half + 1)
    for _ in range(passes):
        pts = np.stack([np.convolve(pts[:, c], kernel, mode="same") for c in range(2)], axis=1)
    return polyline_route(pts[pad:len(pts) - pad])


def straight_route(xy: np.ndarray, heading: float, back_m: float = 100.0, ahead_m: float = 400.0) -> Route:
    """Straight line through the pose ``(xy [2], heading)``; the pose is at arc length ``back_m``."""
    d = _unit(heading)
    p = np.asarray(xy, dtype=np.float64)[:2]
    route = polyline_route(np.stack([p - back_m * d, p + ahead_m * d]))
    return Route(route.path, np.full(2, heading))


def log_route(xy: np.ndarray, heading: np.ndarray, min_step_m: float = 0.5, min_length_m: float = 1.0) -> Route | None:
    """The path of a log trajectory (``xy [K, 2]``, ``heading [K]`` at its valid steps, in order) with its
    box headings, in the direction the boxes face: a point is kept when it lies at least ``min_step_m``
    from the last kept one and ahead of it (box jitter of a standing agent and annotation wobble do not
    fold the path back). ``None`` when it moves less than ``min_length_m`` (a parked car has no path)."""
    xy = np.asarray(xy, dtype=np.float64)
    heading = np.unwrap(np.asarray(heading, dtype=np.float64))
    if len(xy) < 2:
        return None
    keep = [0]
    for k in range(1, len(xy)):
        step = xy[k] - xy[keep[-1]]
        ahead = float(np.dot(step, _unit(float(heading[keep[-1]]))))
        if np.linalg.norm(step) >= min_step_m and ahead >= 0.5 * min_step_m:
            keep.append(k)
    if len(keep) < 2:
        return None
    route = polyline_route(xy[keep], heading[keep])
    return route if route.length >= min_length_m else None


def lane_route(lanes: LaneGraph | None, xy: np.ndarray, heading: float, manoeuvre: str = "straight",
               max_length_m: float = 300.0, max_dist_m: float = 2.5,
               align_deg: float = 45.0) -> tuple[Route, LanePath] | None:
    """Lane-following route from the pose (``LaneGraph.follow``), ``None`` without a lane aligned with the
    heading within ``max_dist_m``. ``marks["turn"]``: arc length where the first lane making the
    manoeuvre begins (left / right turns that were made)."""
    if lanes is None or not len(lanes):
        return None
    p = np.asarray(xy, dtype=np.float64)[:2]
    match = lanes.nearest(p[None], np.array([heading]), align_deg=align_deg, max_dist_m=max_dist_m)
    if match.lane[0] < 0:
        return None
    lp = lanes.follow(p, heading, manoeuvre, max_length_m=max_length_m)
    route = smooth_route(lp.path)
    marks = {}
    if manoeuvre in ("left", "right") and lp.turn_taken:
        for k, lane in enumerate(lp.lanes):
            if k > 0 and lanes.turn_of(lane) == manoeuvre:
                marks["turn"] = lp.lane_span(k)[0]
                marks["turn_end"] = lp.lane_span(k)[1]
                break
    return Route(route.path, route.headings, marks), lp


def merge_onto(before: Route | None, s_join: float, after: Route, ramp_m: float,
               final_offset_m: float = 0.0, point: np.ndarray | None = None) -> Route:
    """Drive ``before`` up to arc length ``s_join``, then ``after``.

    The join point (``before.position(s_join)``, or ``point`` when ``before`` is ``None``) is projected onto
    ``after`` at ``(s_a, lateral)``; from there the route follows ``after`` with a lateral offset easing
    from ``lateral`` to ``final_offset_m`` over ``ramp_m`` metres (quintic), then held. The result's arc
    length equals ``before``'s up to ``s_join`` (``marks["join"] = s_join``); without ``before`` the route
    starts ``STEP_M * 4`` behind the join point along ``after`` and ``marks["join"]`` is the point's arc length.
    ``after``'s marks move with it (a mark behind the join point, e.g. a turn already begun, lands before
    ``marks["join"]``).
    """
    p = before.position(s_join) if before is not None else np.asarray(point, dtype=np.float64)[:2]
    s_a, lateral = after.project(p)
    # sampled to the end of ``after`` and of the ramp (which may run on past it, straight), then 50 m on
    sampled = max(after.length - s_a, ramp_m, 0.0) + STEP_M
    ds = np.arange(-4 * STEP_M if before is None else 0.0, sampled, STEP_M)
    ds = np.concatenate([ds, [ds[-1] + 50.0]])  # run on past the end (straight)
    u = ds / max(ramp_m, 1e-6)
    offset = lateral + (final_offset_m - lateral) * quintic(u)
    slope = (final_offset_m - lateral) * quintic_slope(u) / max(ramp_m, 1e-6)
    if before is None:
        offset[ds < 0] = lateral
        slope[ds < 0] = 0.0
    base_h = after.heading(s_a + ds)
    pts = after.position(s_a + ds) + offset[:, None] * np.stack([-np.sin(base_h), np.cos(base_h)], axis=1)
    heads = base_h + np.arctan(slope)
    marks_after = {k: v - s_a for k, v in after.marks.items()}
    if before is None:
        route = polyline_route(pts, heads)
        join = 4 * STEP_M
        return Route(route.path, route.headings, {"join": join} | {k: join + v for k, v in marks_after.items()})
    keep = before.path.s < s_join - 1e-6
    pts = np.concatenate([before.path.points[keep], pts])
    heads = np.concatenate([before.headings[keep], heads])
    heads = np.concatenate([heads[:1], heads[0] + np.cumsum(np.angle(np.exp(1j * np.diff(heads))))])
    route = polyline_route(pts, heads)
    marks = {k: v for k, v in before.marks.items() if v < s_join} | {"join": s_join}
    return Route(route.path, route.headings, marks | {k: s_join + v for k, v in marks_after.items()})


def offset_route(route: Route, s_from: float, offset_m: float, ramp_m: float) -> Route:
    """``route`` shifted sideways by ``offset_m`` (positive = left) from ``s_from`` on, eased in over ``ramp_m``."""
    return merge_onto(route, s_from, route, ramp_m, final_offset_m=offset_m)


def passing_route(route: Route, s_from: float, s_until: float, offset_m: float, ramp_m: float) -> Route:
    """``route`` shifted sideways by ``offset_m`` (positive = left) from ``s_from``, eased in over ``ramp_m``,
    and eased back onto it from ``s_until`` (at least ``ramp_m`` later) on: a step aside to pass someone."""
    aside = offset_route(route, s_from, offset_m, ramp_m)
    return merge_onto(aside, max(s_until, s_from + ramp_m), route, ramp_m, final_offset_m=0.0)


def crosswalk_ends(polygon: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The two ends ``([2], [2])`` of a crosswalk polygon's long axis (where people step on and off it)."""
    pts = np.asarray(polygon, dtype=np.float64)[:, :2]
    centre = pts.mean(axis=0)
    axis = np.linalg.svd(pts - centre)[2][0]
    along = (pts - centre) @ axis
    return centre + along.min() * axis, centre + along.max() * axis


def nearest_lane_segment(map_ctx: MapContext, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, float] | None:
    """``(foot [2], unit direction of travel [2], distance)`` of the lane centre-line segment nearest the point
    ``xy [2]`` (any direction), ``None`` on a map without lanes."""
    if not map_ctx.has_lanes:
        return None
    p = np.asarray(xy, dtype=np.float64)[:2]
    dist = segment_distances(p[None], map_ctx.lane_a, map_ctx.lane_b)[0]
    k = int(np.argmin(dist))
    a, b = map_ctx.lane_a[k], map_ctx.lane_b[k]
    ab = b - a
    t = float(np.clip(np.dot(p - a, ab) / np.dot(ab, ab), 0.0, 1.0))
    return a + t * ab, ab / np.linalg.norm(ab), float(dist[k])


def next_area_s(route: Route, map_ctx: MapContext, kind: str, s_from: float, max_ahead_m: float = 200.0,
                step_m: float = 0.25) -> float | None:
    """Arc length where the route next enters a ``kind`` area (``"crosswalk"`` or ``"intersection"``) after
    ``s_from`` (an area it starts inside is skipped), ``None`` when none within ``max_ahead_m``."""
    if kind not in ("crosswalk", "intersection"):
        raise ValueError(f"kind must be 'crosswalk' or 'intersection', got {kind!r}")
    s = s_from + np.arange(0.0, max_ahead_m + step_m, step_m)
    facts = map_ctx.facts(route.position(s), route.heading(s))
    inside = facts.in_crosswalk if kind == "crosswalk" else facts.at_intersection
    entries = np.flatnonzero(inside[1:] & ~inside[:-1]) + 1
    return float(s[entries[0]]) if entries.size else None


def curvature_caps(route: Route, s_from: float, s_to: float, lateral_accel_mps2: float,
                   min_speed_mps: float = 2.0, step_m: float = 1.0, window_m: float = 4.0) -> SpeedCaps | None:
    """Curve speed bounds ``sqrt(lateral_accel / curvature)`` along ``[s_from, s_to]`` (curvature from heading
    change over ``window_m``), ``None`` on a straight route or without a lateral bound."""
    if not np.isfinite(lateral_accel_mps2) or s_to <= s_from:
        return None
    s = np.arange(s_from, s_to + step_m, step_m)
    half = window_m / 2.0
    kappa = np.abs(route.heading(s + half) - route.heading(s - half)) / window_m
    v = np.sqrt(lateral_accel_mps2 / np.maximum(kappa, 1e-9))
    tight = v < 40.0
    if not tight.any():
        return None
    return SpeedCaps(s[tight], np.maximum(v[tight], min_speed_mps))
