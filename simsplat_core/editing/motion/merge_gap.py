"""Lane changes into a gap: does an edited car moving into a lane leave room to the vehicles there?

MOBIL's safety criterion, as the reactive traffic model's own lane changes use it
(``motion.traffic_params.LaneChangeParams.safe_decel_mps2`` with the default car-following ``IDMParams``): when
the planned car enters another vehicle's path ahead of it, that vehicle's IDM braking behind it must not
exceed ``b_safe``; when it enters the path of a vehicle ahead, its own braking behind that one must not either.
``editing.motion.plans`` delays (or slows) a lane change until both hold.

    hit = unsafe_merge(states, motion_xy, motion_heading, motion_speed, motion_valid, size, exclude, step)
"""

from __future__ import annotations

import numpy as np

from simsplat_core.geometry import wrap_angle
from simsplat_core.motion.longitudinal import IDMArrays, interaction_accel
from simsplat_core.motion.traffic_params import CorridorParams, IDMParams, LaneChangeParams
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.metrics import kind_of
from simsplat_core.scenario.vocabulary import VEHICLE

#: Agents whose heading is within this of a planned one's drive the same way (a follower it can squeeze; a leader
#: ahead that keeps its pace, ``editing.motion.plans.making_room``).
SAME_WAY_DEG = 45.0


def unsafe_merge(states: AgentStates, xy: np.ndarray, heading: np.ndarray, speed: np.ndarray,
                 valid: np.ndarray, size: np.ndarray, exclude: tuple[str, ...], from_step: int
                 ) -> tuple[int, int] | None:
    """``(row, step)`` of the first vehicle of ``states`` (but ``exclude``) whose path the planned motion
    (``xy [T, 2]``, ``heading / speed / valid [T]``, box ``size [>=2]``) enters at a step from ``from_step`` on
    with a gap that the one behind (that vehicle, entered ahead of; or the planned car, entering behind it)
    cannot take braking at most ``b_safe``; ``None`` when there is none."""
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
        in_path = both & same_way & (across < (size[1] + states.size[r, 1]) / 2.0 + margin)
        entering = in_path & ~np.concatenate([[False], in_path[:-1]])
        entering[from_step] = False  # already in its path where the plan starts: following, not changing lanes
        for k in np.flatnonzero(entering).tolist():
            gap = abs(float(along[k])) - (size[0] + states.size[r, 0]) / 2.0
            own, other = max(float(speed[k]), 0.0), max(float(states.speed[r, k]), 0.0)
            behind, ahead = (other, own) if along[k] > 0.0 else (own, other)  # who follows whom
            if gap <= 0.0 or float(interaction_accel(np.array([behind]), np.array([ahead]), np.array([gap]),
                                                     idm)[0]) < -b_safe:
                return r, k
    return None
