"""Gap acceptance at conflict points: where another agent's predicted path crosses a driven agent's route.

For each candidate pair whose headings cross or oppose (``GapAcceptanceParams.crossing_deg``), the other agent's
predicted positions (``[H]`` samples every ``sample_dt_s`` over ``horizon_s``: fixed agents' given future,
driven agents along their routes) are projected onto the driven agent's route. The first sample inside
the corridor, ahead of the agent's front and within its look-ahead, is the other's arrival ``tau_other``,
the first one outside again its departure; the stretch of route it sweeps in between is the conflict zone.
The driven agent stops before the zone (a virtual standing obstacle, fed to IDM) when

* ``tau_other`` is under its critical gap (vehicles: ``critical_gap_s``; pedestrians: ``time_to_conflict_s``),
* the two would occupy the zone at overlapping times: the other arrives before the agent has cleared it
  plus ``clearance_time_s`` (accelerating at ``a`` up to its desired speed), and leaves after the agent
  would arrive, and
* either the other is in the zone already, or its trajectory is fixed (it will not react: braking is the only
  way out), and then the agent brakes whether it can stop in time or not (at most at the hard-brake limit); or
  the agent can still stop at the hard-brake limit (otherwise it is committed and drives through) and the
  other has priority: it is a pedestrian on a crosswalk and the agent is not; or, both driven and neither on
  a crosswalk, it arrives first (ties: lower index first).

Pedestrians give way to vehicles only (pedestrians among themselves keep distance by car following).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simsplat_core.motion.corridor import Pairs, box_extents, group_min
from simsplat_core.motion.lateral import OffsetProfiles
from simsplat_core.motion.route_grid import RouteGrid

_EPS = 1e-6


@dataclass(frozen=True)
class Predictions:
    """Every agent's predicted positions over the conflict horizon.

    Attributes:
        xy: ``[M, H, 2]`` positions at ``h * sample_dt``; heading: ``[M, H]`` yaw there; valid: ``[M, H]``.
        driven: ``[M]`` index among the driven agents, ``-1`` for agents whose trajectories are given.
        priority: ``[M]`` bool, a pedestrian on a crosswalk.
        is_vehicle: ``[M]`` bool.
        sample_dt: seconds between samples.
    """

    xy: np.ndarray
    heading: np.ndarray
    valid: np.ndarray
    driven: np.ndarray
    priority: np.ndarray
    is_vehicle: np.ndarray
    sample_dt: float


@dataclass(frozen=True)
class DrivenAgents:
    """``[N]`` arrays describing the driven agents at the current step.

    Attributes:
        s, v, v_plan: arc length, speed, and the speed used for its arrival time (``max(v, v_ref)``).
        half_length, half_width: half box sizes.
        critical_s: critical gap; lookahead_m: how far along the route conflicts count.
        max_decel, max_accel: hard-brake limit and IDM's ``a``.
        is_pedestrian: bool; row: the agent's index among all agents.
    """

    s: np.ndarray
    v: np.ndarray
    v_plan: np.ndarray
    half_length: np.ndarray
    half_width: np.ndarray
    critical_s: np.ndarray
    lookahead_m: np.ndarray
    max_decel: np.ndarray
    max_accel: np.ndarray
    is_pedestrian: np.ndarray
    row: np.ndarray


def travel_time(dist: np.ndarray, v: np.ndarray, v_max: np.ndarray, accel: np.ndarray) -> np.ndarray:
    """``[...]`` time to cover ``dist`` from speed ``v``, accelerating at ``accel`` up to ``max(v, v_max)``."""
    v_top = np.maximum(v, v_max)
    t_up = (v_top - v) / accel
    d_up = v * t_up + 0.5 * accel * t_up**2
    t_short = (np.sqrt(v * v + 2.0 * accel * dist) - v) / accel
    return np.where(dist <= d_up, t_short, t_up + (dist - d_up) / np.maximum(v_top, _EPS))


def yield_gaps(grid: RouteGrid, k0: np.ndarray, width: int, pairs: Pairs, crossing: np.ndarray, agents: DrivenAgents,  # noqa: PLR0913 -- struct-of-arrays step of the vectorised predictor
               profiles: OffsetProfiles, pred: Predictions, size: np.ndarray,
               stop_margin_m: float, margin_m: float, clearance_time_s: float) -> tuple[np.ndarray, np.ndarray]:
    """``([N] gap from each driven agent's front to the point where it must stop and give way (``inf``: none),
    [N] the agent it gives way to (``-1``: none))``.

    Args:
        grid, k0, width: the driven agents' routes and windows; pairs: candidate pairs (``corridor.route_pairs``).
        crossing: ``[P]`` bool, the pair's headings cross or oppose.
        agents, profiles: the driven agents and their lateral offset profiles.
        pred: every agent's predicted positions.
        size: ``[M, 2]`` (length, width) of every agent.
        stop_margin_m: distance kept before the conflict zone; margin_m: corridor margin.
        clearance_time_s: the post-encroachment margin (``GapAcceptanceParams.clearance_time_s``).
    """
    n = len(agents.s)
    c = np.flatnonzero(crossing & (pred.is_vehicle[pairs.j] | ~agents.is_pedestrian[pairs.i]))
    if not c.size:
        return np.full(n, np.inf), np.full(n, -1)
    # only others whose predicted path comes within the agent's look-ahead of it (cheap, before projecting)
    here, _ = grid.pose(agents.s)  # [N, 2]
    reach = agents.lookahead_m[pairs.i[c]] + 2.0 * agents.half_length[pairs.i[c]] + size[pairs.j[c]].max(axis=1)
    d2 = ((pred.xy[pairs.j[c]] - here[pairs.i[c]][:, None]) ** 2).sum(-1).min(axis=1)  # [C]
    c = c[d2 < reach**2]
    if not c.size:
        return np.full(n, np.inf), np.full(n, -1)
    i, j = pairs.i[c], pairs.j[c]
    along, lateral, yaw = grid.project(i, k0, width, pred.xy[j])  # [C, H]
    ext_along, ext_lat = box_extents(size[j, 0:1], size[j, 1:2], pred.heading[j] - yaw)
    offset = profiles.offset(i[:, None], along)
    lo = k0[i][:, None] * grid.step
    hi = (k0[i][:, None] + width - 1) * grid.step
    ahead = along - agents.s[i][:, None]
    inside = (np.abs(lateral - offset) < agents.half_width[i][:, None] + ext_lat + margin_m) & pred.valid[j]
    inside &= (along >= lo) & (along <= hi) & (ahead > agents.half_length[i][:, None])
    inside &= ahead < agents.lookahead_m[i][:, None] + agents.half_length[i][:, None]
    has = inside.any(axis=1)
    horizon = inside.shape[1]
    steps = np.arange(horizon)[None]
    first = np.argmax(inside, axis=1)  # the other enters the corridor
    left = ~inside & (steps > first[:, None])
    leave = np.where(left.any(axis=1), np.argmax(left, axis=1), horizon)  # ... and is out again
    run = inside & (steps < leave[:, None])
    tau_other, tau_leave = first * pred.sample_dt, leave * pred.sample_dt
    # stop before the nearest point of the zone it sweeps (a turning path may cross nearer later)
    near_edge = np.where(run, along - ext_along, np.inf).min(axis=1)
    far_edge = np.where(run, along + ext_along, -np.inf).max(axis=1)
    front = agents.s[i] + agents.half_length[i]
    stop_gap = near_edge - stop_margin_m - front
    stoppable = stop_gap >= agents.v[i] ** 2 / (2.0 * agents.max_decel[i]) - _EPS
    v, v_plan, accel = agents.v[i], agents.v_plan[i], agents.max_accel[i]
    tau_arrive = travel_time(np.maximum(near_edge - front, 0.0), v, v_plan, accel)
    tau_clear = travel_time(np.maximum(far_edge - front, 0.0) + 2.0 * agents.half_length[i], v, v_plan, accel)
    # the two occupy the zone at overlapping times (the agent clears it ``clearance_time_s`` before the other
    # enters, or arrives after the other has left: no conflict)
    overlap = (tau_other < tau_clear + clearance_time_s) & (tau_leave > tau_arrive)
    fixed_other = pred.driven[j] < 0
    prio_self, prio_other = pred.priority[agents.row[i]], pred.priority[j]
    first_come = (tau_other < tau_arrive) | ((tau_other == tau_arrive) & (j < agents.row[i]))
    other_first = fixed_other | (prio_other & ~prio_self) | ((prio_other == prio_self) & first_come)
    there = first == 0  # already in the way: give way whatever the priority, as hard as it takes
    # a fixed other never gives way: braking (at most at the hard-brake limit) is the only way out, stoppable or not
    must = has & overlap & (tau_other < agents.critical_s[i]) & (there | fixed_other | (stoppable & other_first))
    gap, idx = group_min(i, np.where(must, stop_gap, np.inf), n)
    return gap, np.where(idx >= 0, j[np.maximum(idx, 0)], -1)
