"""Waymax-style validation metrics over :class:`~simsplat_core.scenario.agents.AgentStates`.

Pure functions of the agents' states (and the map) returning per-agent, per-step arrays, as Waymax's
``overlap`` / ``roadgraph`` / ``comfort`` metrics do; the editor validates an edit with them and the
refinement of the next issue scores rollouts with the same ones.

* :func:`overlap` -- ``[A, A, T]`` oriented-box overlap of every pair of valid agents (separating-axis test,
  ``geometry.footprints_overlap``), an agent never overlapping itself. Waymax's ``OverlapMetric`` is the
  ``any`` over the other agents.
* :func:`collision_steps` -- the checked rows against everyone, split by the other agent's kind (vehicle,
  pedestrian, static object). Pairs of two unedited agents (``source == "log"``) are the log's own overlaps
  (parked cars touching, boxes of a group of people) and are not collisions of the edit; given the
  unedited scenario (``baseline``), neither is a pair that overlapped there at the same step. They are
  left out and counted separately (``CollisionSteps.log_pairs``).
* :func:`offroad_steps` -- Waymax's ``OffroadMetric``: some box corner lies outside the drivable area
  (``geometry.offroad``), for vehicles and cyclists. On a map without drivable-area polygons but with road
  edges (Waymo Open Motion), Waymax's own definition: some corner lies on the non-road side of its nearest
  road edge (``geometry.offroad_by_road_edges``). Pedestrians and static objects may stand on sidewalks:
  they are off-road only where the map says where people may be (it has sidewalks and a drivable area) and
  their box centre is on none of sidewalk, crosswalk or drivable area. Nothing is off-road on a map with
  neither a drivable area nor road edges.
* :func:`kinematics` / :func:`kinematic_violations` -- Waymax's ``KinematicsInfeasibilityMetric`` (bounds on
  acceleration and steering curvature, from the motion itself: velocities are local line fits of the box
  centres, not the stored ``speed``), plus jerk, yaw-rate and speed bounds; limits per agent kind
  (:class:`KinematicLimits`, :data:`DEFAULT_LIMITS`).
* :func:`validate_agents` -- all of the above for the checked rows (edited and inserted agents) against
  every agent, as a :class:`ValidationReport`.

Steps are the states' steps; ``step`` in reports is the index into ``states.times``, ``frame`` the log frame.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.geometry import footprints_overlap, offroad, offroad_by_road_edges
from simsplat_core.scenario.map_context import MapContext
from simsplat_core.scenario.trajectory import agent_kind, smoothed_velocity, yaw_rate
from simsplat_core.scenario.vocabulary import PEDESTRIAN, VEHICLE

#: Kinds of agents the metrics tell apart (``agent_kind`` of the category; no motion codebook = static).
STATIC = "static"
KINDS: tuple[str, ...] = (VEHICLE, PEDESTRIAN, STATIC)
#: Agents compared per block in :func:`overlap` (bounds the ``[block, A, T]`` temporaries).
_PAIR_BLOCK = 32


def kind_of(category: str) -> str:
    """``"vehicle"`` (vehicles, cyclists, other movers, the ego), ``"pedestrian"`` or ``"static"``."""
    return agent_kind(category) or STATIC


@dataclass(frozen=True)
class KinematicLimits:
    """Bounds of physically plausible motion for one kind of agent (``inf`` = not checked).

    Attributes:
        max_speed_mps: ``|speed|`` bound, m/s.
        max_accel_mps2: ``|d speed / dt|`` bound, m/s^2 (Waymax: 10.4).
        max_jerk_mps3: ``|d accel / dt|`` bound, m/s^3.
        max_curvature_per_m: ``|yaw rate / speed|`` bound, 1/m (Waymax's steering curvature: 0.3), checked
            where ``|speed| >= min_speed_mps``.
        max_yaw_rate_rps: ``|d heading / dt|`` bound, rad/s, checked where ``|speed| >= min_speed_mps``.
        min_speed_mps: below this speed a box's yaw jitter is not a turn.
        half_window_s: half width of the local line fits that differentiate positions, speeds and
            accelerations (a log's box jitter is not acceleration).
    """

    max_speed_mps: float = math.inf
    max_accel_mps2: float = math.inf
    max_jerk_mps3: float = math.inf
    max_curvature_per_m: float = math.inf
    max_yaw_rate_rps: float = math.inf
    min_speed_mps: float = 2.0
    half_window_s: float = 0.2


#: Default limits per kind: vehicles get Waymax's acceleration and curvature bounds and a jerk bound above
#: any controlled manoeuvre (hard braking ramps in at 15 m/s^3); pedestrians a running person's bounds;
#: static objects must not move.
DEFAULT_LIMITS: dict[str, KinematicLimits] = {
    VEHICLE: KinematicLimits(max_speed_mps=70.0, max_accel_mps2=10.4, max_jerk_mps3=30.0,
                             max_curvature_per_m=0.3, max_yaw_rate_rps=1.5),
    PEDESTRIAN: KinematicLimits(max_speed_mps=8.0, max_accel_mps2=6.0),
    STATIC: KinematicLimits(max_speed_mps=1.0),
}


def _as_rows(states: AgentStates, rows: Sequence[int] | np.ndarray | None) -> np.ndarray:
    out = np.arange(states.num_agents) if rows is None else np.asarray(rows, dtype=np.int64).reshape(-1)
    bad = out[(out < 0) | (out >= states.num_agents)]
    if bad.size:
        raise IndexError(f"rows {bad.tolist()} out of range for {states.num_agents} agents")
    return out


def overlap_rows(states: AgentStates, rows: Sequence[int] | np.ndarray | None = None) -> np.ndarray:
    """``[R, A, T]`` bool: agent ``rows[r]``'s box overlaps agent ``a``'s at step ``t`` (both valid, ``a`` not
    ``rows[r]``). ``rows=None``: every agent (``R = A``)."""
    rows = _as_rows(states, rows)
    a, t = states.num_agents, states.num_steps
    out = np.zeros((len(rows), a, t), dtype=bool)
    size = states.size[:, :2]
    for start in range(0, len(rows), _PAIR_BLOCK):
        block = rows[start:start + _PAIR_BLOCK]
        hit = footprints_overlap(states.xy[block, None], states.heading[block, None], size[block, None, None],
                                 states.xy[None], states.heading[None], size[None, :, None])  # [b, A, T]
        hit &= states.valid[block, None] & states.valid[None]
        hit[np.arange(len(block)), block] = False
        out[start:start + len(block)] = hit
    return out


def overlap(states: AgentStates) -> np.ndarray:
    """``[A, A, T]`` bool pairwise box overlap (symmetric, false on the diagonal and at invalid steps)."""
    return overlap_rows(states)


@dataclass(frozen=True)
class CollisionSteps:
    """Overlaps of the checked rows with every other agent.

    Attributes:
        rows: ``[R]`` checked agent rows.
        pairs: ``[R, A, T]`` overlaps counted as collisions (log-vs-log pairs removed).
        vehicle, pedestrian, static: ``[R, T]`` collision with some agent of that kind.
        log_pairs: ``[R, A, T]`` overlaps that are the log's own (two unedited agents, or a pair that
            overlapped in the baseline at that step), not counted.
    """

    rows: np.ndarray
    pairs: np.ndarray
    vehicle: np.ndarray
    pedestrian: np.ndarray
    static: np.ndarray
    log_pairs: np.ndarray

    def of_kind(self, kind: str) -> np.ndarray:
        """``[R, T]`` collisions with agents of ``kind`` (one of :data:`KINDS`)."""
        if kind not in KINDS:
            raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
        return {VEHICLE: self.vehicle, PEDESTRIAN: self.pedestrian, STATIC: self.static}[kind]


def collision_steps(states: AgentStates, rows: Sequence[int] | np.ndarray,
                    baseline: AgentStates | None = None, *, count_log_pairs: bool = False) -> CollisionSteps:
    """Collisions of agents ``rows`` with everyone, per step, split by the other agent's kind.

    Two agents that both replay their log are not a collision of the edit (``log_pairs``), unless
    ``count_log_pairs`` (a rollout, where every agent's path is the predictor's). ``baseline`` (the unedited
    scenario on the same steps): a pair of agents that already overlapped there at that step is the log's
    overlap too (an edited car whose log box touched a parked car's keeps touching it before the edit changes
    anything), not a collision.
    """
    rows = _as_rows(states, rows)
    hit = overlap_rows(states, rows)
    is_log = np.array([s == "log" and not count_log_pairs for s in states.sources])
    log_pair = np.broadcast_to((is_log[rows][:, None] & is_log[None])[..., None], hit.shape).copy()  # [R, A, T]
    if baseline is not None:
        log_pair |= _baseline_overlap(states, rows, baseline)
    pairs = hit & ~log_pair
    kinds = np.array([kind_of(c) for c in states.categories])
    by_kind = {k: (pairs & (kinds == k)[None, :, None]).any(axis=1) for k in KINDS}
    return CollisionSteps(rows=rows, pairs=pairs, vehicle=by_kind[VEHICLE], pedestrian=by_kind[PEDESTRIAN],
                          static=by_kind[STATIC], log_pairs=hit & log_pair)


def _baseline_overlap(states: AgentStates, rows: np.ndarray, baseline: AgentStates) -> np.ndarray:
    """``[R, A, T]`` bool: the pair (by object id) overlapped in ``baseline`` at that step."""
    out = np.zeros((len(rows), states.num_agents, states.num_steps), dtype=bool)
    if baseline.num_steps != states.num_steps:
        raise ValueError(f"baseline has {baseline.num_steps} steps, the states {states.num_steps}")
    index = {oid: k for k, oid in enumerate(baseline.object_ids)}
    base_rows = [index.get(states.object_ids[r], -1) for r in rows]
    present = [k for k in base_rows if k >= 0]
    if not present:
        return out
    base_hit = overlap_rows(baseline, present)  # [P, A_b, T]
    cols = np.array([index.get(oid, -1) for oid in states.object_ids])
    known = cols >= 0
    p = 0
    for r, k in enumerate(base_rows):
        if k >= 0:
            out[r, known] = base_hit[p, cols[known]]
            p += 1
    return out


def offroad_steps(states: AgentStates, map_ctx: MapContext, rows: Sequence[int] | np.ndarray | None = None,
                  tolerance_m: float = 0.0) -> np.ndarray:
    """``[R, T]`` bool off-road flags of ``rows`` (default: every agent), see the module docstring.

    Vehicles (and cyclists): some box corner more than ``tolerance_m`` outside the drivable area, or, on a
    map without one, more than ``tolerance_m`` on the non-road side of its nearest road edge.
    Pedestrians and static objects: only on maps with sidewalks and a drivable area, the box centre on no
    sidewalk, crosswalk or drivable area. All false without a drivable area and road edges, and at invalid
    steps.
    """
    rows = _as_rows(states, rows)
    out = np.zeros((len(rows), states.num_steps), dtype=bool)
    by_edges = not map_ctx.has_drivable and map_ctx.has_road_edges
    if not (map_ctx.has_drivable or by_edges):
        return out
    for r, row in enumerate(rows):
        steps = np.flatnonzero(states.valid[row])
        if not steps.size:
            continue
        if kind_of(states.categories[row]) == VEHICLE:
            if by_edges:
                out[r, steps] = offroad_by_road_edges(
                    states.xy[row, steps], states.heading[row, steps], states.size[row, :2], map_ctx.edge_a,
                    map_ctx.edge_b, map_ctx.edge_next, map_ctx.edge_prev, tolerance_m, map_ctx.road_side)
            else:
                out[r, steps] = offroad(states.xy[row, steps], states.heading[row, steps], states.size[row, :2],
                                        map_ctx.drivable, tolerance_m)
        elif map_ctx.has_sidewalks and map_ctx.has_drivable:
            facts = map_ctx.facts(states.xy[row, steps], states.heading[row, steps])
            out[r, steps] = ~(facts.on_drivable | facts.on_sidewalk | facts.in_crosswalk)
    return out


@dataclass(frozen=True)
class Kinematics:
    """Derivatives of the agents' motion, ``[R, T]`` each, 0 at invalid steps and in runs of fewer than
    three valid steps.

    Attributes:
        speed: signed speed along the heading, m/s (from the box centres' fitted velocity).
        accel: m/s^2; jerk: m/s^3; yaw_rate: rad/s (positive = left); curvature: 1/m (``yaw_rate / speed``,
            0 below the kind's ``min_speed_mps``).
        checked: ``[R, T]`` bool, the step lies in a run of at least three valid steps.
    """

    speed: np.ndarray
    accel: np.ndarray
    jerk: np.ndarray
    yaw_rate: np.ndarray
    curvature: np.ndarray
    checked: np.ndarray


def _valid_runs(valid: np.ndarray) -> list[np.ndarray]:
    """Step indices of the maximal runs of consecutive true entries of ``valid [T]``."""
    steps = np.flatnonzero(valid)
    if not steps.size:
        return []
    breaks = np.flatnonzero(np.diff(steps) > 1) + 1
    return np.split(steps, breaks)


def _limits_of(limits: KinematicLimits | Mapping[str, KinematicLimits] | None, category: str) -> KinematicLimits:
    if isinstance(limits, KinematicLimits):
        return limits
    table = DEFAULT_LIMITS if limits is None else limits
    return table.get(kind_of(category), KinematicLimits())


def kinematics(states: AgentStates, rows: Sequence[int] | np.ndarray | None = None,
               limits: KinematicLimits | Mapping[str, KinematicLimits] | None = None) -> Kinematics:
    """Speed, acceleration, jerk, yaw rate and curvature of ``rows`` (default: every agent), by local line
    fits over each run of valid steps (half window and minimum turning speed from the agent's limits)."""
    rows = _as_rows(states, rows)
    shape = (len(rows), states.num_steps)
    speed, accel, jerk, rate, curv = (np.zeros(shape) for _ in range(5))
    checked = np.zeros(shape, dtype=bool)
    for r, row in enumerate(rows):
        lim = _limits_of(limits, states.categories[row])
        for run in _valid_runs(states.valid[row]):
            if len(run) < 3:
                continue
            t = states.times[run]
            heading = np.unwrap(states.heading[row, run])
            vel = smoothed_velocity(t, states.xy[row, run], lim.half_window_s)
            v = vel[:, 0] * np.cos(heading) + vel[:, 1] * np.sin(heading)
            a = smoothed_velocity(t, v[:, None], lim.half_window_s)[:, 0]
            speed[r, run], accel[r, run] = v, a
            jerk[r, run] = smoothed_velocity(t, a[:, None], lim.half_window_s)[:, 0]
            w = yaw_rate(t, heading, lim.half_window_s)
            moving = np.abs(v) >= lim.min_speed_mps
            rate[r, run] = np.where(moving, w, 0.0)
            curv[r, run] = np.where(moving, w / np.maximum(np.abs(v), lim.min_speed_mps), 0.0)
            checked[r, run] = True
    return Kinematics(speed, accel, jerk, rate, curv, checked)


#: Checked quantities: (name in reports, Kinematics field, KinematicLimits field, unit).
_BOUNDS: tuple[tuple[str, str, str, str], ...] = (
    ("speed", "speed", "max_speed_mps", "m/s"),
    ("acceleration", "accel", "max_accel_mps2", "m/s^2"),
    ("jerk", "jerk", "max_jerk_mps3", "m/s^3"),
    ("curvature", "curvature", "max_curvature_per_m", "1/m"),
    ("yaw rate", "yaw_rate", "max_yaw_rate_rps", "rad/s"),
)


def _violation_masks(states: AgentStates, rows: np.ndarray, kin: Kinematics,
                     limits: KinematicLimits | Mapping[str, KinematicLimits] | None) -> dict[str, np.ndarray]:
    """Per checked quantity, ``[R, T]`` bool where it exceeds its bound."""
    bounds = {name: np.array([getattr(_limits_of(limits, states.categories[row]), lim) for row in rows])[:, None]
              for name, _, lim, _ in _BOUNDS}
    return {name: kin.checked & (np.abs(getattr(kin, fld)) > bounds[name] + 1e-9) for name, fld, _, _ in _BOUNDS}


def kinematic_violations(states: AgentStates, limits: KinematicLimits | Mapping[str, KinematicLimits] | None = None,
                         rows: Sequence[int] | np.ndarray | None = None) -> np.ndarray:
    """``[R, T]`` bool: the motion of ``rows`` (default: every agent) exceeds some bound of its kind's
    :class:`KinematicLimits` (``limits``: one for everyone, or per kind; default :data:`DEFAULT_LIMITS`)."""
    rows = _as_rows(states, rows)
    masks = _violation_masks(states, rows, kinematics(states, rows, limits), limits)
    return np.logical_or.reduce(list(masks.values()))


# ---------------------------------------------------------------------------------------------- report
def _first(mask: np.ndarray) -> int | None:
    steps = np.flatnonzero(mask)
    return int(steps[0]) if steps.size else None


@dataclass(frozen=True)
class AgentValidation:
    """Validation of one checked agent.

    Attributes:
        object_id, category, source: the agent.
        collision_vehicle / collision_pedestrian / collision_static: its box overlaps a vehicle (the ego
            included) / a pedestrian / a static object at some step.
        collision_step, collision_with: first colliding step (any kind) and the other agent's object id there.
        offroad, offroad_step: off the drivable (walkable) area at some step, the first such step.
        kinematic, kinematic_step, kinematic_detail: some kinematic bound exceeded, the first such step and
            what (``"acceleration 12.3 m/s^2 > 10.4"``).
        steps: number of valid steps checked.
    """

    object_id: str
    category: str
    source: str
    collision_vehicle: bool = False
    collision_pedestrian: bool = False
    collision_static: bool = False
    collision_step: int | None = None
    collision_with: str | None = None
    offroad: bool = False
    offroad_step: int | None = None
    kinematic: bool = False
    kinematic_step: int | None = None
    kinematic_detail: str = ""
    steps: int = 0

    @property
    def collision(self) -> bool:
        return self.collision_vehicle or self.collision_pedestrian or self.collision_static

    @property
    def ok(self) -> bool:
        return not (self.collision or self.offroad or self.kinematic)

    def failures(self, frame_idx: np.ndarray | None = None) -> list[str]:
        """Human-readable failures (``frame_idx [T]`` turns steps into log frames in the text)."""

        def at(step: int | None) -> str:
            return f"frame {int(frame_idx[step])}" if frame_idx is not None and step is not None else f"step {step}"

        who = f"{self.category} {self.object_id!r} ({self.source})"
        out = []
        if self.collision:
            kinds = [k for k, hit in (("vehicle", self.collision_vehicle), ("pedestrian", self.collision_pedestrian),
                                      ("static object", self.collision_static)) if hit]
            out.append(f"{who} collides with {' and '.join(kinds)} agents, first with {self.collision_with!r} "
                       f"at {at(self.collision_step)}")
        if self.offroad:
            out.append(f"{who} leaves the drivable area at {at(self.offroad_step)}")
        if self.kinematic:
            out.append(f"{who} moves infeasibly at {at(self.kinematic_step)}: {self.kinematic_detail}")
        return out

    def as_dict(self) -> dict[str, Any]:
        return {name: getattr(self, name) for name in self.__dataclass_fields__} | {"ok": self.ok}


@dataclass(frozen=True)
class ValidationReport:
    """Validation of the checked agents of an edited scenario (:func:`validate_agents`).

    Attributes:
        agents: one entry per checked agent, in the order checked.
        frame_idx: ``[T]`` log frames of the steps (for messages).
        log_overlap_steps: (checked agent, other agent, step) overlaps that are the log's own, not counted.
    """

    agents: tuple[AgentValidation, ...] = ()
    frame_idx: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    log_overlap_steps: int = 0

    @property
    def ok(self) -> bool:
        return all(a.ok for a in self.agents)

    def failures(self) -> list[str]:
        """One line per failure of each agent, e.g. ``"vehicle 'ins_1' (inserted) collides with vehicle
        agents, first with 'car_3' at frame 12"``."""
        return [line for a in self.agents for line in a.failures(self.frame_idx)]

    def agent(self, object_id: str) -> AgentValidation:
        """The entry of ``object_id``. Raises ``KeyError`` naming it."""
        for a in self.agents:
            if a.object_id == object_id:
                return a
        raise KeyError(f"agent {object_id!r} was not validated (checked: {[a.object_id for a in self.agents]})")

    def as_dict(self) -> dict[str, Any]:
        """JSON-able: ``ok``, counts, ``failures`` and the per-agent entries."""
        return {
            "ok": self.ok,
            "checked": len(self.agents),
            "collisions": sum(a.collision for a in self.agents),
            "offroad": sum(a.offroad for a in self.agents),
            "kinematic": sum(a.kinematic for a in self.agents),
            "log_overlap_steps": int(self.log_overlap_steps),
            "failures": self.failures(),
            "agents": [a.as_dict() for a in self.agents],
        }


def _kinematic_summary(category: str, masks: dict[str, np.ndarray], kin: Kinematics, r: int,
                       limits: KinematicLimits | Mapping[str, KinematicLimits] | None) -> tuple[int | None, str]:
    """First step of row ``r`` exceeding a bound, and each exceeded quantity's peak against its bound, the
    most exceeded first (``"acceleration up to 30.00 m/s^2 > 10.4; jerk up to 60.00 m/s^3 > 30"``)."""
    lim = _limits_of(limits, category)
    steps, parts = [], []
    for name, fld, lim_name, unit in _BOUNDS:
        bad = masks[name][r]
        if bad.any():
            peak, bound = float(np.abs(getattr(kin, fld)[r, bad]).max()), getattr(lim, lim_name)
            steps.append(int(np.flatnonzero(bad)[0]))
            parts.append((peak / bound, f"{name} up to {peak:.2f} {unit} > {bound:g}"))
    if not steps:
        return None, ""
    return min(steps), "; ".join(text for _, text in sorted(parts, key=lambda p: -p[0]))


def validate_agents(states: AgentStates, map_ctx: MapContext, rows: Sequence[int] | np.ndarray,
                    limits: KinematicLimits | Mapping[str, KinematicLimits] | None = None,
                    offroad_tolerance_m: float = 0.0, baseline: AgentStates | None = None) -> ValidationReport:
    """Collisions (with every agent; log-vs-log pairs and, given the unedited ``baseline``, pairs that
    overlapped there at the same step left out), off-road and kinematic checks of ``rows``."""
    rows = _as_rows(states, rows)
    coll = collision_steps(states, rows, baseline)
    off = offroad_steps(states, map_ctx, rows, offroad_tolerance_m)
    kin = kinematics(states, rows, limits)
    masks = _violation_masks(states, rows, kin, limits)
    entries = []
    for r, row in enumerate(rows):
        hit_step = _first(coll.pairs[r].any(axis=0))
        other = None
        if hit_step is not None:
            other = states.object_ids[int(np.flatnonzero(coll.pairs[r, :, hit_step])[0])]
        kin_step, detail = _kinematic_summary(states.categories[row], masks, kin, r, limits)
        entries.append(AgentValidation(
            object_id=states.object_ids[row], category=states.categories[row], source=states.sources[row],
            collision_vehicle=bool(coll.vehicle[r].any()), collision_pedestrian=bool(coll.pedestrian[r].any()),
            collision_static=bool(coll.static[r].any()), collision_step=hit_step, collision_with=other,
            offroad=bool(off[r].any()), offroad_step=_first(off[r]), kinematic=kin_step is not None,
            kinematic_step=kin_step, kinematic_detail=detail, steps=int(states.valid[row].sum())))
    return ValidationReport(agents=tuple(entries), frame_idx=np.asarray(states.frame_idx),
                            log_overlap_steps=int(coll.log_pairs.sum()))
