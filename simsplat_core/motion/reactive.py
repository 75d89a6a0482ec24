"""``ReactivePredictor``: the default, deterministic reactive traffic model behind ``MotionPredictor``.

Each free agent gets a route (``motion.routes``: its logged path, or the lane graph) and moves along it,
one step of the states' time axis at a time, every step vectorised over agents:

1. every driven agent's window of its route (``RouteGrid``) and the candidate pairs near it
   (``corridor.route_pairs``): fixed, edited, inserted, replayed and static agents at their given positions
   for that step, the other driven agents at their current predicted ones;
2. the leader: the nearest agent in its corridor ahead (``corridor.nearest_ahead``), and IDM's
   interaction term behind it (``longitudinal``);
3. gap acceptance: agents crossing the route that would reach it within the critical gap make the agent
   stop before the conflict point (``conflicts.yield_gaps``); pedestrians wait for vehicles the same way;
4. the free-road term tracks the agent's logged speed profile (nobody in the way: the log is reproduced);
   the acceleration is the minimum of the three (IDM+);
5. MOBIL: a vehicle closing on an obstacle standing in its lane moves into a neighbour lane with a safe
   gap, over a smooth lateral offset profile (``lateral``).

Output: positions on the route plus the lateral offset, heading from the route tangent and the offset's
slope, speed (never negative), validity from ``start_step`` to the agent's last valid log step; ``source``
``"refined"`` where the path leaves the log by more than ``RouteParams.refined_m``. Fixed rows and replayed
agents are returned exactly as given; history steps are copied.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field, replace

import numpy as np

from simsplat_core.geometry import wrap_angle
from simsplat_core.motion.conflicts import DrivenAgents, Predictions, yield_gaps
from simsplat_core.motion.corridor import Nearest, Pairs, nearest_ahead, nearest_behind, route_pairs
from simsplat_core.motion.lateral import OffsetProfiles, change_length, mobil_gain
from simsplat_core.motion.leader_filters import IgnoredLeaders, mutual_leaders
from simsplat_core.motion.longitudinal import IDMArrays, free_accel, interaction_accel, next_speed
from simsplat_core.motion.predictor import Rollout, RolloutRequest
from simsplat_core.motion.route_grid import RouteGrid
from simsplat_core.motion.routes import RoutePlan, plan_routes
from simsplat_core.motion.traffic_params import ReactiveParams
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.geometry import points_in_polygon
from simsplat_core.scenario.metrics import kind_of
from simsplat_core.scenario.vocabulary import PEDESTRIAN, VEHICLE

logger = logging.getLogger(__name__)


def _given_velocity(states: AgentStates) -> np.ndarray:
    """``[A, T, 2]`` velocity of the given trajectories: position differences where two consecutive steps are
    valid, the stored speed along the heading otherwise."""
    dt = np.maximum(np.diff(states.times), 1e-6)
    vel = states.speed[..., None] * np.stack([np.cos(states.heading), np.sin(states.heading)], axis=-1)
    diff = np.diff(states.xy, axis=1) / dt[None, :, None]
    both = states.valid[:, 1:] & states.valid[:, :-1]
    vel[:, 1:] = np.where(both[..., None], diff, vel[:, 1:])
    return vel


@dataclass
class _Driven:
    """Mutable per-step state of the ``N`` driven agents (arrays ``[N]``)."""

    rows: np.ndarray
    s: np.ndarray
    v: np.ndarray
    v_ref: np.ndarray  # [N, T]
    last_valid: np.ndarray
    half_length: np.ndarray
    half_width: np.ndarray
    is_pedestrian: np.ndarray
    idm: IDMArrays
    critical_s: np.ndarray
    lookahead_m: np.ndarray
    shift_left: np.ndarray
    shift_right: np.ndarray
    profiles: OffsetProfiles
    log_end: np.ndarray  # [N] arc length where the logged route ends (0: lane-graph route)


#: Codes of :attr:`LimitTrace.rule`: what set a driven agent's acceleration at a step.
RULE_FREE, RULE_LEADER, RULE_GAP = 0, 1, 2
#: Names of the rule codes, by code.
RULE_NAMES: tuple[str, ...] = ("free road", "leader", "gap acceptance")


@dataclass(frozen=True)
class LimitTrace:
    """What held each driven agent back at each step of a rollout (filled by ``ReactivePredictor.traced_rollout``).

    Attributes:
        rows: ``[N]`` the driven agents' rows in the request's states.
        rule: ``[N, T]`` :data:`RULE_FREE` / :data:`RULE_LEADER` / :data:`RULE_GAP` (free road before ``start``).
        other: ``[N, T]`` row of the leader or of the agent given way to (``-1``: none).
        gap: ``[N, T]`` metres from the agent's front to that leader or stop point (``inf``: none).
    """

    rows: np.ndarray
    rule: np.ndarray
    other: np.ndarray
    gap: np.ndarray

    @classmethod
    def empty(cls, rows: np.ndarray, steps: int) -> LimitTrace:
        """A trace of ``rows`` over ``steps`` steps with nobody held back."""
        n = len(rows)
        return cls(rows, np.zeros((n, steps), np.int8), np.full((n, steps), -1, np.int64), np.full((n, steps), np.inf))

    def record(self, t: int, a_free: np.ndarray, a_lead: np.ndarray, a_yield: np.ndarray, leader: np.ndarray,
               lead_gap: np.ndarray, yielded_to: np.ndarray, yield_gap: np.ndarray) -> None:
        """Step ``t``'s limiting rule per agent (the smallest of the three ``[N]`` accelerations)."""
        held = np.minimum(a_lead, a_yield) < a_free - 1e-9
        by_leader = held & (a_lead <= a_yield)
        by_gap = held & ~by_leader
        self.rule[:, t] = np.where(by_leader, RULE_LEADER, np.where(by_gap, RULE_GAP, RULE_FREE))
        self.other[:, t] = np.where(by_leader, leader, np.where(by_gap, yielded_to, -1))
        self.gap[:, t] = np.where(by_leader, lead_gap, np.where(by_gap, yield_gap, np.inf))


@dataclass
class ReactivePredictor:
    """IDM+ car following, gap acceptance, pedestrian waiting and MOBIL detours along per-agent routes.

    Attributes:
        params: every parameter (``motion.traffic_params``).
        name: ``"reactive"``.
    """

    params: ReactiveParams = field(default_factory=ReactiveParams)
    name: str = "reactive"

    def rollout(self, request: RolloutRequest) -> Rollout:
        """The request's agents with the free ones driven from ``request.start_step`` on."""
        return self.traced_rollout(request)[0]

    def traced_rollout(self, request: RolloutRequest) -> tuple[Rollout, LimitTrace]:
        """:meth:`rollout` plus what held each driven agent back at each step (:class:`LimitTrace`)."""
        states, start = request.states, request.start_step
        plan = plan_routes(request, self.params.route, self.params.pedestrian)
        replayed = {states.object_ids[r]: reason for r, reason in plan.replayed.items()}
        if not plan.routes:
            return Rollout(states, replayed, self.name), LimitTrace.empty(np.zeros(0, np.int64), states.num_steps)
        xy, heading, speed = states.xy.copy(), states.heading.copy(), states.speed.copy()
        valid, z = states.valid.copy(), states.z.copy()
        drv = self._driven(request, plan)
        grid = self._grid(request, plan, drv)
        trace = LimitTrace.empty(drv.rows.copy(), states.num_steps)
        self._simulate(request, drv, grid, xy, heading, speed, valid, z, trace)
        sources = self._sources(states, drv, xy, start)
        out = replace(states, xy=xy, heading=heading, speed=speed, valid=valid, z=z, sources=sources)
        logger.debug("reactive rollout: %d driven, %d replayed", len(drv.rows), len(replayed))
        return Rollout(out, replayed, self.name), trace

    # ------------------------------------------------------------------ set-up
    def _driven(self, request: RolloutRequest, plan: RoutePlan) -> _Driven:
        p = self.params
        states, last_obs = request.states, request.start_step - 1
        rows = np.array([r.row for r in plan.routes], dtype=np.int64)
        ped = np.array([r.kind == PEDESTRIAN for r in plan.routes])
        v_ref = np.stack([r.v_ref for r in plan.routes])
        s0 = np.array([r.s0 for r in plan.routes])
        v0 = v_ref[:, last_obs].copy()
        lc = p.lane_change
        length = np.maximum(v0 * lc.duration_s, lc.min_length_m)
        profiles = OffsetProfiles(start=s0.copy(), length=length, origin=np.array([r.offset0 for r in plan.routes]),
                                  target=np.zeros(len(rows)))
        idm = IDMArrays.per_agent([p.pedestrian.following if k else p.idm for k in ped])
        dt = np.maximum(np.diff(states.times[last_obs:]), 1e-6)
        log_accel = np.percentile(np.diff(v_ref[:, last_obs:], axis=1) / dt, 95, axis=1) if dt.size \
            else np.zeros(len(rows))
        idm = replace(idm, max_accel=np.where(ped, idm.max_accel,
                                              np.clip(log_accel, idm.max_accel,
                                                      np.maximum(idm.max_accel, p.idm.log_accel_cap_mps2))))
        size = states.size[rows]
        return _Driven(rows=rows, s=s0, v=v0, v_ref=v_ref, last_valid=np.array([r.last_valid for r in plan.routes]),
                       half_length=size[:, 0] / 2.0, half_width=size[:, 1] / 2.0, is_pedestrian=ped, idm=idm,
                       critical_s=np.where(ped, p.pedestrian.time_to_conflict_s, p.gap.critical_gap_s),
                       lookahead_m=np.where(ped, p.pedestrian.wait_radius_m, p.corridor.ahead_m),
                       shift_left=np.array([r.lane_shift[0] for r in plan.routes]),
                       shift_right=np.array([r.lane_shift[1] for r in plan.routes]), profiles=profiles,
                       log_end=np.array([r.log_end for r in plan.routes]))

    def _grid(self, request: RolloutRequest, plan: RoutePlan, drv: _Driven) -> RouteGrid:
        c = self.params.corridor
        horizon = float(request.states.times[-1] - request.states.times[request.start_step - 1])
        reach = float(np.max(drv.s + drv.v_ref.max(axis=1) * horizon))
        length = max(reach, 0.0) + c.ahead_m + c.behind_m
        return RouteGrid.from_paths([r.path for r in plan.routes], length, c.grid_step_m)

    # ------------------------------------------------------------------ the step loop
    def _simulate(self, request: RolloutRequest, drv: _Driven, grid: RouteGrid, xy: np.ndarray, heading: np.ndarray,
                  speed: np.ndarray, valid: np.ndarray, z: np.ndarray, trace: LimitTrace) -> None:
        """Fill the driven rows of ``xy / heading / speed / valid / z [A, T]`` from ``start_step`` on, in place,
        and ``trace`` with what limited each agent."""
        p = self.params
        states, start = request.states, request.start_step
        t_count, n = states.num_steps, len(drv.rows)
        kinds = [kind_of(c) for c in states.categories]
        is_vehicle = np.array([k == VEHICLE for k in kinds])
        is_ped_all = np.array([k == PEDESTRIAN for k in kinds])
        is_log = np.array([src == "log" for src in states.sources])
        driven_of = np.full(states.num_agents, -1)
        driven_of[drv.rows] = np.arange(n)
        given = driven_of < 0
        vel_given = _given_velocity(states)
        size2 = states.size[:, :2]
        width = int(np.ceil((p.corridor.behind_m + p.corridor.ahead_m) / grid.step)) + 1
        reach = p.corridor.ahead_m + float(size2.max(initial=0.0))
        horizon = int(np.floor(p.gap.horizon_s / p.gap.sample_dt_s)) + 1
        tau = np.arange(horizon) * p.gap.sample_dt_s  # [H]
        horizon_steps = int(np.ceil(p.gap.horizon_s / float(np.median(np.diff(states.times)))))
        cos_cross = np.cos(np.deg2rad(p.gap.crossing_deg))
        crosswalks = request.map.context.crosswalks
        last_z = z[drv.rows, start - 1].copy()
        ignored = IgnoredLeaders.of(states, drv.rows, start - 1, given, is_log, is_ped_all, drv.log_end,
                                     p.corridor)
        for t in range(start, t_count):
            dt = float(states.times[t] - states.times[t - 1])
            cur_xy, cur_heading, cur_valid = xy[:, t - 1], heading[:, t - 1], valid[:, t - 1]
            vel = vel_given[:, t - 1].copy()
            vel[drv.rows] = drv.v[:, None] * np.stack([np.cos(cur_heading[drv.rows]), np.sin(cur_heading[drv.rows])], 1)
            # given agents that appear within the conflict horizon (a pedestrian stepping out later) are
            # candidates too, where they will appear: gap acceptance sees them coming, car following does not
            see_xy, see_heading, seen = self._appearing(states, t, horizon_steps, given, cur_xy, cur_heading,
                                                        cur_valid)
            k0 = grid.window_start(drv.s, p.corridor.behind_m, width)
            pairs = route_pairs(grid, k0, width, cur_xy[drv.rows], drv.rows, see_xy, see_heading, size2, vel,
                                seen, reach)
            offset = drv.profiles.offset(pairs.i, pairs.along)
            # crossing or oncoming: a moving agent heading against a vehicle's route is a conflict, never a leader;
            # pedestrians meeting head-on keep their distance by following (they give way to vehicles only)
            cos_rel = np.cos(see_heading[pairs.j] - pairs.yaw)
            walkers = drv.is_pedestrian[pairs.i] & is_ped_all[pairs.j]
            crossing = np.where(walkers, np.abs(cos_rel), cos_rel) < cos_cross
            moving = np.hypot(vel[pairs.j, 0], vel[pairs.j, 1]) >= p.lane_change.blocked_speed_mps
            follows = ~(crossing & moving) & cur_valid[pairs.j]  # moving crossing agents: gap acceptance
            follows &= ~ignored.pairs(pairs)  # parked obstacles the log passes, companions
            lead = nearest_ahead(pairs, drv.s, drv.half_length, drv.half_width, offset, p.corridor.lateral_margin_m,
                                 mask=follows)
            lead = self._break_deadlocks(pairs, drv, driven_of, lead, offset, follows)
            if t == start:  # the log's own following distances (behind unedited agents only)
                log_leader = (lead.other >= 0) & is_log[np.maximum(lead.other, 0)]
                drv.idm = drv.idm.calibrated(drv.v, lead.speed, np.where(log_leader, lead.gap, np.inf))
            a_lead = interaction_accel(drv.v, lead.speed, lead.gap, drv.idm)
            # gap acceptance against every agent's predicted positions
            v_plan = np.maximum(drv.v, drv.v_ref[:, t])
            pred = self._predictions(states, grid, drv, t, tau, v_plan, given, is_vehicle, is_ped_all, cur_xy,
                                     cur_valid, crosswalks)
            agents = DrivenAgents(s=drv.s, v=drv.v, v_plan=v_plan, half_length=drv.half_length,
                                  half_width=drv.half_width, critical_s=drv.critical_s, lookahead_m=drv.lookahead_m,
                                  max_decel=drv.idm.max_decel, max_accel=drv.idm.max_accel,
                                  is_pedestrian=drv.is_pedestrian, row=drv.rows)
            y_gap, y_other = yield_gaps(grid, k0, width, pairs, crossing, agents, drv.profiles, pred, size2,
                                        p.gap.stop_margin_m, p.corridor.lateral_margin_m,
                                        p.gap.clearance_time_s)
            a_yield = interaction_accel(drv.v, np.zeros(n), y_gap, drv.idm)
            a_free = free_accel(drv.v, drv.v_ref[:, t], drv.v_ref[:, t - 1], dt, drv.idm)
            accel = np.minimum(np.minimum(a_free, a_lead), a_yield)
            self._note_limits(trace, states, t, drv, (a_free, a_lead, a_yield), lead, y_other, y_gap)
            self._lane_change(drv, pairs, follows, cur_valid[pairs.j], lead, a_lead)
            # the positional bound holds against real obstacles only: a give-way line is no wall, an agent that
            # finds it too late brakes at the hard-brake limit and stops a little past it
            v_new = next_speed(drv.v, accel, dt, lead.gap, drv.idm)
            drv.s = drv.s + v_new * dt
            drv.v = v_new
            pos, yaw = self._steered_pose(grid, drv, heading[drv.rows, t - 1], cur_valid[drv.rows] & ~drv.is_pedestrian,
                                          v_new * dt)
            xy[drv.rows, t], heading[drv.rows, t], speed[drv.rows, t] = pos, yaw, v_new
            valid[drv.rows, t] = t <= drv.last_valid
            log_ok = states.valid[drv.rows, t]
            last_z = np.where(log_ok, states.z[drv.rows, t], last_z)
            z[drv.rows, t] = last_z

    def _break_deadlocks(self, pairs: Pairs, drv: _Driven, driven_of: np.ndarray, lead: Nearest, offset: np.ndarray,
                         follows: np.ndarray) -> Nearest:
        """``lead`` with mutual leaders (``i`` follows ``j`` and ``j`` follows ``i``: both would wait for ever)
        resolved: the first of each pair in row order
        ignores the other."""
        mutual = mutual_leaders(lead.other, driven_of, drv.rows)
        if not mutual.any():
            return lead
        drop = mutual[pairs.i] & (pairs.j == lead.other[pairs.i])
        logger.debug("mutual leaders: %d agents ignore each other", int(mutual.sum()))
        return nearest_ahead(pairs, drv.s, drv.half_length, drv.half_width, offset,
                             self.params.corridor.lateral_margin_m, mask=follows & ~drop)

    def _note_limits(self, trace: LimitTrace, states: AgentStates, t: int, drv: _Driven,
                     accels: tuple[np.ndarray, np.ndarray, np.ndarray], lead: Nearest, yielded_to: np.ndarray,
                     yield_gap: np.ndarray) -> None:
        """Record step ``t``'s limits (``accels``: free, leader and give-way terms ``[N]``) into ``trace``; log
        them at debug level."""
        a_free, a_lead, a_yield = accels
        trace.record(t, a_free, a_lead, a_yield, lead.other, lead.gap, yielded_to, yield_gap)
        if logger.isEnabledFor(logging.DEBUG):
            self._log_limits(states, t, drv, a_free, a_lead, a_yield, lead.other, yielded_to)

    @staticmethod
    def _log_limits(states: AgentStates, t: int, drv: _Driven, a_free: np.ndarray, a_lead: np.ndarray,
                    a_yield: np.ndarray, leader: np.ndarray, yielded_to: np.ndarray) -> None:
        """Debug: the driven agents held back by a leader or by giving way at step ``t``."""
        ids = states.object_ids
        for k in np.flatnonzero(np.minimum(a_lead, a_yield) < a_free - 1e-9).tolist():
            row = int(drv.rows[k])
            if a_lead[k] <= a_yield[k]:
                logger.debug("t=%d %s follows %s (a=%.2f, free %.2f)", t, ids[row], ids[int(leader[k])], a_lead[k],
                             a_free[k])
            else:
                logger.debug("t=%d %s gives way to %s (a=%.2f, free %.2f)", t, ids[row], ids[int(yielded_to[k])],
                             a_yield[k], a_free[k])

    @staticmethod
    def _appearing(states: AgentStates, t: int, horizon_steps: int, given: np.ndarray, cur_xy: np.ndarray,
                   cur_heading: np.ndarray, cur_valid: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``([A, 2] xy, [A] heading, [A] bool)``: the agents' current poses, with given agents that are not valid
        now but appear within ``horizon_steps`` placed where they appear, and which agents those are plus the
        currently valid ones."""
        window = states.valid[:, t - 1:t - 1 + horizon_steps]  # [A, W]
        first = np.argmax(window, axis=1)
        appear = given & ~cur_valid & window.any(axis=1)
        rows = np.flatnonzero(appear)
        xy, heading = cur_xy.copy(), cur_heading.copy()
        xy[rows] = states.xy[rows, t - 1 + first[rows]]
        heading[rows] = states.heading[rows, t - 1 + first[rows]]
        return xy, heading, cur_valid | appear

    def _steered_pose(self, grid: RouteGrid, drv: _Driven, previous: np.ndarray, limited: np.ndarray,
                      travelled: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`_pose`, its heading turned from ``previous [N]`` by at most ``max_curvature_per_m`` times the
        distance ``travelled [N]`` where ``limited [N]`` (vehicles observed at the previous step)."""
        pos, yaw = self._pose(grid, drv)
        limit = self.params.route.max_curvature_per_m * np.abs(travelled)
        turned = previous + np.clip(wrap_angle(yaw - previous), -limit, limit)
        return pos, np.where(limited, wrap_angle(turned), yaw)

    def _pose(self, grid: RouteGrid, drv: _Driven) -> tuple[np.ndarray, np.ndarray]:
        """``([N, 2] centre, [N] yaw)`` of the driven agents: route point plus lateral offset."""
        rows = np.arange(len(drv.s))
        base, yaw = grid.pose(drv.s)
        off = drv.profiles.offset(rows, drv.s)
        normal = np.stack([-np.sin(yaw), np.cos(yaw)], axis=1)
        return base + off[:, None] * normal, wrap_angle(yaw + np.arctan(drv.profiles.slope(rows, drv.s)))

    def _predictions(self, states: AgentStates, grid: RouteGrid, drv: _Driven, t: int, tau: np.ndarray,  # noqa: PLR0913 -- struct-of-arrays step of the vectorised predictor
                     v_plan: np.ndarray, given: np.ndarray, is_vehicle: np.ndarray, is_ped: np.ndarray,
                     cur_xy: np.ndarray, cur_valid: np.ndarray, crosswalks: tuple[np.ndarray, ...]) -> Predictions:
        """Every agent's positions over the conflict horizon: given trajectories for fixed / replayed agents,
        the route at the planned speed for driven ones."""
        t_count = states.num_steps
        step_dt = float(np.median(np.diff(states.times)))
        ahead = t - 1 + np.rint(tau / step_dt).astype(np.int64)  # [H]
        idx = np.clip(ahead, 0, t_count - 1)
        pred_xy = states.xy[:, idx].copy()  # [A, H, 2]
        pred_heading = states.heading[:, idx].copy()  # [A, H]
        pred_valid = states.valid[:, idx] & (ahead <= t_count - 1)[None]  # nobody is known past the data's end
        s_future = drv.s[:, None] + v_plan[:, None] * tau[None]  # [N, H]
        base, yaw = grid.pose(s_future)
        off = drv.profiles.offset(np.arange(len(drv.s))[:, None], s_future)
        pred_xy[drv.rows] = base + off[..., None] * np.stack([-np.sin(yaw), np.cos(yaw)], axis=-1)
        pred_heading[drv.rows] = yaw + np.arctan(drv.profiles.slope(np.arange(len(drv.s))[:, None], s_future))
        pred_valid[drv.rows] = cur_valid[drv.rows, None]
        priority = np.zeros(len(given), dtype=bool)
        peds = np.flatnonzero(is_ped & cur_valid)
        for poly in crosswalks:  # a handful of polygons
            if peds.size:
                priority[peds] |= points_in_polygon(cur_xy[peds], poly)
        driven = np.where(given, -1, 0)
        driven[drv.rows] = np.arange(len(drv.rows))
        sample_dt = float(tau[1] - tau[0]) if len(tau) > 1 else step_dt
        return Predictions(pred_xy, pred_heading, pred_valid, driven, priority, is_vehicle, sample_dt)

    def _lane_change(self, drv: _Driven, pairs: Pairs, follows: np.ndarray, present: np.ndarray, lead: Nearest,
                     a_lead: np.ndarray) -> None:
        """MOBIL: start a move into a neighbour lane for vehicles closing on an obstacle standing in their lane
        (``follows [P]``: the pairs that count as leaders, ``present [P]``: the other agent is there now,
        ``lead`` / ``a_lead``: the current leader and its IDM term)."""
        p = self.params
        lc, margin = p.lane_change, p.corridor.lateral_margin_m
        blocked = (~drv.is_pedestrian & drv.profiles.settled(drv.s) & (lead.other >= 0)
                   & (np.abs(lead.speed) < lc.blocked_speed_mps) & (lead.gap < lc.trigger_gap_m))
        if not blocked.any():
            return
        length = change_length(drv.v, lead.gap, lc.duration_s, lc.min_length_m, lc.clearance_m)
        blocked &= np.isfinite(length)
        best_gain = np.full(len(drv.s), -np.inf)
        best_shift = np.zeros(len(drv.s))
        free = drv.idm.max_accel
        for shift in (drv.shift_left, drv.shift_right):  # two sides
            ok = blocked & np.isfinite(shift)
            if not ok.any():
                continue
            target = drv.profiles.target + np.where(ok, shift, 0.0)
            off = target[pairs.i]
            new_lead = nearest_ahead(pairs, drv.s, drv.half_length, drv.half_width, off, margin, mask=follows)
            a_new = interaction_accel(drv.v, new_lead.speed, new_lead.gap, drv.idm)
            foll = nearest_behind(pairs, drv.s, drv.half_length, drv.half_width, off, margin, mask=present)
            v_f = np.maximum(foll.speed, 0.0)
            a_f = np.where(foll.other >= 0, interaction_accel(v_f, drv.v, np.maximum(foll.gap, 1e-3), drv.idm), free)
            safe = (a_f >= -lc.safe_decel_mps2) & (foll.gap > 0.0)
            gain = mobil_gain(a_lead, a_new, free, a_f, lc.politeness)
            take = ok & safe & (gain > lc.threshold_mps2) & (gain > best_gain)
            best_gain = np.where(take, gain, best_gain)
            best_shift = np.where(take, shift, best_shift)
        rows = np.flatnonzero(np.isfinite(best_gain))
        if not rows.size:
            return
        origin = drv.profiles.target[rows]
        shift = best_shift[rows]
        drv.profiles.replace(rows, drv.s[rows], length[rows], origin, origin + shift)
        left = shift > 0
        drv.shift_right[rows] = np.where(left, -shift, np.nan)
        drv.shift_left[rows] = np.where(left, np.nan, -shift)
        logger.debug("lane change of %d agents", rows.size)

    # ------------------------------------------------------------------ output
    def _sources(self, states: AgentStates, drv: _Driven, xy: np.ndarray, start: int) -> tuple[str, ...]:
        dev = np.linalg.norm(xy[drv.rows, start:] - states.xy[drv.rows, start:], axis=-1)
        dev = np.where(states.valid[drv.rows, start:], dev, 0.0).max(axis=1, initial=0.0)
        sources = list(states.sources)
        for k, row in enumerate(drv.rows.tolist()):
            if dev[k] > self.params.route.refined_m:
                sources[row] = "refined"
        return tuple(sources)
