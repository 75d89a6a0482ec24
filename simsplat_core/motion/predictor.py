"""The ``MotionPredictor`` protocol: roll every free agent of a scenario out from its observed history.

A predictor gets one :class:`RolloutRequest` (every agent's states over the whole horizon, the step where
prediction starts, the rows whose trajectories are fixed, the map) and returns a :class:`Rollout`: the
same agents over the same steps, history copied, free agents predicted from ``start_step`` on. Fixed
rows (the edited or inserted agents, the ego whose cameras render the scene, static obstacles) are
returned unchanged; a predictor reads their whole trajectory, future included, so the traffic reacts
to what the edit does later (a car that will brake, a pedestrian that will step out).

The default is the deterministic reactive traffic model (``motion.reactive``); a learned model
(SMART-like) implements the same protocol. Agents a predictor cannot drive (no lane near them, too
short a history) are replayed from the log and named in :attr:`Rollout.replayed` with the reason:
never silently dropped.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np

from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.lane_graph import LaneGraph
from simsplat_core.scenario.map_context import MapContext

#: Observed steps before prediction starts (1.1 s at 10 Hz, Waymo Open Motion's history).
DEFAULT_HISTORY_STEPS = 11


@dataclass(frozen=True)
class MotionMap:
    """The map a predictor drives on: the lane graph and the polygons (drivable area, crosswalks, ...).

    Attributes:
        lanes: directed lane graph (may be empty: then vehicles are replayed, see ``Rollout.replayed``).
        context: polygons and lane segments for off-road and crosswalk queries.
        road_edges: ``[E, 2, 2]`` road-edge segments (``(a, b)`` endpoints), empty when the map has none.
    """

    lanes: LaneGraph
    context: MapContext
    road_edges: np.ndarray = field(default_factory=lambda: np.zeros((0, 2, 2)))


@dataclass(frozen=True)
class RolloutRequest:
    """What to roll out.

    Attributes:
        states: all ``A`` agents over ``T`` steps; steps ``< start_step`` are the observed history, later
            steps of free agents hold the log's future (used for each agent's intent/route, never copied
            into the prediction), later steps of fixed agents are their imposed trajectories.
        start_step: first predicted step (``1 <= start_step < T``).
        fixed_rows: ``[F]`` rows of ``states`` whose trajectories are kept as given for every step.
        map: the map.
        use_log_routes: take each free agent's route from its logged future when it has one (keeps its
            intent: a car that turned right in the log turns right); the lane graph otherwise.
    """

    states: AgentStates
    start_step: int
    fixed_rows: np.ndarray
    map: MotionMap
    use_log_routes: bool = True

    def __post_init__(self) -> None:
        t = self.states.num_steps
        if not 1 <= self.start_step < t:
            raise ValueError(f"RolloutRequest.start_step must be in [1, {t - 1}], got {self.start_step}")
        rows = np.asarray(self.fixed_rows, dtype=np.int64)
        if rows.size and (rows.min() < 0 or rows.max() >= self.states.num_agents):
            raise ValueError(f"RolloutRequest.fixed_rows must index the {self.states.num_agents} agents, "
                             f"got {rows.tolist()}")

    @property
    def free_rows(self) -> np.ndarray:
        """``[A - F]`` rows the predictor drives."""
        fixed = set(np.asarray(self.fixed_rows, dtype=np.int64).tolist())
        return np.array([r for r in range(self.states.num_agents) if r not in fixed], dtype=np.int64)


@dataclass(frozen=True)
class Rollout:
    """A predictor's answer.

    Attributes:
        states: the same agents and steps as the request; free agents whose predicted path differs from
            the log carry ``source == "refined"``.
        replayed: ``object_id -> reason`` for free agents the predictor could not drive and replayed.
        predictor: name of the predictor that produced it.
    """

    states: AgentStates
    replayed: dict[str, str]
    predictor: str


@runtime_checkable
class MotionPredictor(Protocol):
    """Rolls out the free agents of a scenario (see the module docstring)."""

    name: str

    def rollout(self, request: RolloutRequest) -> Rollout:
        """The request's agents with free agents predicted from ``request.start_step`` on."""
        ...
