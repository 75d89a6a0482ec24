"""Lane changes into a gap: does an edited car cutting into a lane leave the vehicle behind it room to react?

MOBIL's safety criterion, as the reactive traffic model's own lane changes use it
(``motion.traffic_params.LaneChangeParams.safe_decel_mps2`` with the default car-following ``IDMParams``): when
the planned car enters another vehicle's path ahead of it, that vehicle's IDM braking behind it must not
exceed ``b_safe``. ``editing.motion_glue`` delays a lane change along the own lane until it does.

    hit = squeezed_follower(states, motion_xy, motion_heading, motion_speed, motion_valid, size, exclude, step)
"""

from __future__ import annotations

import numpy as np

from simsplat_core.geometry import wrap_angle
from simsplat_core.motion.longitudinal import IDMArrays, interaction_accel
from simsplat_core.motion.traffic_params import CorridorParams, IDMParams, LaneChangeParams
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.metrics import kind_of
from simsplat_core.scenario.vocabulary import VEHICLE

#: Vehicles whose heading is within this of the planned car's drive the same way (a follower it can squeeze).
SAME_WAY_DEG = 45.0


def squeezed_follower(states: AgentStates, xy: np.ndarray, heading: np.ndarray, speed: np.ndarray,
                      valid: np.ndarray, size: np.ndarray, exclude: tuple[str, ...], from_step: int
                      ) -> tuple[int, int] | None:
    """``(row, step)`` of the first vehicle of ``states`` (but ``exclude``) that the planned motion (``xy [T, 2]``,
    ``heading / speed / valid [T]``, box ``size [>=2]``) enters the path of, ahead of it, at a step from
    ``from_step`` on, leaving it a gap it cannot take braking at most ``b_safe``; ``None`` when there is none."""
    idm = IDMArrays.per_agent([IDMParams()])
    b_safe = LaneChangeParams().safe_decel_mps2
    margin = CorridorParams().lateral_margin_m
    steps = np.arange(states.num_steps)
    for r in range(states.num_agents):
        if states.object_ids[r] in exclude or kind_of(states.categories[r]) != VEHICLE:
            continue
        both = valid & states.valid[r] & (steps >= from_step)
        if not both.any():
            continue
        fwd = np.stack([np.cos(states.heading[r]), np.sin(states.heading[r])], axis=1)  # [T, 2]
        rel = xy - states.xy[r]
        along = (rel * fwd).sum(axis=1)
        across = np.abs(rel[:, 0] * fwd[:, 1] - rel[:, 1] * fwd[:, 0])
        same_way = np.abs(wrap_angle(heading - states.heading[r])) <= np.deg2rad(SAME_WAY_DEG)
        ahead_in_path = both & same_way & (along > 0.0) & (across < (size[1] + states.size[r, 1]) / 2.0 + margin)
        entering = ahead_in_path & ~np.concatenate([[False], ahead_in_path[:-1]])
        entering[from_step] = False  # already in its path where the plan starts: following, not cutting in
        for k in np.flatnonzero(entering).tolist():
            gap = along[k] - (size[0] + states.size[r, 0]) / 2.0
            if gap <= 0.0:
                return r, k
            v_f = np.array([max(float(states.speed[r, k]), 0.0)])
            a_f = interaction_accel(v_f, np.array([float(speed[k])]), np.array([gap]), idm)
            if float(a_f[0]) < -b_safe:
                return r, k
    return None
