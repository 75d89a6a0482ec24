"""Named parameters of the reactive traffic model (``motion.reactive``): every number the algorithm uses.

* :class:`IDMParams` -- car following, the Intelligent Driver Model (Treiber, Hennecke & Helbing 2000) in
  its IDM+ form (Schakel et al. 2010: the free-road and interaction terms combine by ``min``). The
  published Treiber values: desired time headway 1.5 s, minimum gap 2 m, maximum acceleration 1.5 m/s^2,
  comfortable deceleration 2 m/s^2, acceleration exponent 4; plus a hard-brake limit for emergencies.
* :class:`GapAcceptanceParams` -- yielding at conflict points (intersections, crosswalks): a crossing
  agent arriving within the critical gap (~4 s, HCM's critical headway for minor-street movements) makes
  the agent stop before the conflict point. Between two driven agents the first to arrive goes (queues
  behind it form by car following, so no separate follow-up time is needed); a pedestrian on a crosswalk
  goes first; agents whose trajectories are fixed never give way, so the others always do.
* :class:`LaneChangeParams` -- MOBIL (Kesting, Treiber & Helbing 2007): politeness 0.3, switching
  threshold 0.2 m/s^2, safe braking 4 m/s^2; the lateral move is a smooth offset profile over ~3 s.
* :class:`PedestrianParams` -- walking, waiting for vehicles about to cross the pedestrian's path.
* :class:`CorridorParams` -- what counts as "on the route ahead" (the corridor and its look-ahead).
* :class:`RouteParams` -- how routes are built from the log or the lane graph.
* :class:`ReactiveParams` -- all of the above.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class IDMParams:
    """Intelligent Driver Model (IDM+) parameters.

    Attributes:
        desired_time_headway_s: ``T``, the time gap kept to the leader at speed.
        min_gap_m: ``s0``, the bumper-to-bumper gap kept at standstill.
        max_accel_mps2: ``a``, the acceleration when catching up with the desired (logged) speed.
        comfortable_decel_mps2: ``b``, the comfortable deceleration of the desired-gap term.
        max_decel_mps2: hard-brake limit, the largest deceleration ever commanded (emergencies).
        accel_exponent: ``delta`` (only the interaction term is used here: the free-road term is the log's
            speed profile, see ``motion.longitudinal``; kept for completeness and documentation).
        min_time_headway_s, min_standstill_gap_m: a driver whose log follows its leader closer than ``T`` /
            ``s0`` at the first predicted step keeps its own (logged) headway, never below these.
        standstill_clearance_m: last-resort positional bound: an agent never advances closer than this to
            the obstacle ahead within one step, whatever the deceleration it takes.
        log_accel_cap_mps2: ``a`` of a vehicle is raised to the acceleration its logged speed profile shows
            (95th percentile), up to this: a driver who accelerates briskly in the log catches up as briskly.
    """

    desired_time_headway_s: float = 1.5
    min_gap_m: float = 2.0
    max_accel_mps2: float = 1.5
    comfortable_decel_mps2: float = 2.0
    max_decel_mps2: float = 8.0
    accel_exponent: float = 4.0
    min_time_headway_s: float = 0.6
    min_standstill_gap_m: float = 1.0
    standstill_clearance_m: float = 0.5
    log_accel_cap_mps2: float = 3.0


@dataclass(frozen=True)
class GapAcceptanceParams:
    """Yielding to agents crossing the route.

    Attributes:
        critical_gap_s: a crossing agent arriving at the conflict point sooner than this is not a gap
            the agent accepts: it stops before the conflict point.
        horizon_s: how far ahead the other agents' positions are predicted.
        sample_dt_s: spacing of those predicted positions.
        clearance_time_s: post-encroachment margin: an agent goes first when it clears the conflict point
            at least this long before the other arrives (accelerating at most at ``a`` up to its desired speed).
        crossing_deg: agents whose heading differs from the route's by more than this cross it or, for a
            vehicle, come towards it head-on (smaller: same direction, handled as leaders; so are pedestrians
            meeting a pedestrian head-on, and agents standing still whatever their heading).
        stop_margin_m: distance kept before the conflict zone when yielding.
    """

    critical_gap_s: float = 4.0
    clearance_time_s: float = 1.0
    horizon_s: float = 6.0
    sample_dt_s: float = 0.3
    crossing_deg: float = 30.0
    stop_margin_m: float = 1.0


@dataclass(frozen=True)
class LaneChangeParams:
    """MOBIL lane change / detour around a blocked lane.

    Attributes:
        politeness: ``p``, weight of the new follower's disadvantage.
        threshold_mps2: ``a_th``, the acceleration gain a change must bring.
        safe_decel_mps2: ``b_safe``, the most the new follower may have to brake.
        duration_s: the lateral move takes about this long at the current speed.
        min_length_m: the lateral move never takes less road than this (a stopped car does not slide sideways).
        trigger_gap_m: a change is considered only with a blocking obstacle closer than this (about where IDM
            starts braking for a standing obstacle at urban speeds).
        blocked_speed_mps: an obstacle slower than this (along the route) blocks the lane.
        clearance_m: the lateral move ends at least this far before the obstacle's rear.
    """

    politeness: float = 0.3
    threshold_mps2: float = 0.2
    safe_decel_mps2: float = 4.0
    duration_s: float = 3.0
    min_length_m: float = 10.0
    trigger_gap_m: float = 60.0
    blocked_speed_mps: float = 0.5
    clearance_m: float = 2.0


@dataclass(frozen=True)
class PedestrianParams:
    """Pedestrians.

    Attributes:
        walk_speed_mps: desired walking speeds are capped at this (a brisk walk; the logged speed otherwise).
        wait_radius_m: how far ahead along its path a pedestrian looks for vehicles about to cross it.
        time_to_conflict_s: a vehicle arriving on the pedestrian's path sooner than this makes it wait.
        following: the pedestrian's "car following" (keeping distance to someone walking ahead).
    """

    walk_speed_mps: float = 2.5
    wait_radius_m: float = 8.0
    time_to_conflict_s: float = 3.0
    following: IDMParams = field(default_factory=lambda: IDMParams(
        desired_time_headway_s=0.5, min_gap_m=0.5, max_accel_mps2=1.0, comfortable_decel_mps2=1.5,
        max_decel_mps2=4.0, min_time_headway_s=0.3, min_standstill_gap_m=0.3, standstill_clearance_m=0.2))


@dataclass(frozen=True)
class CorridorParams:
    """The strip along a route in which other agents are obstacles.

    Attributes:
        lateral_margin_m: added to the two half widths when testing whether an agent is in the corridor.
        ahead_m: look-ahead along the route.
        behind_m: look-behind (new followers of a lane change).
        grid_step_m: spacing of the arc-length grid the routes are sampled on.
        parked_move_m: a given agent whose logged box never moves farther than this from its first position is
            parked: an unedited agent whose logged route passes it does not take it as a leader.
        company_gap_m, company_speed_mps, company_heading_deg: two unedited agents whose centres are closer
            than this at the last observed step, both moving with speeds within ``company_speed_mps`` and
            headings within ``company_heading_deg``, travel in company: neither is the other's leader.
    """

    lateral_margin_m: float = 0.3
    ahead_m: float = 70.0
    behind_m: float = 30.0
    grid_step_m: float = 1.0
    parked_move_m: float = 2.0
    company_gap_m: float = 3.0
    company_speed_mps: float = 0.5
    company_heading_deg: float = 30.0


@dataclass(frozen=True)
class RouteParams:
    """Building routes.

    Attributes:
        min_route_m: a logged future shorter than this does not fix a direction: the lane graph is used.
        point_spacing_m: logged positions closer than this to the previous kept one are dropped (box jitter
            of a stopped agent) before smoothing.
        smooth_points: moving-average window (points) of the logged route.
        lane_search_m: a vehicle farther than this from every aligned lane has no lane.
        lane_align_deg: heading tolerance of that search.
        route_length_m: how far lane-graph routes (and extensions of logged ones) reach.
        stationary_speed_mps: agents whose logged speed stays below this over the whole log ...
        stationary_move_m: ... and whose box moves less than this are parked: kept as logged.
        parked_jitter_m: agents whose logged speed stays below ``stationary_speed_mps`` but whose box wanders
            (label jitter) less than this from its first position are parked too: replayed.
        reverse_speed_mps: a logged speed below minus this means the agent reverses: replayed.
        extension_blend_m: a logged route continues on the lane graph from this far past its last point.
        min_history_steps: valid observed steps an agent without a logged route needs to be driven (one with
            a logged route takes its intent and speeds from it: an edit present from the first frame is
            reacted to from the second step).
        max_speed_mps: desired speeds are capped at this.
        refined_m: an agent whose predicted path leaves its log by more than this is ``"refined"``.
        speed_window_s: desired speeds are the logged ones averaged over this window (centred): a box that
            jitters from step to step gives speeds that jump by metres per second, and an agent that follows
            every drop but speeds up only at its comfortable rate falls behind its log.
        max_curvature_per_m: a vehicle's (or cyclist's) heading turns by at most this many radians per metre
            it travels (a bicycle model's steering limit, about a 4 m turning radius): one that barely moves
            keeps its heading while its route eases it into the lane. Pedestrians turn freely.
    """

    min_route_m: float = 2.0
    point_spacing_m: float = 0.5
    smooth_points: int = 5
    lane_search_m: float = 3.0
    lane_align_deg: float = 45.0
    route_length_m: float = 300.0
    stationary_speed_mps: float = 0.3
    stationary_move_m: float = 1.0
    parked_jitter_m: float = 5.0
    reverse_speed_mps: float = 0.5
    extension_blend_m: float = 5.0
    min_history_steps: int = 2
    max_speed_mps: float = 40.0
    refined_m: float = 0.5
    speed_window_s: float = 1.0
    max_curvature_per_m: float = 0.25


@dataclass(frozen=True)
class ReactiveParams:
    """Everything ``ReactivePredictor`` uses."""

    idm: IDMParams = field(default_factory=IDMParams)
    gap: GapAcceptanceParams = field(default_factory=GapAcceptanceParams)
    lane_change: LaneChangeParams = field(default_factory=LaneChangeParams)
    pedestrian: PedestrianParams = field(default_factory=PedestrianParams)
    corridor: CorridorParams = field(default_factory=CorridorParams)
    route: RouteParams = field(default_factory=RouteParams)
