"""Each free agent's route: the 1-D path (``scenario.path.Path``) it moves along, and its desired speeds.

* From the log (``use_log_routes`` and a logged future of at least ``RouteParams.min_route_m``): the
  agent's valid logged positions (history and future), thinned (box jitter of a stopped agent dropped)
  and smoothed, continued on the lane graph (vehicles near a lane) or straight along the final heading
  (``Path`` extrapolates), so an agent never runs out of path. Keeps intent: a logged right turn stays one.
* From the lane graph otherwise (vehicles): ``LaneGraph.follow`` straight on from the last observed pose.
* Pedestrians without a logged path walk straight along their heading.

Desired speed ``v_ref [T]``: the speed along the route the log implies (differences of the logged
positions' arc lengths; the logged speed on lane-graph routes), held after the last valid step and averaged
over ``RouteParams.speed_window_s`` (box jitter); without a logged route, scaled to cover no more than the log's
displacement by its last valid step (a box jittering in place, its velocity field noise, stays in place).

Agents that cannot be driven get a reason instead (:data:`REASONS`): replayed, never silently dropped.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from simsplat_core.motion.predictor import RolloutRequest
from simsplat_core.motion.traffic_params import PedestrianParams, RouteParams
from simsplat_core.scenario.geometry import segment_distances
from simsplat_core.scenario.lane_graph import LaneGraph
from simsplat_core.scenario.metrics import STATIC, kind_of
from simsplat_core.scenario.path import Path
from simsplat_core.scenario.trajectory import moving_average
from simsplat_core.scenario.vocabulary import PEDESTRIAN, VEHICLE

logger = logging.getLogger(__name__)

#: Why a free agent is replayed from the log.
APPEARS_LATER = "appears after start"
NOT_OBSERVED = "not observed at start"
SHORT_HISTORY = "history too short"
STATIC_OBJECT = "static object"
STATIONARY = "stationary in the log"
PARKED_JITTER = "parked in the log (its box jitters)"
REVERSES = "reverses in the log"
NO_LANE = "no lane near the vehicle (and no logged route to follow)"
REASONS: tuple[str, ...] = (APPEARS_LATER, NOT_OBSERVED, SHORT_HISTORY, STATIC_OBJECT, STATIONARY, PARKED_JITTER,
                            REVERSES, NO_LANE)


@dataclass(frozen=True)
class AgentRoute:
    """One free agent's route.

    Attributes:
        row: the agent's row in the request's states.
        kind: ``"vehicle"`` or ``"pedestrian"``.
        path: the route (arc length = distance travelled).
        s0: arc length of the last observed position (step ``start_step - 1``).
        offset0: signed lateral offset (left positive) of that position from the route; it fades out.
        v_ref: ``[T]`` desired speed along the route at each step, m/s (``>= 0``).
        last_valid: last step the agent stays valid (its log's last valid step).
        from_log: the route follows the logged positions.
        lane_shift: ``(left, right)`` signed lateral shift to the neighbour lanes' centre lines, ``nan`` where
            there is none (vehicles; pedestrians always ``nan``).
        log_end: arc length of the last logged position on a logged route (0 for lane-graph routes).
    """

    row: int
    kind: str
    path: Path
    s0: float
    offset0: float
    v_ref: np.ndarray
    last_valid: int
    from_log: bool
    lane_shift: tuple[float, float]
    log_end: float = 0.0


@dataclass(frozen=True)
class RoutePlan:
    """Routes of the drivable free agents and reasons for the others.

    Attributes:
        routes: the drivable free agents, in row order.
        replayed: ``row -> reason`` (one of :data:`REASONS`).
    """

    routes: tuple[AgentRoute, ...]
    replayed: dict[int, str]


def project_points(path: Path, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``([N] arc length, [N] signed lateral offset, left positive)`` of ``[N, 2]`` points on ``path``."""
    a, b = path.points[:-1], path.points[1:]
    ab = b - a  # [S, 2]
    seg_len = np.linalg.norm(ab, axis=1)
    rel = points[:, None, :] - a[None]  # [N, S, 2]
    t = np.clip((rel * ab[None]).sum(-1) / np.maximum(seg_len**2, 1e-12)[None], 0.0, 1.0)
    dist = np.linalg.norm(rel - t[..., None] * ab[None], axis=-1)
    k = np.argmin(dist, axis=1)
    n = np.arange(len(points))
    s = path.s[k] + t[n, k] * seg_len[k]
    cross = ab[k, 0] * rel[n, k, 1] - ab[k, 1] * rel[n, k, 0]
    return s, cross / np.maximum(seg_len[k], 1e-12)


def _thin(points: np.ndarray, spacing: float) -> np.ndarray:
    """The points each at least ``spacing`` from the previous kept one (the first and last always kept)."""
    kept = [points[0]]
    for p in points[1:]:
        if np.hypot(*(p - kept[-1])) >= spacing:
            kept.append(p)
    if len(kept) > 1 and np.hypot(*(points[-1] - kept[-1])) > 1e-6:
        kept[-1] = points[-1]
    return np.asarray(kept)


def _smooth(points: np.ndarray, window: int) -> np.ndarray:
    """Moving average of ``[N, 2]`` points over ``window`` points, both ends pinned."""
    if window < 2 or len(points) <= 2:
        return points
    out = moving_average(points, window)
    out[0], out[-1] = points[0], points[-1]
    return out


def _lane_extension(lanes: LaneGraph, end: np.ndarray, heading: float, params: RouteParams) -> np.ndarray:
    """``[K, 2]`` lane-graph points continuing a route past ``end`` (empty without a lane near it)."""
    if not len(lanes):
        return np.zeros((0, 2))
    match = lanes.nearest(end[None], np.array([heading]), params.lane_align_deg, params.lane_search_m)
    if match.lane[0] < 0:
        return np.zeros((0, 2))
    lp = lanes.follow(end, heading, "straight", max_length_m=params.route_length_m)
    return lp.path.points[lp.path.s > lp.start_s + params.extension_blend_m]


def _lane_shift(lanes: LaneGraph, xy: np.ndarray, heading: float, params: RouteParams) -> tuple[float, float]:
    """Signed lateral shift from ``xy`` to the left / right neighbour lane's centre line (``nan``: none)."""
    if not len(lanes):
        return (np.nan, np.nan)
    match = lanes.nearest(xy[None], np.array([heading]), params.lane_align_deg, params.lane_search_m)
    lane = int(match.lane[0])
    if lane < 0:
        return (np.nan, np.nan)
    out = []
    for side, table in ((1.0, lanes.left), (-1.0, lanes.right)):
        other = int(table[lane])
        if other < 0:
            out.append(np.nan)
            continue
        pts = lanes.lanes[other].points
        out.append(side * float(segment_distances(xy[None], pts[:-1], pts[1:]).min()))
    return out[0], out[1]


def _speeds_from_arc(times: np.ndarray, steps: np.ndarray, s: np.ndarray, t_count: int) -> np.ndarray:
    """``[T]`` speeds from arc lengths ``s`` at valid ``steps``: interpolated over gaps, held outside."""
    s = np.maximum.accumulate(s)  # never backwards along the route
    s_all = np.interp(times, times[steps], s)
    v = np.zeros(t_count)
    v[1:] = np.diff(s_all) / np.maximum(np.diff(times), 1e-6)
    first, last = int(steps[0]), int(steps[-1])
    if last > first:
        v[:first + 1] = v[first + 1]
        v[last + 1:] = v[last]
    return v


def _speeds_from_log(times: np.ndarray, steps: np.ndarray, speed: np.ndarray) -> np.ndarray:
    """``[T]`` absolute logged speeds at valid ``steps``, interpolated over gaps, held outside."""
    return np.interp(times, times[steps], np.abs(speed[steps]))


def smoothed_speeds(v: np.ndarray, times: np.ndarray, window_s: float) -> np.ndarray:
    """``[T]`` speeds ``v [T]`` averaged over a centred window of ``window_s`` seconds (the ends held: the
    distance covered inside the log is kept)."""
    dt = float(np.median(np.diff(times))) if len(times) > 1 else 0.0
    half = int(round(0.5 * window_s / dt)) if dt > 0 else 0
    if half < 1 or len(v) < 2:
        return v
    return moving_average(v, 2 * half + 1)


def _within_logged_displacement(v_ref: np.ndarray, times: np.ndarray, xy: np.ndarray, last_obs: int,
                                last_valid: int) -> np.ndarray:
    """``v_ref [T]`` scaled down so that by ``last_valid`` it covers no more than the logged displacement from
    ``last_obs`` (``xy [T, 2]``): an agent whose logged future is too short to follow (a box jittering in place)
    keeps the logged speeds' shape, not the noise of its velocity field."""
    if last_valid <= last_obs:
        return v_ref
    planned = float(np.sum(v_ref[last_obs + 1:last_valid + 1] * np.diff(times[last_obs:last_valid + 1])))
    net = float(np.linalg.norm(xy[last_valid] - xy[last_obs]))
    return v_ref * (net / planned) if planned > net else v_ref


def plan_routes(request: RolloutRequest, params: RouteParams, pedestrian: PedestrianParams) -> RoutePlan:
    """Routes of the request's free agents (see the module docstring)."""
    states, start = request.states, request.start_step
    lanes = request.map.lanes
    last_obs = start - 1
    routes: list[AgentRoute] = []
    replayed: dict[int, str] = {}
    for row in request.free_rows.tolist():
        kind = kind_of(states.categories[row])
        reason, route = _route_of(request, row, kind, last_obs, lanes, params, pedestrian)
        if route is None:
            replayed[row] = reason
        else:
            routes.append(route)
    logger.debug("routes: %d driven, %d replayed", len(routes), len(replayed))
    return RoutePlan(tuple(routes), replayed)


def _route_of(request: RolloutRequest, row: int, kind: str, last_obs: int, lanes: LaneGraph, params: RouteParams,
              pedestrian: PedestrianParams) -> tuple[str, AgentRoute | None]:
    """``(reason, None)`` for an agent to replay, ``("", route)`` otherwise."""
    states = request.states
    valid = states.valid[row]
    if kind == STATIC:
        return STATIC_OBJECT, None
    if not valid[last_obs]:
        return (APPEARS_LATER if valid[last_obs + 1:].any() else NOT_OBSERVED), None
    steps = np.flatnonzero(valid)
    xy, speed = states.xy[row], states.speed[row]
    moved = float(np.linalg.norm(xy[steps] - xy[steps[0]], axis=1).max())
    if np.all(np.abs(speed[steps]) < params.stationary_speed_mps):
        if moved < params.stationary_move_m:
            return STATIONARY, None
        if moved < params.parked_jitter_m:
            return PARKED_JITTER, None
    future = steps[steps >= last_obs]
    if np.any(speed[future] < -params.reverse_speed_mps):
        return REVERSES, None
    times, t_count = states.times, states.num_steps
    heading0 = float(states.heading[row, last_obs])
    # length of the logged future with box jitter thinned out (a box wobbling in place is no route)
    future_len = float(np.linalg.norm(np.diff(_thin(xy[future], params.point_spacing_m), axis=0), axis=1).sum()) \
        if len(future) > 1 else 0.0
    shift = _lane_shift(lanes, xy[last_obs], heading0, params) if kind == VEHICLE else (np.nan, np.nan)
    cap = pedestrian.walk_speed_mps if kind == PEDESTRIAN else params.max_speed_mps
    last_valid = int(future[-1])
    from_log = request.use_log_routes and future_len >= params.min_route_m
    # a logged route carries the agent's intent and speed profile; without one, the history must give them
    if not from_log and int(valid[:last_obs + 1].sum()) < params.min_history_steps:
        return SHORT_HISTORY, None
    if from_log:
        pts = _smooth(_thin(xy[steps], params.point_spacing_m), params.smooth_points)
        if len(pts) >= 2:
            base = Path.from_points(pts)
            ext = _lane_extension(lanes, pts[-1], float(base.heading(base.length)), params) if kind == VEHICLE \
                else np.zeros((0, 2))
            path = Path.from_points(np.concatenate([pts, ext])) if len(ext) else base
            s_all, lat = project_points(path, xy[steps])
            v_ref = np.minimum(smoothed_speeds(_speeds_from_arc(times, steps, s_all, t_count), times,
                                               params.speed_window_s), cap)
            k = int(np.flatnonzero(steps == last_obs)[0])
            return "", AgentRoute(row, kind, path, float(s_all[k]), float(lat[k]), v_ref, last_valid, True, shift,
                                  float(s_all.max()))
    v_ref = np.minimum(smoothed_speeds(_speeds_from_log(times, steps[steps >= last_obs], speed), times,
                                       params.speed_window_s), cap)
    if request.use_log_routes:
        v_ref = _within_logged_displacement(v_ref, times, xy, last_obs, last_valid)
    direction = np.array([np.cos(heading0), np.sin(heading0)])
    if kind == PEDESTRIAN:
        path = Path.from_points(np.stack([xy[last_obs], xy[last_obs] + params.route_length_m * direction]))
        return "", AgentRoute(row, kind, path, 0.0, 0.0, v_ref, last_valid, False, shift)
    match = lanes.nearest(xy[last_obs][None], np.array([heading0]), params.lane_align_deg, params.lane_search_m) \
        if len(lanes) else None
    if match is None or match.lane[0] < 0:
        return NO_LANE, None
    lp = lanes.follow(xy[last_obs], heading0, "straight", max_length_m=params.route_length_m)
    s0, lat0 = project_points(lp.path, xy[last_obs][None])
    return "", AgentRoute(row, kind, lp.path, float(s0[0]), float(lat0[0]), v_ref, last_valid, False, shift)
