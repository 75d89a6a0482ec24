"""How fast an inserted mover starts: it joins the traffic around it.

A car inserted ahead of traffic drives at least as fast as the vehicle driving up behind it (so the agents
replaying their log, the ego first, do not run into it), but no faster than it can still stop behind whatever
stands or drives ahead of it in its lane (a car put 5 m behind a queue creeps up to it instead of arriving at
cruising speed). An asked speed is taken as asked; pedestrians start at walking pace.
"""

from __future__ import annotations

import numpy as np

from simsplat_core.editing.behaviours.gait import WALK_MPS
from simsplat_core.editing.commands import Behaviour
from simsplat_core.editing.motion.requests import DEFAULT_CRUISE_MPS, FOLLOW_GAP_M
from simsplat_core.geometry import wrap_angle
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.trajectory import agent_kind
from simsplat_core.scenario.vocabulary import VEHICLE

#: The traffic a new vehicle joins: vehicles (the ego too) at most this far behind it in its direction, m ...
FLOW_BEHIND_M = 40.0
#: ... or whatever stands or drives at most this far ahead of it, m ...
QUEUE_AHEAD_M = 40.0
#: ... at most this far to its side, m, and (behind it) heading within this angle of it, rad.
FLOW_LATERAL_M = 2.0
FLOW_HEADING_RAD = np.deg2rad(30.0)
#: Deceleration (m/s^2) a joining car may count on to stop behind what is ahead: half the controller's comfortable
#: braking, which it reaches only after its jerk-limited ramp.
JOIN_DECEL_MPS2 = 1.5


def _lane_frame(states: AgentStates, xy: np.ndarray, heading: float, step: int) -> tuple[np.ndarray, np.ndarray]:
    """``([A] metres ahead of xy along heading, [A] metres aside)`` of every agent at ``step``."""
    forward = np.array([np.cos(heading), np.sin(heading)])
    side = np.array([-forward[1], forward[0]])
    rel = states.xy[:, step] - np.asarray(xy, np.float64)[None]  # [A, 2]
    return rel @ forward, np.abs(rel @ side)


def flow_speed(states: AgentStates, xy: np.ndarray, heading: float, step: int) -> float:
    """Speed (m/s) at ``step`` of the nearest vehicle (the ego included) driving up behind ``xy`` in its lane
    (within ``FLOW_BEHIND_M`` behind, ``FLOW_LATERAL_M`` aside, heading within ``FLOW_HEADING_RAD``), 0 when
    none."""
    ahead, lateral = _lane_frame(states, xy, heading, step)
    behind = -ahead
    same_way = np.abs(wrap_angle(states.heading[:, step] - heading)) <= FLOW_HEADING_RAD
    vehicle = np.array([agent_kind(c) == VEHICLE for c in states.categories])  # the ego's category is vehicle
    near = (behind > 0) & (behind <= FLOW_BEHIND_M) & (lateral <= FLOW_LATERAL_M)
    ok = states.valid[:, step] & vehicle & same_way & near
    if not ok.any():
        return 0.0
    nearest = np.flatnonzero(ok)[int(np.argmin(behind[ok]))]
    return float(abs(states.speed[nearest, step]))


def queue_speed(states: AgentStates, xy: np.ndarray, heading: float, step: int, length_m: float) -> float:
    """Highest speed (m/s) at which a vehicle of ``length_m`` at ``xy`` can still stop (at ``JOIN_DECEL_MPS2``,
    keeping ``FOLLOW_GAP_M``) behind the nearest agent ahead in its lane (within ``QUEUE_AHEAD_M`` ahead and
    ``FLOW_LATERAL_M`` aside; its speed along ``heading`` counts, a crossing agent's none); ``inf`` when nothing
    is ahead."""
    ahead, lateral = _lane_frame(states, xy, heading, step)
    half = np.asarray(states.size[:, 0], np.float64) / 2.0
    gap = ahead - half - length_m / 2.0
    ok = states.valid[:, step] & (ahead > 0) & (ahead <= QUEUE_AHEAD_M) & (lateral <= FLOW_LATERAL_M)
    if not ok.any():
        return float("inf")
    row = np.flatnonzero(ok)[int(np.argmin(gap[ok]))]
    along = float(states.speed[row, step] * np.cos(wrap_angle(states.heading[row, step] - heading)))
    room = max(float(gap[row]) - FOLLOW_GAP_M, 0.0)
    return float(np.sqrt(max(along, 0.0) ** 2 + 2.0 * JOIN_DECEL_MPS2 * room))


def start_speed(states: AgentStates, behaviour: Behaviour, kind: str, xy: np.ndarray, heading: float, step: int,
                length_m: float) -> float:
    """Speed (m/s) an inserted mover of ``kind`` starts with at ``xy`` (module docstring): the asked absolute speed
    (0 parks it); else, for a vehicle, the traffic's pace (at least ``DEFAULT_CRUISE_MPS``, the flow behind it)
    capped by what it can stop from behind the agent ahead; for a pedestrian ``WALK_MPS``."""
    if kind != VEHICLE:
        cruise = WALK_MPS
    else:
        cruise = max(DEFAULT_CRUISE_MPS, flow_speed(states, xy, heading, step))
    if behaviour.speed is not None:
        return behaviour.speed.target_mps(cruise)
    if kind != VEHICLE:
        return cruise
    return min(cruise, queue_speed(states, xy, heading, step, length_m))
