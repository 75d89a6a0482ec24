"""Gap acceptance at conflict points: where another agent's predicted path crosses a driven agent's route.

For each candidate pair whose headings cross (``GapAcceptanceParams.crossing_deg``), the other agent's
predicted positions (``[H]`` samples every ``sample_dt_s`` over ``horizon_s``: fixed agents' given future,
driven agents along their routes) are projected onto the driven agent's route. The first sample inside
the corridor, ahead of the agent's front and within its look-ahead, is the conflict point; the sample's
time is the other agent's arrival ``tau_other``. The driven agent stops before the conflict point (a
virtual standing obstacle, fed to IDM) when

* ``tau_other`` is under its critical gap (vehicles: ``critical_gap_s``; pedestrians: ``time_to_conflict_s``),
* it can still stop there at the hard-brake limit (otherwise it is committed and drives through), and
* the other has priority: its trajectory is fixed (it will not react); or it is a pedestrian on a
  crosswalk and the agent is not; or, both driven and neither on a crosswalk, it arrives first
  (ties: lower index first).

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
        xy: ``[M, H, 2]`` positions at ``h * sample_dt``; valid: ``[M, H]``.
        driven: ``[M]`` index among the driven agents, ``-1`` for agents whose trajectories are given.
        priority: ``[M]`` bool, a pedestrian on a crosswalk.
        is_vehicle: ``[M]`` bool.
        sample_dt: seconds between samples.
    """

    xy: np.ndarray
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
        max_decel: hard-brake limit; is_pedestrian: bool; row: the agent's index among all agents.
    """

    s: np.ndarray
    v: np.ndarray
    v_plan: np.ndarray
    half_length: np.ndarray
    half_width: np.ndarray
    critical_s: np.ndarray
    lookahead_m: np.ndarray
    max_decel: np.ndarray
    is_pedestrian: np.ndarray
    row: np.ndarray


def yield_gaps(grid: RouteGrid, k0: np.ndarray, width: int, pairs: Pairs, crossing: np.ndarray, agents: DrivenAgents,
               profiles: OffsetProfiles, pred: Predictions, size: np.ndarray, heading: np.ndarray,
               stop_margin_m: float, margin_m: float) -> np.ndarray:
    """``[N]`` gap from each driven agent's front to the point where it must stop and give way (``inf``: none).

    Args:
        grid, k0, width: the driven agents' routes and windows; pairs: candidate pairs (``corridor.route_pairs``).
        crossing: ``[P]`` bool, the pair's headings cross.
        agents, profiles: the driven agents and their lateral offset profiles.
        pred: every agent's predicted positions.
        size: ``[M, 2]`` (length, width); heading: ``[M]`` current yaw of every agent.
        stop_margin_m: distance kept before the conflict zone; margin_m: corridor margin.
    """
    n = len(agents.s)
    c = np.flatnonzero(crossing & (pred.is_vehicle[pairs.j] | ~agents.is_pedestrian[pairs.i]))
    if not c.size:
        return np.full(n, np.inf)
    i, j = pairs.i[c], pairs.j[c]
    along, lateral, yaw = grid.project(i, k0, width, pred.xy[j])  # [C, H]
    ext_along, ext_lat = box_extents(size[j, 0:1], size[j, 1:2], heading[j][:, None] - yaw)
    offset = profiles.offset(i[:, None], along)
    lo = k0[i][:, None] * grid.step
    hi = (k0[i][:, None] + width - 1) * grid.step
    ahead = along - agents.s[i][:, None]
    inside = (np.abs(lateral - offset) < agents.half_width[i][:, None] + ext_lat + margin_m) & pred.valid[j]
    inside &= (along >= lo) & (along <= hi) & (ahead > agents.half_length[i][:, None])
    inside &= ahead < agents.lookahead_m[i][:, None] + agents.half_length[i][:, None]
    has = inside.any(axis=1)
    first = np.argmax(inside, axis=1)
    rows = np.arange(len(c))
    tau_other = first * pred.sample_dt
    stop_gap = along[rows, first] - ext_along[rows, first] - stop_margin_m - (agents.s[i] + agents.half_length[i])
    stoppable = stop_gap >= agents.v[i] ** 2 / (2.0 * agents.max_decel[i]) - _EPS
    tau_self = np.maximum(stop_gap + stop_margin_m, 0.0) / np.maximum(agents.v_plan[i], _EPS)
    fixed_other = pred.driven[j] < 0
    prio_self, prio_other = pred.priority[agents.row[i]], pred.priority[j]
    first_come = (tau_other < tau_self) | ((tau_other == tau_self) & (j < agents.row[i]))
    other_first = fixed_other | (prio_other & ~prio_self) | ((prio_other == prio_self) & first_come)
    must = has & (tau_other < agents.critical_s[i]) & stoppable & other_first
    gap, _ = group_min(i, np.where(must, stop_gap, np.inf), n)
    return gap
