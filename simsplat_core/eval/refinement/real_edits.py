"""Scripted edits of real scenarios (the ``"<dataset>+edits"`` rows of the ``motion`` table).

Real motion datasets have agents' tracks and a map but nothing to render or ground language in, so these edits
are applied directly to a :class:`~simsplat_core.eval.refinement.real.RealScenario`'s ``AgentStates``:

* ``lead_brakes`` ("the lead vehicle brakes hard"): the nearest moving vehicle ahead of the ego in its lane at
  ``start_step`` brakes from ``start_step + BRAKE_DELAY_STEPS`` at :data:`BRAKE_DECEL_MPS2` to a stop along
  its own logged path (the jerk-limited profile of ``editing.motion.speed_profile.brake_segments``), then stands;
* ``stopped_truck`` ("insert a stopped truck in the ego lane 30 m ahead"): a :data:`TRUCK_SIZE` vehicle
  standing :data:`TRUCK_AHEAD_M` ahead of the ego along its lane (``LaneGraph.follow`` from the ego's pose at
  ``start_step``, heading along the lane), valid at every step;
* ``jaywalker`` ("a pedestrian jaywalks in front of the second car"): a pedestrian walking at
  :data:`WALK_MPS` perpendicular to the path of the second moving vehicle ahead of the ego in its lane (the
  nearest moving vehicle ahead when there is no second), from the kerb side (the car's right) so that it is on
  the car's logged position :data:`CROSS_AFTER_S` after ``start_step``; valid from ``start_step``.

"Ahead in the ego's lane" and "moving" at ``start_step`` are ``scenario.lead``'s. An edit the scenario has no
situation for returns ``None`` and logs why (:attr:`RealEdit.reason`).

Edited agents carry source ``"edited"``, inserted ones ``"inserted"``. :func:`evaluate_real_edits` then
refines each edited scenario in every mode with ``ego_reacts=True``: nothing is rendered from real motion data,
so the ego may react too (a rendered edit keeps the ego on its log for the cameras). Outcomes are measured
like the synthetic ones (``synthetic.measure``): failures over every agent with the unedited log as
``baseline`` (overlaps the log already has at that step are not the edit's), progress and stopped share over
the agents the edit did not change.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from simsplat_core.editing.motion.speed_profile import VEHICLE_LIMITS, brake_segments, integrate
from simsplat_core.eval.refinement.real import RealScenario
from simsplat_core.eval.refinement.synthetic import MotionCase, MotionOutcome, measure, synthetic_rows
from simsplat_core.motion.predictor import MotionPredictor
from simsplat_core.motion.refine import REFINE_MODES, edit_start_step, refine
from simsplat_core.scenario import lead
from simsplat_core.scenario.agents import EGO_ID, AgentStates
from simsplat_core.scenario.geometry import footprints_overlap
from simsplat_core.scenario.lead import AHEAD_RANGE_M, ego_pose, speed_at
from simsplat_core.scenario.path import Path

logger = logging.getLogger(__name__)

#: The lead vehicle starts braking this many steps after ``start_step``, at this deceleration (m/s^2).
BRAKE_DELAY_STEPS = 5
BRAKE_DECEL_MPS2 = 6.0
#: The inserted truck: (length, width, height), metres, and its distance ahead of the ego along the lane.
TRUCK_SIZE = (8.0, 2.5, 3.2)
TRUCK_AHEAD_M = 30.0
#: The jaywalker: box, walking speed, when it is on the car's path (s after ``start_step``); it starts
#: ``WALK_MPS * CROSS_AFTER_S`` = 3.5 m from the path, on the kerb side.
PEDESTRIAN_SIZE = (0.6, 0.6, 1.8)
WALK_MPS = 1.4
CROSS_AFTER_S = 2.5
#: Id of the inserted agents.
TRUCK_ID = "edit_truck"
JAYWALKER_ID = "edit_jaywalker"
#: ``name -> text`` of the edits, in table order.
EDIT_TEXTS: dict[str, str] = {
    "lead_brakes": "the lead vehicle brakes hard",
    "stopped_truck": "insert a stopped truck in the ego lane 30 m ahead",
    "jaywalker": "a pedestrian jaywalks in front of the second car",
}


@dataclass(frozen=True)
class RealEdit:
    """One scripted edit of one scenario: ``states`` (``None`` when it does not apply, then ``reason`` says why)."""

    name: str
    scenario: RealScenario
    states: AgentStates | None
    reason: str = ""
    object_id: str = ""

    @property
    def text(self) -> str:
        return EDIT_TEXTS[self.name]


# ------------------------------------------------------------------------------------------ geometry
def _ego_pose(scenario: RealScenario) -> tuple[np.ndarray, float] | None:
    return ego_pose(scenario.states, scenario.start_step)


def ego_lane_path(scenario: RealScenario, length_m: float = AHEAD_RANGE_M + 20.0) -> tuple[Path, float] | None:
    """The ego's lane ahead from its pose at ``start_step`` (``scenario.lead.ego_lane_path``)."""
    return lead.ego_lane_path(scenario.states, scenario.map.lanes, scenario.start_step, length_m, scenario.seq_id)


def vehicles_ahead(scenario: RealScenario, moving: bool = True) -> list[tuple[int, float]]:
    """``[(row, distance along the ego's lane)]`` of the vehicles ahead of the ego in its lane at ``start_step``
    (``scenario.lead.vehicles_ahead``), nearest first; only moving ones unless ``moving=False``."""
    return lead.vehicles_ahead(scenario.states, scenario.map.lanes, scenario.start_step, moving, scenario.seq_id)


def _overlaps_at(states: AgentStates, xy: np.ndarray, heading: float, size: Sequence[float], steps: np.ndarray
                 ) -> str | None:
    """Id of an agent whose box overlaps the box ``(xy, heading, size)`` at one of ``steps``, else ``None``."""
    for r in range(states.num_agents):
        ok = steps[states.valid[r, steps]]
        if not ok.size:
            continue
        n = len(ok)
        hit = footprints_overlap(np.repeat(xy[None], n, 0), np.full(n, heading),
                                 np.repeat(np.asarray(size[:2], float)[None], n, 0), states.xy[r, ok],
                                 states.heading[r, ok], np.repeat(states.size[r, :2][None], n, 0))
        if np.any(hit):
            return states.object_ids[r]
    return None


def braking_distances(v0: float, times: np.ndarray, decel: float = BRAKE_DECEL_MPS2,
                      jerk: float = VEHICLE_LIMITS.hard_jerk_mps3) -> tuple[np.ndarray, np.ndarray]:
    """``(distance, speed)`` at ``times`` (s since braking starts, ``>= 0``) of a jerk-limited stop from ``v0``
    at a peak deceleration ``decel`` (``editing.motion.speed_profile.brake_segments``); at rest after the stop."""
    segments = brake_segments(max(v0, 0.0), 0.0, decel, jerk)
    dist, speed = np.zeros(len(times)), np.zeros(len(times))
    for k, tau in enumerate(np.asarray(times, dtype=np.float64)):
        left, partial = float(tau), []
        for dur, j in segments:
            if left <= 0.0:
                break
            partial.append((min(dur, left), j))
            left -= dur
        s, v, _, _ = integrate(0.0, max(v0, 0.0), 0.0, partial)
        dist[k], speed[k] = s, max(v, 0.0)
    return dist, speed


# ------------------------------------------------------------------------------------------ edits
def lead_brakes(scenario: RealScenario) -> RealEdit:
    """The nearest moving vehicle ahead of the ego in its lane brakes hard to a stop (module docstring)."""
    name = "lead_brakes"
    ahead = vehicles_ahead(scenario)
    if not ahead:
        return _skip(name, scenario, "no moving vehicle ahead of the ego in its lane")
    states = scenario.states
    row = ahead[0][0]
    b = scenario.start_step + BRAKE_DELAY_STEPS
    if b >= states.num_steps or not states.valid[row, b]:
        return _skip(name, scenario, f"lead vehicle {states.object_ids[row]} is not observed at step {b}")
    future = np.flatnonzero(states.valid[row, b:]) + b
    points = states.xy[row, future]
    if len(points) < 2 or np.linalg.norm(points[-1] - points[0]) < 0.5:
        points = np.stack([states.xy[row, b], states.xy[row, b] + np.array([math.cos(states.heading[row, b]),
                                                                           math.sin(states.heading[row, b])])])
    path = Path.from_points(points)
    v0 = speed_at(states, row, b)
    steps = np.arange(b, states.num_steps)
    dist, speed = braking_distances(v0, states.times[steps] - states.times[b])
    xy, heading, spd, valid = states.xy[row].copy(), states.heading[row].copy(), states.speed[row].copy(), \
        states.valid[row].copy()
    xy[steps] = path.position(dist)
    heading[steps] = path.heading(dist)
    spd[steps] = speed
    valid[steps] = True
    edited = states.with_agent(states.object_ids[row], states.categories[row], "edited", xy=xy, heading=heading,
                               speed=spd, valid=valid, size=states.size[row], z=_held_z(states, row),
                               node_id=int(states.node_ids[row]))
    logger.info("%s: %s brakes from %.1f m/s at step %d (%.1f m ahead of the ego)", scenario.seq_id,
                states.object_ids[row], v0, b, ahead[0][1])
    return RealEdit(name, scenario, edited, object_id=states.object_ids[row])


def _held_z(states: AgentStates, row: int) -> np.ndarray:
    """The agent's heights with invalid steps filled by the nearest valid one (it now exists there)."""
    z = states.z[row].copy()
    ok = np.flatnonzero(states.valid[row])
    if ok.size:
        z = np.interp(np.arange(states.num_steps), ok, z[ok])
    return z


def stopped_truck(scenario: RealScenario) -> RealEdit:
    """A stopped truck in the ego's lane :data:`TRUCK_AHEAD_M` ahead (module docstring)."""
    name = "stopped_truck"
    pose = _ego_pose(scenario)
    if pose is None:
        return _skip(name, scenario, "the ego is not observed at start_step")
    if not len(scenario.map.lanes):
        return _skip(name, scenario, "the map has no lanes")
    try:
        lane = scenario.map.lanes.follow(pose[0], pose[1], max_length_m=TRUCK_AHEAD_M + 20.0)
    except ValueError:
        return _skip(name, scenario, "no lane near the ego")
    s = lane.start_s + TRUCK_AHEAD_M
    if s > lane.path.length:
        return _skip(name, scenario, f"the ego's lane ends {lane.path.length - lane.start_s:.0f} m ahead")
    states = scenario.states
    xy, heading = lane.path.position(s), float(lane.path.heading(s))
    history = np.arange(0, scenario.start_step + 1)
    occupied = _overlaps_at(states, xy, heading, TRUCK_SIZE, history)
    if occupied is not None:
        return _skip(name, scenario, f"{occupied} is on the spot by start_step")
    t = states.num_steps
    ego = states.index(EGO_ID)
    z = float(states.z[ego, scenario.start_step] - states.size[ego, 2] / 2.0 + TRUCK_SIZE[2] / 2.0)
    edited = states.with_agent(TRUCK_ID, "vehicle", "inserted", xy=np.repeat(xy[None], t, 0),
                               heading=np.full(t, heading), speed=np.zeros(t), valid=np.ones(t, bool),
                               size=TRUCK_SIZE, z=np.full(t, z))
    return RealEdit(name, scenario, edited, object_id=TRUCK_ID)


def jaywalker(scenario: RealScenario) -> RealEdit:
    """A pedestrian crossing in front of the second car ahead of the ego (module docstring)."""
    name = "jaywalker"
    ahead = vehicles_ahead(scenario)
    if len(ahead) >= 2:
        row = ahead[1][0]
    elif ahead:
        row = ahead[0][0]
    else:
        return _skip(name, scenario, "no moving vehicle ahead of the ego in its lane")
    states = scenario.states
    t0 = scenario.start_step
    if states.times[-1] < states.times[t0] + CROSS_AFTER_S:
        return _skip(name, scenario, f"the log ends before {CROSS_AFTER_S:g} s after start_step")
    tc = int(np.argmin(np.abs(states.times - (states.times[t0] + CROSS_AFTER_S))))
    if not states.valid[row, tc]:
        return _skip(name, scenario, f"{states.object_ids[row]} is not observed {CROSS_AFTER_S:g} s after start")
    cross = states.xy[row, tc]
    h = float(states.heading[row, tc])
    right = np.array([math.sin(h), -math.cos(h)])  # the kerb side of right-hand traffic
    steps = np.arange(t0, states.num_steps)
    dt = states.times[steps] - states.times[tc]
    xy = np.zeros((states.num_steps, 2))
    xy[steps] = cross[None] - right[None] * WALK_MPS * dt[:, None]  # on the kerb side before tc, beyond after
    walk = math.atan2(-right[1], -right[0])
    valid = np.zeros(states.num_steps, bool)
    valid[steps] = True
    ego = states.index(EGO_ID)
    z = float(states.z[ego, t0] - states.size[ego, 2] / 2.0 + PEDESTRIAN_SIZE[2] / 2.0)
    start_gap = float(WALK_MPS * (states.times[tc] - states.times[t0]))
    occupied = _overlaps_at(states, xy[t0], walk, PEDESTRIAN_SIZE, np.array([t0]))
    if occupied is not None:
        return _skip(name, scenario, f"{occupied} stands where the pedestrian would start")
    edited = states.with_agent(JAYWALKER_ID, "pedestrian", "inserted", xy=xy, heading=np.full(states.num_steps, walk),
                               speed=np.where(valid, WALK_MPS, 0.0), valid=valid, size=PEDESTRIAN_SIZE,
                               z=np.full(states.num_steps, z))
    logger.info("%s: a pedestrian starts %.1f m right of %s's path and crosses it at step %d", scenario.seq_id,
                start_gap, states.object_ids[row], tc)
    return RealEdit(name, scenario, edited, object_id=states.object_ids[row])


def _skip(name: str, scenario: RealScenario, reason: str) -> RealEdit:
    logger.info("%s: edit %r does not apply: %s", scenario.seq_id, name, reason)
    return RealEdit(name, scenario, None, reason)


#: ``name -> edit``, in table order.
EDITS: dict[str, Callable[[RealScenario], RealEdit]] = {
    "lead_brakes": lead_brakes, "stopped_truck": stopped_truck, "jaywalker": jaywalker}


def apply_edits(scenario: RealScenario, names: Sequence[str] = tuple(EDITS)) -> list[RealEdit]:
    """Every edit ``names`` on ``scenario`` (those that do not apply have ``states is None`` and a reason)."""
    unknown = sorted(set(names) - set(EDITS))
    if unknown:
        raise KeyError(f"unknown real edits {unknown}; known: {list(EDITS)}")
    return [EDITS[n](scenario) for n in names]


# ------------------------------------------------------------------------------------------ evaluation
def edits_dataset(dataset: str) -> str:
    """``dataset`` of the edited scenarios' rows: ``"<dataset>+edits"``."""
    return f"{dataset}+edits"


@dataclass(frozen=True)
class RealEditEvaluation:
    """What :func:`evaluate_real_edits` returns.

    Attributes:
        rows: table rows, per dataset ``"<dataset>+edits"`` one per mode.
        outcomes: every (edit, mode) outcome (cases' ``source`` ``"real-edit"``, ``kind`` the edit's name).
        applied: ``{seq_id: {edit: "" when applied, else why not}}``.
        datasets: ``{seq_id: dataset}`` of the outcomes.
    """

    rows: list[dict[str, object]]
    outcomes: list[MotionOutcome]
    applied: dict[str, dict[str, str]]
    datasets: dict[str, str]


def evaluate_edit(edit: RealEdit, predictor: MotionPredictor, mode: str) -> MotionOutcome:
    """``edit`` refined in ``mode`` (``ego_reacts=True``) and measured against the unedited log."""
    if edit.states is None:
        raise ValueError(f"{edit.scenario.seq_id}: edit {edit.name!r} did not apply: {edit.reason}")
    scenario = edit.scenario
    case = MotionCase(f"{scenario.seq_id}:{edit.name}", scenario.seq_id, "real-edit", edit.name, edit.text)
    started = time.perf_counter()
    # prediction starts where the edit departs from the log, never inside the scenario's history (a truck present
    # from the first step is reacted to from start_step: before it, everyone replays the log, which keeps clear of
    # the truck's spot, see stopped_truck)
    start = max(scenario.start_step, edit_start_step(edit.states, scenario.states))
    refined = refine(edit.states, scenario.map, predictor, mode, original=scenario.states, start_step=start,
                     ego_reacts=True)
    return measure(case, mode, refined.states, scenario.states, scenario.map.context, refined,
                   time.perf_counter() - started)


def evaluate_real_edits(scenarios: Sequence[RealScenario], predictor: MotionPredictor,
                        modes: Sequence[str] = REFINE_MODES, names: Sequence[str] = tuple(EDITS),
                        progress: Callable[[int, int, str], None] | None = None) -> RealEditEvaluation:
    """Every edit on every scenario in every mode (module docstring); rows per ``"<dataset>+edits"``."""
    edits = [e for s in scenarios for e in apply_edits(s, names)]
    applied = {s.seq_id: {e.name: e.reason for e in edits if e.scenario is s} for s in scenarios}
    todo = [e for e in edits if e.states is not None]
    outcomes: list[MotionOutcome] = []
    for edit in todo:
        for mode in modes:
            outcomes.append(evaluate_edit(edit, predictor, mode))
            if progress is not None:
                progress(len(outcomes), len(todo) * len(modes), f"{edit.scenario.seq_id} {edit.name} {mode}")
    datasets = {s.seq_id: s.dataset for s in scenarios}
    rows: list[dict[str, object]] = []
    for dataset in dict.fromkeys(s.dataset for s in scenarios):
        mine = [o for o in outcomes if datasets[o.case.seq_id] == dataset]
        rows += synthetic_rows(mine, (), dataset=edits_dataset(dataset), predictor=predictor.name)
    return RealEditEvaluation(rows, outcomes, applied, datasets)


__all__ = ["EDITS", "EDIT_TEXTS", "JAYWALKER_ID", "TRUCK_ID", "RealEdit", "RealEditEvaluation", "apply_edits",
           "braking_distances", "edits_dataset", "ego_lane_path", "evaluate_edit", "evaluate_real_edits",
           "jaywalker", "lead_brakes", "stopped_truck", "vehicles_ahead"]
