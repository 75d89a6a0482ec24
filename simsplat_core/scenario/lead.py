"""The vehicles ahead of the ego in its lane, nearest first: who "the lead vehicle" is.

"Ahead in the ego's lane" at step ``t``: the vehicle's box at least :data:`IN_LANE_M` inside the
:data:`LANE_HALF_WIDTH_M` corridor around the ego's lane path (``LaneGraph.follow`` from the ego's pose at ``t``,
straight on at branches; a straight line along the ego's heading on a map without lanes near it), 0 to
:data:`AHEAD_RANGE_M` metres ahead along it, heading within :data:`SAME_DIRECTION_DEG` of the path's. "Moving":
faster than :data:`MOVING_MPS` at ``t`` (from the box centres' displacement into ``t``).

    ahead = vehicles_ahead(states, lanes, t)        # [(row, metres along the ego's lane)], nearest first
    row = lead_vehicle(states, lanes)               # the first step with a moving one: its nearest, or None

Used by the scripted edits of real scenarios (``eval.refinement.real_edits``) and by grounding "the lead vehicle"
in an edit (``editing.grounding``).
"""

from __future__ import annotations

import logging
import math

import numpy as np

from simsplat_core.scenario.agents import EGO_ID, AgentStates
from simsplat_core.scenario.lane_graph import LaneGraph
from simsplat_core.scenario.path import Path
from simsplat_core.scenario.trajectory import agent_kind
from simsplat_core.scenario.vocabulary import VEHICLE

logger = logging.getLogger(__name__)

#: A vehicle moves when faster than this, m/s.
MOVING_MPS = 2.0
#: Half width of the ego's lane around its path, metres; a vehicle is in the lane when its box reaches at least
#: ``IN_LANE_M`` into it (a car straddling the lane line is a lead the ego must follow).
LANE_HALF_WIDTH_M = 1.75
IN_LANE_M = 0.5
#: ... and this far ahead at most, metres.
AHEAD_RANGE_M = 80.0
#: ... with a heading within this of the path's, degrees.
SAME_DIRECTION_DEG = 30.0


def ego_pose(states: AgentStates, t: int) -> tuple[np.ndarray, float] | None:
    """``(xy [2], heading)`` of the ego at step ``t``; ``None`` when it is not observed then."""
    ego = states.index(EGO_ID)
    if not states.valid[ego, t]:
        return None
    return states.xy[ego, t].copy(), float(states.heading[ego, t])


def ego_lane_path(states: AgentStates, lanes: LaneGraph, t: int, length_m: float = AHEAD_RANGE_M + 20.0,
                  seq_id: str = "") -> tuple[Path, float] | None:
    """``(path, arc length of the ego on it)``: the ego's lane ahead from its pose at step ``t`` (module
    docstring); ``None`` when the ego is not observed then."""
    pose = ego_pose(states, t)
    if pose is None:
        return None
    xy, heading = pose
    if len(lanes):
        try:
            lane = lanes.follow(xy, heading, max_length_m=length_m)
            return lane.path, lane.start_s
        except ValueError:
            logger.info("%s: no lane near the ego; its lane ahead is a straight line", seq_id or "scene")
    direction = np.array([math.cos(heading), math.sin(heading)])
    return Path.from_points(np.stack([xy, xy + length_m * direction])), 0.0


def speed_at(states: AgentStates, row: int, t: int) -> float:
    """Speed from the box centres' displacement into step ``t`` (the log's speed when ``t - 1`` is not valid), m/s."""
    if t > 0 and states.valid[row, t - 1] and states.valid[row, t]:
        return float(np.linalg.norm(states.xy[row, t] - states.xy[row, t - 1]) /
                     max(states.times[t] - states.times[t - 1], 1e-9))
    return abs(float(states.speed[row, t]))


def vehicles_ahead(states: AgentStates, lanes: LaneGraph, t: int, moving: bool = True,
                   seq_id: str = "") -> list[tuple[int, float]]:
    """``[(row, distance along the ego's lane)]`` of the vehicles ahead of the ego in its lane at step ``t``
    (module docstring), nearest first; only moving ones unless ``moving=False``."""
    lane = ego_lane_path(states, lanes, t, seq_id=seq_id)
    if lane is None:
        return []
    path, ego_s = lane
    out = []
    for r, (oid, category) in enumerate(zip(states.object_ids, states.categories)):
        if oid == EGO_ID or agent_kind(category) != VEHICLE or not states.valid[r, t]:
            continue
        if moving and speed_at(states, r, t) <= MOVING_MPS:
            continue
        p = states.xy[r, t]
        s = path.project(p)
        ahead = s - ego_s
        if not 0.0 < ahead <= AHEAD_RANGE_M or s >= path.length:
            continue
        if np.linalg.norm(path.position(s) - p) - states.size[r, 1] / 2.0 > LANE_HALF_WIDTH_M - IN_LANE_M:
            continue
        dh = abs(math.remainder(float(states.heading[r, t]) - float(path.heading(s)), 2 * math.pi))
        if dh > math.radians(SAME_DIRECTION_DEG):
            continue
        out.append((r, float(ahead)))
    return sorted(out, key=lambda x: x[1])


def lead_vehicle(states: AgentStates, lanes: LaneGraph, seq_id: str = "") -> int | None:
    """Row of the lead vehicle: the nearest moving vehicle ahead of the ego in its lane at the first step that has
    one (``None``: no step has one)."""
    ego = states.index(EGO_ID)
    for t in np.flatnonzero(states.valid[ego]):
        ahead = vehicles_ahead(states, lanes, int(t), seq_id=seq_id)
        if ahead:
            return ahead[0][0]
    return None


__all__ = ["AHEAD_RANGE_M", "IN_LANE_M", "LANE_HALF_WIDTH_M", "MOVING_MPS", "SAME_DIRECTION_DEG", "ego_lane_path",
           "ego_pose", "lead_vehicle", "speed_at", "vehicles_ahead"]
