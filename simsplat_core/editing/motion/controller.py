"""The motion controller: new trajectories for edited and inserted agents on the log's step times.

``plan_vehicle(request, lanes, map_ctx)`` and ``plan_pedestrian(request, map_ctx)`` turn a resolved request
(``editing.motion.requests``) into a :class:`PlannedTrajectory`:

1. a route (``editing.motion.routes``): the agent's own log path (extended along the lane graph), a lane-graph
   path through the next intersection for a turn, the neighbour lane for a lane change (quintic lateral
   ramp over ``lane_change_s`` at the cruise speed), a sideways shift, a path straight back for reversing;
   for pedestrians the path across the nearest crosswalk (when it is reached in half the time left; else
   straight across from where they stand), straight across the road away from crosswalks (jaywalking), or on
   along their way;
2. a longitudinal plan (``speed_profile.plan_speed``): jerk-limited tracking of the wanted speed (the log's
   own speed where the behaviour does not change it, replayed later after a delayed start; a turn its log
   halts short of is driven at the log's top pace), curve speed caps (never below the log's own speed
   where it drove the route), a leader's gap and gaps to traffic in the way (IDM), stops at a time, before
   the next crosswalk / intersection or behind an object, ending at rest;
3. positions and headings along the route at the planned arc lengths. Steps before the start step keep the
   log (or, with ``backfill``, run the start state backwards).

Refusals (``EditRefused``): ``infeasible_motion`` -- no intersection within reach for a turn, no lane on
that side for a lane change, no crosswalk / road / leader where the behaviour needs one, a stop that
hard braking cannot make.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import torch

from simsplat_core.editing.behaviours.gait import WALK_MPS
from simsplat_core.editing.motion.requests import (
    DEFAULT_CRUISE_MPS,
    PASS_LEAD_M,
    PASS_RAMP_M,
    PASS_TRAIL_M,
    STOP_GAP_M,
    LogTrajectory,
    OtherAgent,
    PassingStep,
    PedestrianMotionRequest,
    VehicleMotionRequest,
    _Common,
)
from simsplat_core.editing.motion.routes import (
    Route,
    crosswalk_ends,
    curvature_caps,
    lane_route,
    log_route,
    merge_onto,
    nearest_lane_segment,
    next_area_s,
    offset_route,
    passing_route,
    polyline_route,
    straight_route,
)
from simsplat_core.editing.motion.speed_profile import LeaderTrack, SpeedCaps, SpeedPlan, StopTarget, plan_speed
from simsplat_core.editing.result import EditRefused
from simsplat_core.geometry import pose_from_yaw
from simsplat_core.scenario.geometry import signed_polygon_distance
from simsplat_core.scenario.lane_graph import LaneGraph
from simsplat_core.scenario.map_context import MapContext
from simsplat_core.scenario.path import Path
from simsplat_core.scene.pose_track import PoseTrack

logger = logging.getLogger(__name__)

#: Lateral distance within which another agent counts as on the route (leaders, objects to stop behind), m ...
ON_ROUTE_M = 2.5
#: ... for traffic, at most the half widths of both plus this clearance (two cars: 2.5 m; a car and a person
#: standing at the edge of a crosswalk 2.4 m off its lane's centre line: not in its way), m.
ROUTE_CLEARANCE_M = 0.6
#: Traffic about to enter the route within this time blocks it where it will enter (crossing traffic), s.
ANTICIPATE_S = 2.0
#: A stop asked by a time may come to rest this much later (s); later is refused.
STOP_BY_TOL_S = 0.15
#: The agent's own log counts as on its edited route within this lateral distance, m.
LOG_ON_ROUTE_M = 0.5
#: Length of the ramp that eases a log path onto a lane path (turns), m.
MERGE_M = 15.0
#: Sideways shifts are eased in over this time at the cruise speed (at least ``MIN_RAMP_M``), s / m.
SHIFT_S = 2.5
MIN_RAMP_M = 10.0
#: Jaywalkers start at least this far from any crosswalk, m; they step this far beyond the far kerb, m.
JAYWALK_CLEARANCE_M = 8.0
KERB_STEP_M = 1.5
#: A pedestrian told to cross walks to the nearest crosswalk when that takes at most this share of the time left.
CROSSWALK_WALK_SHARE = 0.5
#: Crosswalks farther than this from a pedestrian are not "nearest" to walk to, m.
CROSSWALK_REACH_M = 60.0


@dataclass(frozen=True)
class PlannedTrajectory:
    """A planned trajectory on the step grid.

    Attributes:
        times: ``[T]`` s; frame_idx: ``[T]`` log frames of the steps.
        xy: ``[T, 2]`` world box centres, m; heading: ``[T]`` yaw, rad (unwrapped); speed: ``[T]`` signed
            speed along the heading, m/s; valid: ``[T]`` bool, the agent exists.
        arc_length: ``[T]`` distance travelled since the first valid step (non-decreasing), m.
        route: the route driven from the start step on.
        start_step: first planned step (earlier steps keep the log or were backfilled).
    """

    times: np.ndarray
    frame_idx: np.ndarray
    xy: np.ndarray
    heading: np.ndarray
    speed: np.ndarray
    valid: np.ndarray
    arc_length: np.ndarray
    route: Route
    start_step: int

    def pose_track(self, z: float | np.ndarray) -> PoseTrack:
        """Node->world poses at the step frames (``z``: box-centre height(s) ``[T]`` or one value), present
        where valid."""
        zs = np.broadcast_to(np.asarray(z, dtype=np.float64), self.heading.shape)
        poses = np.stack([pose_from_yaw(float(x), float(y), float(h), float(a)) for (x, y), h, a in
                          zip(self.xy, zs, self.heading)])
        return PoseTrack(self.frame_idx.astype(np.float64), torch.as_tensor(poses, dtype=torch.float32),
                         torch.as_tensor(self.valid))


# ------------------------------------------------------------------------------------------ vehicles
def plan_vehicle(request: VehicleMotionRequest, lanes: LaneGraph | None, map_ctx: MapContext) -> PlannedTrajectory:
    """The vehicle's trajectory (module docstring). Raises ``EditRefused`` (``infeasible_motion``)."""
    req = request
    start = req.start
    own = _own_route(req)
    base = _base_route(req, own, lanes)
    s0 = base.project(start.xy)[0]
    route, s0 = _vehicle_route(req, base, s0, lanes)
    moving = abs(start.speed) > 0.3 or (req.log is not None and _log_moves(req.log))
    drives = any(change.drives and change.asked(req) for _, change in VEHICLE_ROUTES) or req.leader is not None
    cruise = req.target_speed_mps
    if cruise is None and drives and not moving:
        cruise = DEFAULT_CRUISE_MPS
    v_ref = _speed_reference(req, cruise, reverse=req.reverse)
    stop = _stop_target(req, route, s0, map_ctx)
    leader = _leader_track(req, route, s0, map_ctx)
    v0 = 0.0 if req.hold_until_s is not None and _first_step(req) else start.speed
    horizon = float(req.times[-1] - req.times[start.step])
    reach = s0 + max(abs(v0), cruise or 0.0, req.limits.max_speed_mps / 2) * horizon + 50.0
    caps = _at_least_the_log(curvature_caps(route, s0, reach, req.limits.lateral_accel_mps2), req, route)
    if own is not None and req.turn is None and _keeps_log_speed(req):
        plan = _replay_log(req, own, s0)
    else:
        plan = _plan(req, s0, v0, v_ref, stop, caps, leader)
    if req.turn in ("left", "right"):
        if cruise is None and req.log is not None and not _turn_reached(route, plan):
            # the log slows down short of the turn (it did not make it): drive on to it at the log's own pace
            pace = float(np.abs(req.log.speed[req.log.valid]).max(initial=abs(start.speed)))
            plan = _plan(req, s0, v0, _speed_reference(req, pace, reverse=False), stop, caps, leader)
        _check_turn_reached(req, route, plan, s0)
    return _compose(req, route, plan)


def _at_least_the_log(caps: SpeedCaps | None, req: VehicleMotionRequest, route: Route) -> SpeedCaps | None:
    """Curve speed caps no lower than the agent's own log speed where its log drives the route (the log shows
    the curve is driven that fast: a speed-up never takes a logged curve slower than the log)."""
    log_s, _ = _log_along(req, route)
    if caps is None or log_s is None or req.log is None:
        return caps
    on = np.isfinite(log_s)
    order = np.argsort(log_s[on])
    s_log, v_log = log_s[on][order], np.abs(req.log.speed[on][order])
    inside = (caps.s >= s_log[0]) & (caps.s <= s_log[-1])
    return SpeedCaps(caps.s, np.where(inside, np.maximum(caps.v, np.interp(caps.s, s_log, v_log)), caps.v))


def _own_route(req: _Common) -> Route | None:
    """The agent's own log path (``None`` without a log, or when it stands)."""
    if req.log is None:
        return None
    steps = np.flatnonzero(req.log.valid)
    return log_route(req.log.xy[steps], req.log.heading[steps])


def _base_route(req: VehicleMotionRequest, own: Route | None, lanes: LaneGraph | None) -> Route:
    """The agent's own path extended along the lanes, else the lane it is on, else straight."""
    start = req.start
    if own is not None:
        end = lane_route(lanes, own.position(own.length), float(own.heading(own.length)))
        return merge_onto(own, own.length, end[0], MERGE_M) if end is not None else own
    on_lane = lane_route(lanes, start.xy, start.heading)
    if on_lane is not None:
        return merge_onto(None, 0.0, on_lane[0], MERGE_M, point=start.xy)
    return straight_route(start.xy, start.heading)


def _turned(req: VehicleMotionRequest, base: Route, s0: float, lanes: LaneGraph | None) -> Route:
    """``base`` merged onto the lane route making the turn (shifted sideways at its end, if asked)."""
    s_join, turned = _turn_route(req, base, s0, lanes)
    return merge_onto(base, s_join, turned, MERGE_M, final_offset_m=req.lateral_offset_m)


def _lane_changed(req: VehicleMotionRequest, base: Route, s0: float, lanes: LaneGraph | None) -> Route:
    """``base`` merged onto the neighbour lane over ``lane_change_s`` at the cruise speed (at least 1.5
    :data:`MIN_RAMP_M`), from ``lane_change_after_m`` on (shifted sideways at its end, if asked)."""
    start = req.start
    target = _neighbour_route(req, lanes)
    length = max(MIN_RAMP_M * 1.5, req.lane_change_s * max(abs(start.speed), req.target_speed_mps or 0.0,
                                                             DEFAULT_CRUISE_MPS if abs(start.speed) < 0.3 else 0.0))
    return merge_onto(base, s0 + req.lane_change_after_m, target, length, final_offset_m=req.lateral_offset_m)


def _shifted(req: VehicleMotionRequest, base: Route, s0: float, lanes: LaneGraph | None) -> Route:
    """``base`` shifted ``lateral_offset_m`` sideways, eased in over :data:`SHIFT_S` at the cruise speed (at least
    :data:`MIN_RAMP_M`)."""
    ramp = max(MIN_RAMP_M, SHIFT_S * max(abs(req.start.speed), req.target_speed_mps or 0.0))
    return offset_route(base, s0, req.lateral_offset_m, ramp)


@dataclass(frozen=True)
class RouteChange:
    """How a behaviour changes a vehicle's route.

    Attributes:
        asked: whether a request asks it.
        route: ``(request, base route, start arc length on it m, lanes) ->`` the changed route.
        drives: a standing vehicle asked it drives off (at ``DEFAULT_CRUISE_MPS`` when no speed is asked).
    """

    asked: Callable[[VehicleMotionRequest], bool]
    route: Callable[[VehicleMotionRequest, Route, float, LaneGraph | None], Route]
    drives: bool


#: The behaviours that change a vehicle's route, in precedence order (the first asked one makes the route; a turn and
#: a lane change take the sideways shift along): behaviour name -> its route change.
VEHICLE_ROUTES: tuple[tuple[str, RouteChange], ...] = (
    ("turn", RouteChange(lambda r: r.turn is not None, _turned, drives=True)),
    ("lane_change", RouteChange(lambda r: r.lane_change is not None, _lane_changed, drives=True)),
    ("lateral_offset", RouteChange(lambda r: bool(r.lateral_offset_m), _shifted, drives=False)),
)


def _vehicle_route(req: VehicleMotionRequest, base: Route, s0: float, lanes: LaneGraph | None) -> tuple[Route, float]:
    """Route with the requested change (:data:`VEHICLE_ROUTES`), and the start's arc length on it."""
    route = next((change.route(req, base, s0, lanes) for _, change in VEHICLE_ROUTES if change.asked(req)), base)
    return route, route.project(req.start.xy)[0] if route is not base else s0


def _turn_route(req: VehicleMotionRequest, base: Route, s0: float, lanes: LaneGraph | None) -> tuple[float, Route]:
    """``(s_join, lane route making the turn)``: followed from the start, or from a little further along the
    agent's own path when the lane nearest the start runs elsewhere than the path (overlapping lanes in an
    intersection): the first candidate heading the way the path does over the next 10 m wins, else the
    first that makes the turn. Going straight, a candidate starting on a turning lane is no candidate (the
    point is on the path's own turn: the lane there keeps it)."""
    label, turn = req.label, req.turn
    assert turn is not None
    if turn == "straight" and (sibling := _straight_sibling(req, lanes)) is not None:
        return s0, sibling
    making: list[tuple[float, Route]] = []
    for ahead in (0.0, 4.0, 8.0, 12.0, 16.0):
        s_p = s0 + ahead
        cand = lane_route(lanes, base.position(s_p), float(base.heading(s_p)), turn)
        if cand is None or (turn != "straight" and "turn" not in cand[0].marks):
            continue
        if turn == "straight" and lanes is not None and lanes.turn_of(cand[1].lanes[0]) != "straight":
            continue  # from a point of the path already in a turn lane: following it would keep the turn
        route = cand[0]
        s_c = route.project(base.position(s_p))[0]
        # a turn's lane heads the way the path does over the next 10 m; going straight, the path may be turning
        # away from the lane (the log's own turn, just begun): the lane need only start the way the path does
        probe = np.linspace(0.0, 2.0 if turn == "straight" else 10.0, 6)
        apart = np.abs(np.angle(np.exp(1j * (route.heading(s_c + probe) - base.heading(s_p + probe))))).max()
        logger.debug("turn %s from %.1f m ahead: %s, headings %.0f deg apart", turn, ahead, route.marks,
                     np.rad2deg(apart))
        if apart <= np.deg2rad(20.0):
            return s_p, route
        making.append((s_p, route))
    if making:
        return making[0]
    if lane_route(lanes, req.start.xy, req.start.heading) is None:
        raise EditRefused(f"turning requires an intersection ahead of {label}, and {label} is not on a lane of "
                          "the map", reason="infeasible_motion")
    raise EditRefused(f"turning requires an intersection ahead of {label} where its lane may turn {turn}: none "
                      "within 300 m", reason="infeasible_motion")


#: A vehicle that has begun a turn may still go straight on while it is this close to the straight lane (m) ...
STRAIGHT_SIBLING_M = 1.5
#: ... and heading within this of it (degrees).
STRAIGHT_SIBLING_DEG = 25.0


def _straight_sibling(req: VehicleMotionRequest, lanes: LaneGraph | None) -> Route | None:
    """The lane route going straight on from the junction entry of the turning lane the start is on, when the
    vehicle, just into its turn, is still within :data:`STRAIGHT_SIBLING_M` and :data:`STRAIGHT_SIBLING_DEG` of
    it; ``None`` otherwise (not on a turning lane, or too far into the turn)."""
    start = req.start
    if lanes is None:
        return None
    match = lanes.nearest(np.asarray(start.xy, np.float64)[None, :2], np.array([start.heading]), max_dist_m=2.5)
    lane = int(match.lane[0])
    if lane < 0 or lanes.turn_of(lane) == "straight":
        return None
    for entry in lanes.predecessors[lane]:
        for other in (entry, *lanes.successors[entry]):  # a lane running on through the junction, or a connector
            if other == lane or lanes.turn_of(other) != "straight":
                continue
            ln = lanes.lanes[other]
            path = Path.from_points(ln.points)
            s_on = path.project(start.xy)
            apart = abs(float(np.angle(np.exp(1j * (float(ln.heading_at(s_on)) - start.heading)))))
            if (float(np.linalg.norm(path.position(s_on) - start.xy)) > STRAIGHT_SIBLING_M
                    or apart > np.deg2rad(STRAIGHT_SIBLING_DEG)):
                continue
            found = lane_route(lanes, path.position(s_on), float(ln.heading_at(s_on)), max_dist_m=0.5,
                               align_deg=20.0)
            if found is not None:
                return found[0]
    return None


def _neighbour_route(req: VehicleMotionRequest, lanes: LaneGraph | None) -> Route:
    """Lane route along the neighbour lane on the ``lane_change`` side of the start's lane (or of the next
    lanes ahead within 40 m)."""
    start, side = req.start, req.lane_change
    own = lane_route(lanes, start.xy, start.heading)
    if lanes is None or own is None:
        raise EditRefused(f"no lane to the {side} of {req.label}: it is not on a lane of the map",
                          reason="infeasible_motion")
    route, lp = own
    table = lanes.left if side == "left" else lanes.right
    for k, lane in enumerate(lp.lanes):
        if lp.lane_span(k)[0] - lp.start_s > 40.0:
            break
        other = int(table[lane])
        if other < 0:
            continue
        ln = lanes.lanes[other]
        on_other = Path.from_points(ln.points)
        s_on = on_other.project(start.xy if k == 0 else lp.path.position(lp.lane_span(k)[0] + 1.0))
        found = lane_route(lanes, on_other.position(s_on), float(ln.heading_at(s_on)), max_dist_m=0.5, align_deg=20.0)
        if found is not None:
            return found[0]
    raise EditRefused(f"no lane to the {side} of {req.label} (lanes run the same way only on the other side, or "
                      "the road has one lane)", reason="infeasible_motion")


def _turn_reached(route: Route, plan: SpeedPlan) -> bool:
    """Whether the plan gets halfway through the turn of ``route`` within the steps."""
    s_turn, s_end = route.marks["turn"], route.marks.get("turn_end", route.marks["turn"])
    return float(plan.s[-1]) >= 0.5 * (s_turn + s_end)


def _check_turn_reached(req: VehicleMotionRequest, route: Route, plan: SpeedPlan, s0: float) -> None:
    s_turn, s_end = route.marks["turn"], route.marks.get("turn_end", route.marks["turn"])
    reached = float(plan.s[-1])
    if not _turn_reached(route, plan):
        horizon = float(req.times[-1] - req.times[req.start.step])
        raise EditRefused(f"turning requires an intersection ahead of {req.label} within reach: the next "
                          f"{req.turn} turn runs from {s_turn - s0:.0f} m to {s_end - s0:.0f} m ahead, but "
                          f"{req.label} covers {reached - s0:.0f} m in the remaining {horizon:.1f} s (it must get "
                          f"halfway through the turn, {0.5 * (s_turn + s_end) - s0:.0f} m)", reason="infeasible_motion")


def _leader_track(req: VehicleMotionRequest, route: Route, s0: float, map_ctx: MapContext) -> LeaderTrack | None:
    """The followed leader and the traffic, where each is on the route ahead of the start (within
    ``ON_ROUTE_M`` of it, traffic within its and the agent's half widths plus ``ROUTE_CLEARANCE_M``, and on the
    drivable surface: a person standing on the corner's pavement beside a right turn is no obstacle); traffic
    that will
    be on the route within ``ANTICIPATE_S`` already blocks it where it will enter, standing (unless the plan is
    past that point by then: ``LeaderTrack.enter_t``); the agent's own log along the route lets a plan behind
    it keep the log's gaps to the traffic (``LeaderTrack.log_s``)."""
    agents = ([req.leader] if req.leader is not None else []) + list(req.traffic)
    if not agents:
        return None
    t = len(req.times)
    s = np.zeros((len(agents), t))
    present = np.zeros((len(agents), t), dtype=bool)
    for i, other in enumerate(agents):
        followed = i == 0 and req.leader is not None
        reach = ON_ROUTE_M if followed else min(ON_ROUTE_M, (req.size[1] + other.size[1]) / 2.0 + ROUTE_CLEARANCE_M)
        steps = np.flatnonzero(other.valid)
        on_road = map_ctx.facts(other.xy[steps], other.heading[steps]).on_drivable if steps.size else steps
        for k, drivable in zip(steps, on_road):
            s[i, k], lat = route.project(other.xy[k])
            present[i, k] = abs(lat) <= reach and s[i, k] > s0 and (bool(drivable) or followed)
    if req.leader is not None and not present[0, req.start.step:].any():
        raise EditRefused(f"{req.label} cannot follow {req.leader.label}: it is not ahead of {req.label} on its "
                          "path", reason="infeasible_motion")
    v = np.where(present, np.gradient(s, req.times, axis=1) if t > 1 else 0.0, 0.0)
    # anticipate: an agent about to enter the route (crossing traffic) already blocks where it will enter
    window = max(int(round(ANTICIPATE_S / max(float(np.median(np.diff(req.times))), 1e-3))), 0) if t > 1 else 0
    s_eff, v_eff, present_eff = s.copy(), v.copy(), present.copy()
    enter_t = np.broadcast_to(req.times, s.shape).copy()
    for step in range(t):
        upcoming = present[:, step:step + window + 1]
        later = upcoming.any(axis=1) & ~present[:, step]
        if later.any():
            s_eff[later, step] = np.where(upcoming[later], s[later, step:step + window + 1], np.inf).min(axis=1)
            v_eff[later, step] = 0.0
            present_eff[later, step] = True
            enter_t[later, step] = req.times[step + np.argmax(upcoming[later], axis=1)]
    cover = np.ones(len(agents), dtype=bool)
    if req.leader is not None:  # the followed leader is followed where it is, not anticipated, at its own gap
        s_eff[0], v_eff[0], present_eff[0], enter_t[0], cover[0] = s[0], v[0], present[0], req.times, False
    gap = np.array([(o.size[0] + req.size[0]) / 2.0 + req.follow_gap_m for o in agents])
    log_s, log_v = _log_along(req, route)
    return LeaderTrack(s=s_eff, v=v_eff, present=present_eff, gap_m=gap, headway_s=req.headway_s, enter_t=enter_t,
                       log_s=log_s, log_v=log_v, log_cover=cover if log_s is not None else None)


def _log_along(req: VehicleMotionRequest, route: Route) -> tuple[np.ndarray | None, np.ndarray | None]:
    """``([T] arc length, [T] speed)`` of the agent's own log along ``route`` where the log is on it (within
    ``LOG_ON_ROUTE_M``; NaN elsewhere), ``(None, None)`` without a log on the route."""
    log = req.log
    if log is None or len(req.times) < 2:
        return None, None
    s = np.full(len(req.times), np.nan)
    for k in np.flatnonzero(log.valid):
        s_k, lat = route.project(log.xy[k])
        if abs(lat) <= LOG_ON_ROUTE_M:
            s[k] = s_k
    if not np.isfinite(s).any():
        return None, None
    return s, np.gradient(s, req.times)


# ------------------------------------------------------------------------------------------ pedestrians
def plan_pedestrian(request: PedestrianMotionRequest, map_ctx: MapContext) -> PlannedTrajectory:
    """The pedestrian's trajectory (module docstring). Raises ``EditRefused`` (``infeasible_motion``)."""
    req = request
    start = req.start
    own = _own_route(req)
    if req.cross_street:
        route = _crossing_route(req, map_ctx)
    else:
        route = own if own is not None else straight_route(start.xy, start.heading)
    s0 = route.project(start.xy)[0]
    if req.lateral_offset_m:
        route = offset_route(route, s0, req.lateral_offset_m, 3.0)
    if req.passing is not None:
        route = _passing(route, req.passing, s0)
    if own is not None and not req.cross_street and _keeps_log_speed(req):
        return _compose(req, route, _replay_log(req, own, s0))
    v_ref = _speed_reference(req, req.target_speed_mps, reverse=False)
    stop = _stop_target(req, route, s0, map_ctx)
    crossing = stop is None and req.cross_street
    if crossing:  # a crossing ends on the far sidewalk (where the route ends), if it gets there
        stop = StopTarget(at_s=max(route.length, s0))
    v0 = 0.0 if req.hold_until_s is not None and _first_step(req) else start.speed
    plan = _plan(req, s0, v0, v_ref, stop, None, None, must_stop=not crossing)
    return _compose(req, route, plan)


def _passing(route: Route, step: PassingStep, s0: float) -> Route:
    """``route`` with the step aside ``step`` (``requests.PassingStep``), begun at the walker's start ``s0``
    at the earliest."""
    s_from = route.project(step.from_xy)[0] - PASS_LEAD_M
    s_until = route.project(step.until_xy)[0] + PASS_TRAIL_M
    return passing_route(route, max(s_from, s0), s_until, step.offset_m, PASS_RAMP_M)


def _crossing_route(req: PedestrianMotionRequest, map_ctx: MapContext) -> Route:
    """Across the road: jaywalking away from crosswalks when asked; else at the nearest crosswalk when the
    pedestrian can walk to it in :data:`CROSSWALK_WALK_SHARE` of the time left, so that it crosses within the
    steps; else straight across from where it stands ("a man 8 m ahead walking across the road" crosses there,
    not 20 m on at a crosswalk the log ends before it reaches)."""
    if req.jaywalk:
        return _jaywalk_route(req, map_ctx)
    if map_ctx.crosswalks:
        start = req.start
        near = min(_crosswalk_distances(start.xy, map_ctx))
        on_one = -signed_polygon_distance(start.xy[None], list(map_ctx.crosswalks)).min() < 1.0
        speed = req.target_speed_mps if req.target_speed_mps else WALK_MPS
        left = float(req.times[-1] - req.times[start.step])
        if on_one or near <= CROSSWALK_WALK_SHARE * speed * left:
            return _crosswalk_route(req, map_ctx)
    return _jaywalk_route(req, map_ctx, keep_clear=False)


def _crosswalk_distances(xy: np.ndarray, map_ctx: MapContext) -> list[float]:
    """Per crosswalk of ``map_ctx``, the distance (m) from ``xy`` to its nearer end."""
    return [min(float(np.linalg.norm(a - xy)), float(np.linalg.norm(b - xy)))
            for a, b in (crosswalk_ends(p) for p in map_ctx.crosswalks)]


def _crosswalk_route(req: PedestrianMotionRequest, map_ctx: MapContext) -> Route:
    """To the near end of the nearest crosswalk, across it and onto the far kerb."""
    start = req.start
    if not map_ctx.crosswalks:
        raise EditRefused(f"{req.label} cannot cross at a crosswalk: the map has none (ask to jaywalk instead)",
                          reason="infeasible_motion")
    dist = _crosswalk_distances(start.xy, map_ctx)
    k = int(np.argmin(dist))
    if dist[k] > CROSSWALK_REACH_M:
        raise EditRefused(f"{req.label} cannot cross at a crosswalk: the nearest is {dist[k]:.0f} m away "
                          f"(within {CROSSWALK_REACH_M:.0f} m needed; ask to jaywalk instead)",
                          reason="infeasible_motion")
    a, b = crosswalk_ends(map_ctx.crosswalks[k])
    near, far = (a, b) if np.linalg.norm(a - start.xy) <= np.linalg.norm(b - start.xy) else (b, a)
    on_it = -signed_polygon_distance(start.xy[None], [map_ctx.crosswalks[k]])[0] < 1.0
    if on_it and np.dot(near - far, [np.cos(start.heading), np.sin(start.heading)]) > 0:
        near, far = far, near  # already crossing: on towards the end it faces
    across = (far - near) / np.linalg.norm(far - near)
    pts = [start.xy]
    if not on_it:
        pts.append(near - 0.5 * across)
    pts += [far, far + KERB_STEP_M * across]
    return polyline_route(np.array(pts), smooth=3)


def _jaywalk_route(req: PedestrianMotionRequest, map_ctx: MapContext, keep_clear: bool = True) -> Route:
    """Straight across the road (perpendicular to the nearest lane), at least ``JAYWALK_CLEARANCE_M`` from any
    crosswalk (``keep_clear``; else from where it stands), onto the far kerb."""
    start = req.start
    nearest = nearest_lane_segment(map_ctx, start.xy)
    if nearest is None:
        raise EditRefused(f"{req.label} cannot cross the street: the map has no lanes to cross",
                          reason="infeasible_motion")
    foot, along, dist = nearest
    if dist > 30.0:
        raise EditRefused(f"{req.label} cannot cross the street: no road within 30 m", reason="infeasible_motion")
    normal = np.array([-along[1], along[0]])
    to_road = foot - start.xy
    facts = map_ctx.facts(start.xy[None], np.array([start.heading]))
    if facts.on_drivable[0] or np.linalg.norm(to_road) < 0.5:
        direction = normal if np.dot(normal, [np.cos(start.heading), np.sin(start.heading)]) >= 0 else -normal
    else:
        direction = normal if np.dot(normal, to_road) >= 0 else -normal
    begin = _away_from_crosswalks(start.xy, along, map_ctx) if keep_clear else start.xy
    ray = begin + np.arange(0.0, 60.0, 0.25)[:, None] * direction
    ray_facts = map_ctx.facts(ray, np.full(len(ray), np.arctan2(direction[1], direction[0])))
    on_road = ray_facts.on_drivable if map_ctx.has_drivable else ray_facts.lane_dist < 2.0
    entered = np.flatnonzero(on_road)
    if not entered.size:
        raise EditRefused(f"{req.label} cannot cross the street: no road in the direction it would cross",
                          reason="infeasible_motion")
    left = np.flatnonzero(~on_road[entered[0]:])
    far = ray[entered[0] + left[0]] if left.size else ray[-1]
    pts = [start.xy] + ([begin] if np.linalg.norm(begin - start.xy) > 0.5 else [])
    pts += [far + KERB_STEP_M * direction]
    return polyline_route(np.array(pts), smooth=3)


def _away_from_crosswalks(xy: np.ndarray, along: np.ndarray, map_ctx: MapContext) -> np.ndarray:
    """The point of the line ``xy + u * along`` (``|u| <= 40`` m) nearest ``xy`` that lies at least
    ``JAYWALK_CLEARANCE_M`` from every crosswalk (``xy`` itself when none is clear)."""
    if not map_ctx.crosswalks:
        return xy
    u = np.array(sorted(np.arange(-40.0, 40.5, 0.5), key=abs))
    cands = xy + u[:, None] * along
    clearance = -signed_polygon_distance(cands, map_ctx.crosswalks)  # distance outside, negative inside
    ok = np.flatnonzero(clearance >= JAYWALK_CLEARANCE_M)
    return cands[ok[0]] if ok.size else xy


# ------------------------------------------------------------------------------------------ shared
def _log_moves(log: LogTrajectory) -> bool:
    return bool(np.abs(log.speed[log.valid]).max(initial=0.0) > 0.5)


def _keeps_log_speed(req: _Common) -> bool:
    """Nothing asks for a different progress than the log's (only sideways changes)."""
    vehicle_change = isinstance(req, VehicleMotionRequest) and (req.reverse or req.leader is not None)
    return (req.log is not None and _log_moves(req.log) and req.target_speed_mps is None and req.stop is None
            and req.hold_until_s is None and not vehicle_change)


def _replay_log(req: _Common, own: Route, s0: float) -> SpeedPlan:
    """The log's own progress along its path from the start step (arc lengths of its positions on ``own``,
    which the edited route shares up to the edit), then its last speed held beyond its last valid step."""
    log = req.log
    assert log is not None
    k0 = req.start.step
    steps = np.flatnonzero(log.valid)
    steps = steps[steps >= k0]
    s_log = np.array([own.project(log.xy[k])[0] for k in steps])
    s_log = s0 + np.maximum.accumulate(s_log - s_log[0])
    times = req.times
    s = np.interp(times, times[steps], s_log)
    v = np.zeros(len(times))
    if len(times) - k0 > 1:
        v[k0:] = np.gradient(s[k0:], times[k0:])
    last = int(steps[-1])
    if last + 1 < len(times):
        v_last = float(v[last])
        tail = plan_speed(times, t0=float(times[last]), s0=float(s[last]), v0=v_last, v_ref=lambda t: v_last,
                          limits=req.limits)
        s[last + 1:], v[last + 1:] = tail.s[last + 1:], tail.v[last + 1:]
    a = np.gradient(v, times) if len(times) > 1 else np.zeros(len(times))
    return SpeedPlan(s, v, a)


def _first_step(req: _Common) -> bool:
    """The plan starts at the agent's first valid log step (nothing before it to stay continuous with)."""
    return req.log is None or not req.log.valid[:req.start.step].any()


def _speed_reference(req: _Common, cruise: float | None, reverse: bool) -> Callable[[float], float]:
    """Wanted signed speed over time: 0 while held; then the cruise speed, else the log's (replayed
    ``log_shift_s`` later), else the start speed (a standing agent keeps standing)."""
    hold = req.hold_until_s
    times, log, shift, v_start = req.times, req.log, req.log_shift_s, req.start.speed

    def v_ref(t: float) -> float:
        if hold is not None and t < hold:
            return 0.0
        if cruise is not None:
            return -cruise if reverse else cruise
        if log is not None and _log_moves(log):
            return log.speed_at(times, t - shift)
        return v_start

    return v_ref


def _stop_target(req: _Common, route: Route, s0: float, map_ctx: MapContext) -> StopTarget | None:
    stop = req.stop
    if stop is None:
        return None
    length = req.size[0]
    if stop.distance_m is not None:
        return StopTarget(at_s=s0 + stop.distance_m, hard=stop.hard)
    if stop.at_time_s is not None:
        return StopTarget(at_time=stop.at_time_s, hard=stop.hard)
    if stop.before is not None:
        kind = "crosswalk" if stop.before in ("crosswalk", "stop_line") else "intersection"
        s_area = next_area_s(route, map_ctx, kind, s0 + length / 2.0)
        if s_area is None:
            raise EditRefused(f"{req.label} cannot stop before the next {stop.before.replace('_', ' ')}: there is no "
                              f"{kind} ahead on its path within 200 m", reason="infeasible_motion")
        gap = stop.gap_m if stop.gap_m is not None else STOP_GAP_M[stop.before]
        return StopTarget(at_s=_ahead(req, s_area - gap - length / 2.0, s0, f"the next {stop.before}"), hard=stop.hard)
    if stop.behind is not None:
        other: OtherAgent = stop.behind
        k = req.start.step
        s_obj, lat = route.project(other.xy[k]) if other.valid[k] else (-np.inf, np.inf)
        if abs(lat) > ON_ROUTE_M or s_obj <= s0:
            raise EditRefused(f"{req.label} cannot stop behind {other.label}: it is not ahead of {req.label} on its "
                              "path", reason="infeasible_motion")
        gap = stop.gap_m if stop.gap_m is not None else STOP_GAP_M["behind"]
        return StopTarget(at_s=_ahead(req, s_obj - other.size[0] / 2.0 - gap - length / 2.0, s0, other.label),
                          hard=stop.hard)
    return StopTarget(hard=stop.hard)


def _ahead(req: _Common, s_stop: float, s0: float, what: str) -> float:
    if s_stop < s0 - 0.1:
        raise EditRefused(f"{req.label} cannot stop before {what}: it is already {s0 - s_stop:.1f} m past the "
                          "stopping point", reason="infeasible_motion")
    return max(s_stop, s0)


def _plan(req: _Common, s0: float, v0: float, v_ref: Callable[[float], float], stop: StopTarget | None,
          caps: SpeedCaps | None, leader: LeaderTrack | None, must_stop: bool = True) -> SpeedPlan:
    """The longitudinal plan; with ``must_stop`` a stop that does not come to rest within the steps is
    refused (it would not be seen)."""
    t0 = float(req.times[req.start.step])
    try:
        plan = plan_speed(req.times, t0=t0, s0=s0, v0=v0, a0=req.start.accel if v0 == req.start.speed else 0.0,
                          v_ref=v_ref, limits=req.limits, stop=stop, caps=caps, leader=leader)
    except ValueError as err:
        raise EditRefused(f"{req.label} {err}", reason="infeasible_motion") from None
    if must_stop and stop is not None and plan.stopped_at is None and abs(v0) > 1e-6:
        end = float(req.times[-1])
        where = (f"the stopping point is {stop.at_s - s0:.0f} m ahead, but {req.label} covers "
                 f"{plan.s[-1] - s0:.0f} m" if stop.at_s is not None else
                 f"it cannot be at rest by {stop.at_time:g} s" if stop.at_time is not None else
                 "it cannot come to rest")
        raise EditRefused(f"{req.label} cannot make the stop before the log ends ({end:.1f} s): {where}",
                          reason="infeasible_motion")
    if (must_stop and stop is not None and stop.at_time is not None and plan.stopped_at is not None
            and plan.stopped_at > stop.at_time + STOP_BY_TOL_S):
        raise EditRefused(f"{req.label} cannot be at rest by {stop.at_time:g} s: braking as hard as allowed "
                          f"({req.limits.hard_decel_mps2:g} m/s^2) from {abs(v0):.1f} m/s it stands only from "
                          f"{plan.stopped_at:.1f} s", reason="infeasible_motion")
    return plan


def _compose(req: _Common, route: Route, plan: SpeedPlan) -> PlannedTrajectory:
    """Positions along the route at the planned arc lengths; the log (or the backfill) before the start."""
    k0 = req.start.step
    t = len(req.times)
    xy = route.position(plan.s)
    heading = route.heading(plan.s)
    speed = plan.v.copy()
    valid = np.zeros(t, dtype=bool)
    valid[k0:] = True
    if req.backfill:
        valid[:k0] = True
    elif req.log is not None:
        xy[:k0], heading[:k0], speed[:k0] = req.log.xy[:k0], req.log.heading[:k0], req.log.speed[:k0]
        valid[:k0] = req.log.valid[:k0]
    heading = np.unwrap(np.where(valid, heading, heading[k0]))
    step = np.r_[0.0, np.linalg.norm(np.diff(xy, axis=0), axis=1)] * (valid & np.r_[False, valid[:-1]])
    arc = np.cumsum(step)
    first = int(np.flatnonzero(valid)[0]) if valid.any() else 0
    arc -= arc[first]
    held = ~valid
    xy[held] = xy[k0]
    return PlannedTrajectory(times=req.times, frame_idx=req.frame_idx, xy=xy, heading=heading, speed=speed,
                             valid=valid, arc_length=np.maximum(arc, 0.0), route=route, start_step=k0)
