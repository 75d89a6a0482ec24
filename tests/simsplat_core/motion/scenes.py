"""Hand-built motion scenes: a straight two-lane road (lane 0 at y = 0, lane 1 at y = 3.5, both eastbound) and
agents over 11 history steps and 80 future steps at 10 Hz."""

from __future__ import annotations

import numpy as np

from simsplat_core.motion.predictor import MotionMap
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.lane_graph import LaneGraph
from simsplat_core.scenario.map_context import MapContext
from tests.simsplat_core.language.scenes import lane, polygon

DT = 0.1
T = 91
START = 11
CAR = (4.5, 2.0, 1.5)
TRUCK = (8.0, 2.5, 3.0)
PERSON = (0.6, 0.6, 1.8)
TIMES = np.arange(T) * DT


def road(with_crosswalk: bool = False) -> MotionMap:
    feats = [lane("lane0", 0.0, x0=-100.0, x1=400.0), lane("lane1", 3.5, x0=-100.0, x1=400.0),
             polygon("drivable_area", "road", -100.0, 400.0, -1.75, 5.25)]
    if with_crosswalk:
        feats.append(polygon("crosswalk", "cw", 28.0, 32.0, -1.75, 5.25))
    return MotionMap(LaneGraph.from_features(feats), MapContext.from_features(feats))


def track(x: np.ndarray, y: np.ndarray | float) -> dict[str, np.ndarray]:
    """An agent's ``xy [T, 2]``, heading and speed from its positions."""
    xy = np.stack([np.asarray(x, float), np.broadcast_to(np.asarray(y, float), (T,))], axis=1)
    vel = np.gradient(xy, DT, axis=0)
    spd = np.linalg.norm(vel, axis=1)
    heading = np.arctan2(vel[:, 1], vel[:, 0])
    heading = np.where(spd > 1e-6, heading, np.interp(np.arange(T), np.flatnonzero(spd > 1e-6),
                                                      heading[spd > 1e-6]) if (spd > 1e-6).any() else 0.0)
    return {"xy": xy, "heading": heading, "speed": spd}


def states(agents: list[tuple[str, str, dict[str, np.ndarray], tuple[float, float, float]]],
           valid: dict[str, np.ndarray] | None = None) -> AgentStates:
    """``(id, category, track, size)`` per agent; all valid unless ``valid`` says otherwise."""
    valid = valid or {}
    a = len(agents)
    return AgentStates(
        object_ids=tuple(x[0] for x in agents), categories=tuple(x[1] for x in agents), sources=("log",) * a,
        node_ids=np.full(a, -1), frame_idx=np.arange(T), times=TIMES.copy(),
        xy=np.stack([x[2]["xy"] for x in agents]), z=np.zeros((a, T)),
        heading=np.stack([x[2]["heading"] for x in agents]), speed=np.stack([x[2]["speed"] for x in agents]),
        size=np.array([x[3] for x in agents], float),
        valid=np.stack([valid.get(x[0], np.ones(T, bool)) for x in agents]))
