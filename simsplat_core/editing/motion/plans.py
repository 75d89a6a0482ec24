"""Between the edit ops and the placement resolver / motion controller: requests in, step-grid motions out.

* :func:`resolve` -- a command's placement as a pose (``editing.placement.resolve.resolve_placement``);
* :func:`plan_inserted` -- how an inserted object moves: vehicles drive along their lane at a sensible speed
  (``editing.motion.requests.DEFAULT_CRUISE_MPS``, keeping a gap to the traffic ahead) unless told otherwise (an
  absolute speed of 0 parks them; one placed parked outside the lanes stays parked unless told to move),
  pedestrians walk (``editing.behaviours.gait.WALK_MPS``) along the sidewalk or
  cross when told, static objects stand still;
* :func:`plan_modified` -- a target's new motion from its log trajectory (``editing.motion.controller``);
* :class:`Motion` -- the result on the step grid, and :func:`changed_motion` (does it differ from the log?).
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import torch

from simsplat_core.editing.assets.record import Asset
from simsplat_core.editing.commands import Behaviour, Placement, StopSpec, TargetRef
from simsplat_core.editing.draft import Draft
from simsplat_core.editing.motion.controller import PlannedTrajectory, plan_pedestrian, plan_vehicle
from simsplat_core.editing.motion.joining import start_speed
from simsplat_core.editing.motion.merge_gap import SAME_WAY_DEG, unsafe_merge
from simsplat_core.editing.motion.requests import (
    LogTrajectory,
    OtherAgent,
    PassingStep,
    PedestrianMotionRequest,
    StartState,
    VehicleMotionRequest,
    motion_kind,
    target_speed,
    traffic_from_states,
)
from simsplat_core.editing.placement.resolve import AnchorPose, PlacedPose, resolve_placement
from simsplat_core.editing.result import EditRefused
from simsplat_core.geometry import wrap_angle
from simsplat_core.motion.refine import fixed_rows
from simsplat_core.scenario.agents import EGO_ID, AgentStates
from simsplat_core.scenario.geometry import footprints_overlap
from simsplat_core.scenario.trajectory import agent_kind
from simsplat_core.scenario.vocabulary import PARKED, PEDESTRIAN, VEHICLE
from simsplat_core.scene.pose_track import PoseTrack
from simsplat_core.scene.transforms import poses_from_boxes

logger = logging.getLogger(__name__)

#: A motion differing from the log by less than this (m, m/s) everywhere changes nothing.
UNCHANGED_TOL = 0.05


@dataclass(frozen=True)
class Motion:
    """An agent's motion on the step grid: ``xy [T, 2]``, ``heading [T]``, ``speed [T]`` (signed), ``valid [T]``,
    ``arc_length [T]`` metres travelled (``None``: not tracked), and a phrase for people."""

    xy: np.ndarray
    heading: np.ndarray
    speed: np.ndarray
    valid: np.ndarray
    arc_length: np.ndarray | None
    description: str

    @classmethod
    def planned(cls, plan: PlannedTrajectory, description: str) -> Motion:
        return cls(plan.xy, plan.heading, plan.speed, plan.valid, plan.arc_length, description)

    @classmethod
    def standing(cls, xy: np.ndarray, heading: float, steps: int, description: str = "standing still") -> Motion:
        return cls(np.tile(np.asarray(xy, np.float64), (steps, 1)), np.full(steps, float(heading)), np.zeros(steps),
                   np.ones(steps, bool), np.zeros(steps), description)

    def track(self, frame_idx: np.ndarray, z: np.ndarray) -> PoseTrack:
        """Box poses at the step frames (``z [T]`` box-centre heights), present where valid."""
        center = np.concatenate([self.xy, np.asarray(z, np.float64).reshape(-1, 1)], axis=1)
        poses = torch.as_tensor(poses_from_boxes(center, self.heading), dtype=torch.float32)
        return PoseTrack(np.asarray(frame_idx, np.float64), poses, torch.as_tensor(self.valid))


def changed_motion(states: AgentStates, row: int, motion: Motion) -> bool:
    """Whether ``motion`` differs from agent ``row`` 's current one (validity, position or speed)."""
    valid = states.valid[row]
    if not np.array_equal(valid, motion.valid):
        return True
    if not valid.any():
        return False
    dxy = np.linalg.norm(states.xy[row][valid] - motion.xy[valid], axis=1).max()
    dv = np.abs(states.speed[row][valid] - motion.speed[valid]).max()
    return bool(dxy > UNCHANGED_TOL or dv > UNCHANGED_TOL)


def anchor_pose(draft: Draft, object_id: str, label: str, step: int, index: int) -> AnchorPose:
    """Agent ``object_id`` at ``step`` as a placement anchor (``EditRefused`` when it is not there then)."""
    try:
        return AnchorPose.from_states(draft.states, draft.row_of(object_id), step, label)
    except ValueError:
        frame = int(draft.states.frame_idx[step])
        raise EditRefused(f"{label} is not in the scene at frame {frame}, where the object is to be placed",
                          reason="infeasible_placement", command_index=index) from None


def resolve(draft: Draft, placement: Placement, asset: Asset, anchor: AnchorPose | None, step: int,
            index: int, behaviour: Behaviour | None = None) -> PlacedPose:
    """Where ``placement`` puts ``asset`` at ``step`` (``EditRefused`` naming why it cannot be placed); a
    ``behaviour`` crossing the street starts it at the road's edge."""
    ctx = draft.ctx
    crossing = behaviour is not None and behaviour.cross_street
    try:
        return resolve_placement(placement, category=asset.category, size=asset.size, anchor=anchor,
                                 ego_pose=ctx.log.ego_poses[step], lanes=ctx.lanes, map_ctx=ctx.map_ctx,
                                 frame=int(draft.states.frame_idx[step]), occupied=draft.states, crossing=crossing)
    except EditRefused as exc:
        raise EditRefused(str(exc), reason=exc.reason, command_index=index) from exc


def _other(draft: Draft, ref: TargetRef | None, index: int, role: str) -> OtherAgent | None:
    """The grounded agent ``ref`` names (a leader, an object to stop behind)."""
    if ref is None:
        return None
    if ref.is_ego:
        row = draft.states.index("ego")
        return OtherAgent.from_states(draft.states, row, "the ego vehicle")
    found = draft.grounder.ground(ref, removed=draft.gone, command_index=index, role=role)
    return OtherAgent.from_states(draft.states, draft.row_of(found.object_ids[0]), draft.describe(found.node_ids[0]))


def making_room(draft: Draft, start: StartState, exclude: tuple[str, ...]) -> tuple[str, ...]:
    """Ids of the agents that will make room for the planned one, so that its plan need not keep clear of them:
    with full refinement (``EditorOptions.refinement``) every agent the predictor drives reacts to the edited
    ones (follows, yields at crossings), except those ahead of it driving the same way, which keep their pace.
    The ego (unless it reacts), static objects, edited and inserted agents and agents standing through the log
    make no room; nor does a pedestrian already on the carriageway (crossing or jaywalking: it gives way only
    from the kerb, and stopping in the lane frees nothing); nor does anyone without refinement (the other agents
    replay their log)."""
    if draft.options.refinement != "full":
        return ()
    states = draft.states
    fixed = set(fixed_rows(states, "full", ego_reacts=draft.options.ego_reacts).tolist())
    k = min(max(int(start.step), 0), states.num_steps - 1)
    forward = np.array([np.cos(start.heading), np.sin(start.heading)])
    on_road = _pedestrians_on_road(draft, k)
    out = []
    for r, oid in enumerate(states.object_ids):
        if r in fixed or oid in exclude or not states.valid[r, k] or r in on_road:
            continue
        if _stands_through_log(states, r):
            continue  # the predictor keeps it there
        ahead = float((states.xy[r, k] - np.asarray(start.xy, np.float64)) @ forward) > 0.0
        same_way = abs(float(wrap_angle(states.heading[r, k] - start.heading))) <= np.deg2rad(SAME_WAY_DEG)
        if not (ahead and same_way):
            out.append(oid)
    return tuple(out)


def _stands_through_log(states: AgentStates, row: int) -> bool:
    """Whether agent ``row`` stays within :data:`LOG_MOVES_M` of where it first is, at every valid step."""
    steps = np.flatnonzero(states.valid[row])
    return float(np.linalg.norm(states.xy[row, steps] - states.xy[row, steps[0]], axis=1).max()) < LOG_MOVES_M


def _pedestrians_on_road(draft: Draft, step: int) -> set[int]:
    """Rows of the pedestrians standing on the carriageway (drivable, not sidewalk) at ``step``."""
    states, map_ctx = draft.states, draft.ctx.map_ctx
    rows = np.flatnonzero(np.array([agent_kind(c) == PEDESTRIAN for c in states.categories]) & states.valid[:, step])
    if not rows.size or not map_ctx.has_drivable:
        return set()
    facts = map_ctx.facts(states.xy[rows, step], states.heading[rows, step])
    return set(rows[facts.on_drivable & ~facts.on_sidewalk].tolist())


def no_room_note(draft: Draft) -> str:
    """Why the traffic does not make room, for refusals (depends on ``EditorOptions.refinement``)."""
    if draft.options.refinement == "full":
        return "the traffic ahead keeps its pace; only agents behind and crossing react"
    return "the other agents replay their log and do not make room"


def _plan(draft: Draft, kind: str, behaviour: Behaviour, start: StartState, size: tuple[float, float, float],  # noqa: PLR0913 -- the private planning step every command kind goes through; its options are the kinds' differences
          log: LogTrajectory | None, index: int, label: str, backfill: bool,
          object_id: str | None, with_traffic: bool = True, lane_change_after_m: float = 0.0,
          pace_mps: float | None = None, sidestep_m: float = 0.0,
          passing: PassingStep | None = None) -> PlannedTrajectory:
    """Plan with the motion controller; a vehicle keeps its gap to every other agent on its route (their
    current trajectories: the log, or what earlier commands made of them; ``with_traffic=False``: to none).
    ``lane_change_after_m`` / ``pace_mps``: a lane change waiting for a gap; ``sidestep_m``: a pedestrian's path
    shifted sideways (+ left) for good to pass someone; ``passing``: a step aside and back."""
    ctx, states = draft.ctx, draft.states
    stop_behind = _other(draft, behaviour.stop.behind if behaviour.stop else None, index, "object to stop behind")
    try:
        if kind == VEHICLE:
            leader = _other(draft, behaviour.follow, index, "agent to follow")
            exclude = tuple(o for o in (object_id, leader.object_id if leader else None) if o is not None)
            exclude += making_room(draft, start, exclude)
            request = VehicleMotionRequest.from_behaviour(
                behaviour, times=states.times, frame_idx=states.frame_idx, start=start, size=size, log=log,
                leader=leader, stop_behind=stop_behind,
                traffic=traffic_from_states(states, exclude) if with_traffic else (),
                backfill=backfill, label=label)
            if lane_change_after_m or pace_mps is not None:  # a lane change waiting for a gap
                request = dataclasses.replace(request, lane_change_after_m=lane_change_after_m,
                                              target_speed_mps=request.target_speed_mps if pace_mps is None
                                              else pace_mps)
            return plan_vehicle(request, ctx.lanes, ctx.map_ctx)
        ped = PedestrianMotionRequest.from_behaviour(
            behaviour, times=states.times, frame_idx=states.frame_idx, start=start, size=size, log=log,
            stop_behind=stop_behind, backfill=backfill, label=label)
        if sidestep_m or passing is not None:  # passing someone in its way
            ped = dataclasses.replace(ped, lateral_offset_m=ped.lateral_offset_m + sidestep_m, passing=passing)
        return plan_pedestrian(ped, ctx.map_ctx)
    except EditRefused as exc:
        raise EditRefused(str(exc), reason=exc.reason, command_index=index) from exc


def describe_behaviour(behaviour: Behaviour | None) -> str:
    """A short phrase for a behaviour ("speed 30 km/h, stop (before crosswalk), delay 2 s")."""
    if behaviour is None or behaviour.is_empty:
        return "default motion"
    parts = []
    if behaviour.speed is not None:
        spec = behaviour.speed
        parts.append({"absolute": f"speed {spec.value:g} {spec.unit}", "factor": f"speed x{spec.value:g}",
                      "delta": f"speed {spec.value:+g} {spec.unit}"}[spec.mode])
    for name, value in behaviour.model_dump(exclude_defaults=True, exclude={"speed"}, mode="json").items():
        words = name.replace("_", " ").replace(" s", "")
        if value is True:
            parts.append(words)
        elif isinstance(value, dict):
            inner = ", ".join(f"{k.replace('_', ' ')} {v}" for k, v in value.items() if v not in (None, False))
            parts.append(f"{words} ({inner})" if inner else words)
        else:
            parts.append(f"{words} {value}" + (" s" if name.endswith("_s") else ""))
    return ", ".join(parts)


def plan_inserted(draft: Draft, behaviour: Behaviour | None, asset: Asset, placed: PlacedPose, step: int,
                  index: int) -> Motion:
    """The motion of an inserted object placed at ``placed``, planned from ``step`` (module docstring)."""
    heading = float(placed.heading)
    xy = np.asarray(placed.xy, np.float64)
    steps = draft.states.num_steps
    if asset.category == "static":
        if behaviour is not None and not behaviour.is_empty:
            raise EditRefused(f"{asset.caption} is a static object: it cannot move ({describe_behaviour(behaviour)})",
                              reason="wrong_category", command_index=index)
        return Motion.standing(xy, heading, steps)
    behaviour = behaviour or Behaviour()
    kind = motion_kind(asset.category, asset.caption)
    if kind == VEHICLE and placed.parked and behaviour.is_empty:
        return Motion.standing(xy, heading, steps, PARKED)
    start = StartState(step, xy, heading, start_speed(draft.states, behaviour, kind, xy, heading, step,
                                                      float(asset.size[0])))
    plan = _plan(draft, kind, behaviour, start, asset.size, None, index, asset.caption, backfill=step > 0,
                 object_id=None)
    motion = Motion.planned(plan, describe_behaviour(behaviour))
    if kind != VEHICLE and behaviour.stop is None and not behaviour.cross_street:
        def replan(b: Behaviour, sidestep_m: float, passing: PassingStep | None) -> PlannedTrajectory:
            return _plan(draft, kind, b, start, asset.size, None, index, asset.caption, backfill=step > 0,
                         object_id=None, sidestep_m=sidestep_m, passing=passing)

        motion = _walk_clear(draft, behaviour, start, np.asarray(asset.size, np.float64), (EGO_ID,), motion, replan)
    return motion


#: Sideways steps (m, + left) a walker tries, in order, to pass a pedestrian in its way: first aside and back
#: (``editing.motion.requests.PassingStep``), then aside for good.
SIDESTEPS_M: tuple[float, ...] = (0.8, -0.8, 1.2, -1.2)
#: Two walkers closer than this (m, between their boxes) are meeting: the step aside spans that stretch.
MEETING_M = 0.5


def _log_overlaps(states: AgentStates, ids: tuple[str, ...], row: int, step: int) -> bool:
    """Whether one of the agents ``ids`` (its log, in ``states``) already overlaps agent ``row`` at ``step``: a
    walker in a group keeps its company."""
    for oid in ids:
        if oid in states.object_ids and oid != EGO_ID:
            r = states.index(oid)
            if states.valid[r, step] and footprints_overlap(
                    states.xy[r, step][None], states.heading[r, step:step + 1], states.size[r, :2],
                    states.xy[row, step][None], states.heading[row, step:step + 1], states.size[row, :2]).any():
                return True
    return False


def _meeting(states: AgentStates, motion: Motion, size: np.ndarray, row: int, step: int) -> PassingStep:
    """The stretch of ``motion`` (box ``size``) around ``step`` where it comes within :data:`MEETING_M` of agent
    ``row``, as a passing step of no offset yet (``PassingStep.from_xy`` / ``until_xy``)."""
    both = motion.valid & states.valid[row]
    wide = np.asarray(size, np.float64)[:2] + 2.0 * MEETING_M
    near = np.zeros(len(both), dtype=bool)
    ks = np.flatnonzero(both)
    near[ks] = footprints_overlap(motion.xy[ks], motion.heading[ks], wide, states.xy[row, ks], states.heading[row, ks],
                                  states.size[row, :2])
    near[step] = True
    first, last = step, step
    while first > 0 and near[first - 1]:
        first -= 1
    while last + 1 < len(near) and near[last + 1]:
        last += 1
    return PassingStep(motion.xy[first].copy(), motion.xy[last].copy(), 0.0)


def _keeps_footing(draft: Draft, walk: Motion, planned: Motion) -> bool:
    """Whether ``walk`` stays on the pavement wherever the ``planned`` walk it steps aside from is on it (a step
    aside does not take a walker into the road)."""
    map_ctx = draft.ctx.map_ctx
    ks = np.flatnonzero(walk.valid & planned.valid)
    if not map_ctx.has_drivable or not ks.size:
        return True
    was = map_ctx.facts(planned.xy[ks], planned.heading[ks]).on_sidewalk
    now = map_ctx.facts(walk.xy[ks], walk.heading[ks]).on_sidewalk
    return bool(np.all(now | ~was))


def _walk_clear(draft: Draft, behaviour: Behaviour, start: StartState, size: np.ndarray, exclude: tuple[str, ...],
                motion: Motion, replan: Callable[[Behaviour, float, PassingStep | None], PlannedTrajectory]) -> Motion:
    """A walker (inserted, or one whose walk an edit changed) walking into someone keeps clear of them, as people
    do on a pavement (the planner has no traffic for pedestrians, and the traffic model keeps edited agents
    fixed): it passes a pedestrian, or a sign or bin, with a step aside and back onto its path
    (:data:`SIDESTEPS_M`, the first that clears everyone and keeps it on the pavement), else with a step aside for
    good (``replan(behaviour, metres for good, passing step)``);
    failing that, it stops behind someone (or something) standing through the log, or, already too close to stop
    walking, stands where it is. ``motion`` when nobody (but ``exclude``) is in its way, or nothing of this
    clears it."""
    states = draft.states
    hit = first_overlap(states, motion, size, exclude)
    if hit is None or _log_overlaps(states, exclude, *hit):
        return motion
    row = hit[0]
    if agent_kind(states.categories[row]) != VEHICLE:  # a person, or a sign or bin on the pavement
        meeting = _meeting(states, motion, size, *hit)
        tries = [(0.0, dataclasses.replace(meeting, offset_m=side)) for side in SIDESTEPS_M]
        for shift, passing in [*tries, *((side, None) for side in SIDESTEPS_M)]:
            side = passing.offset_m if passing is not None else shift
            try:
                walk = Motion.planned(replan(behaviour, shift, passing), "")
            except EditRefused:
                continue
            if first_overlap(states, walk, size, exclude) is None and _keeps_footing(draft, walk, motion):
                back = " and back" if passing is not None else ""
                return dataclasses.replace(walk, description=f"{motion.description}; steps {abs(side):g} m "
                                           f"{'left' if side > 0 else 'right'}{back} to pass {_name(draft, row)}")
    if not _stands_through_log(states, row):
        return motion  # it moves: the traffic model makes it wait, or the validation reports it
    waiting = behaviour.model_copy(update={"stop": StopSpec(behind=TargetRef(object_id=states.object_ids[row]))})
    try:
        plan = replan(waiting, 0.0, None)
    except EditRefused as exc:  # too close to stop behind it walking: it waits where it is
        logger.debug("walker stands: %s", exc)
        return Motion.standing(start.xy, start.heading, states.num_steps,
                               f"standing behind {_name(draft, row)}, who stands in its way")
    return Motion.planned(plan, f"{motion.description}; stops behind {_name(draft, row)} standing in its way")


#: An inserted vehicle asked to drive at a speed holds it when its plan never falls more than this below it
#: (m/s, or this share of it when more) ...
SPEED_HELD_TOL_MPS = 0.5
SPEED_HELD_SHARE = 0.08
#: ... looking this far ahead of its route position for the vehicle that holds it back, m.
BLOCKER_AHEAD_M = 60.0
BLOCKER_LATERAL_M = 2.0


def asked_cruise_speed(behaviour: Behaviour | None, category: str) -> float | None:
    """The speed (m/s) an inserted vehicle is asked to drive at ("travelling at 20 kph"), ``None`` when it is not
    asked one to hold (no speed, a parked 0, or a stop / delay / follow that changes it on purpose)."""
    if behaviour is None or behaviour.speed is None or behaviour.speed.mode != "absolute" or category != VEHICLE:
        return None
    if behaviour.stop is not None or behaviour.delay_s is not None or behaviour.follow is not None or behaviour.reverse:
        return None
    target = behaviour.speed.target_mps(0.0)
    return target if target > 0.0 else None


def speed_shortfall(motion: Motion, target: float, start_step: int) -> tuple[float, int]:
    """``(largest amount the motion falls below target from start_step on, m/s; the step where it first falls
    short by more than the tolerance, -1 when never)``."""
    tol = max(SPEED_HELD_TOL_MPS, SPEED_HELD_SHARE * target)
    v = np.abs(motion.speed[start_step:])
    short = target - v
    over = np.flatnonzero(short > tol)
    return float(short.max(initial=0.0)), (start_step + int(over[0]) if over.size else -1)


def blocker_ahead(states: AgentStates, motion: Motion, step: int, exclude: tuple[str, ...] = ()) -> int | None:
    """Row of the nearest vehicle ahead of ``motion`` on its heading line at ``step`` (within
    :data:`BLOCKER_AHEAD_M` ahead and :data:`BLOCKER_LATERAL_M` aside, heading the same way); ``None``."""
    xy, heading = motion.xy[step], float(motion.heading[step])
    forward = np.array([np.cos(heading), np.sin(heading)])
    rel = states.xy[:, step] - xy[None]
    ahead, lateral = rel @ forward, np.abs(rel @ np.array([-forward[1], forward[0]]))
    same_way = np.abs(wrap_angle(states.heading[:, step] - heading)) <= np.pi / 2
    kinds = np.array([agent_kind(c) is not None for c in states.categories])
    ok = (states.valid[:, step] & kinds & same_way & (ahead > 0.5) & (ahead <= BLOCKER_AHEAD_M)
          & (lateral <= BLOCKER_LATERAL_M) & ~np.isin(np.asarray(states.object_ids), exclude))
    if not ok.any():
        return None
    return int(np.flatnonzero(ok)[int(np.argmin(np.where(ok, ahead, np.inf)[ok]))])


def plan_modified(draft: Draft, row: int, behaviour: Behaviour, placement: Placement | None, index: int,
                  label: str) -> Motion:
    """Agent ``row`` 's new motion from its current trajectory by ``behaviour`` (moved to ``placement`` first when
    given); ``label`` names it in messages."""
    states = draft.states
    kind = motion_kind(states.categories[row], label)
    log = LogTrajectory.from_states(states, row)
    start = StartState.from_log(log, states.times)
    if placement is not None:
        placed = _resolve_for_agent(draft, placement, row, start.step, index, crossing=behaviour.cross_street)
        start = StartState(start.step, np.asarray(placed.xy, np.float64), float(placed.heading), start.speed)
    size3 = (float(states.size[row, 0]), float(states.size[row, 1]), float(states.size[row, 2]))
    plan = _plan(draft, kind, behaviour, start, size3, log, index, label, backfill=False,
                 object_id=states.object_ids[row])
    if kind == VEHICLE and behaviour.lane_change is not None:
        def delayed(after_m: float, pace: float | None) -> PlannedTrajectory:
            return _plan(draft, kind, behaviour, start, size3, log, index, label, backfill=False,
                         object_id=states.object_ids[row], lane_change_after_m=after_m, pace_mps=pace)

        plan = _into_a_gap(draft, plan, delayed, row, start, may_slow=behaviour.speed is None)
    if kind == VEHICLE:
        _check_speed_reached(draft, plan, behaviour, start, size3, log, index, label, states.object_ids[row])
    motion = Motion.planned(plan, describe_behaviour(behaviour))
    if kind != VEHICLE and behaviour.stop is None and not behaviour.cross_street:
        def replan(b: Behaviour, sidestep_m: float, passing: PassingStep | None) -> PlannedTrajectory:
            return _plan(draft, kind, b, start, size3, log, index, label, backfill=False,
                         object_id=states.object_ids[row], sidestep_m=sidestep_m, passing=passing)

        motion = _walk_clear(draft, behaviour, start, states.size[row], (EGO_ID, states.object_ids[row]), motion,
                             replan)
    if behaviour.delay_s is not None or behaviour.start_time_s is not None:
        def free_plan() -> Motion:
            return Motion.planned(_plan(draft, kind, behaviour, start, size3, log, index, label, backfill=False,
                                        object_id=states.object_ids[row], with_traffic=False), "")

        late = (f"set off {behaviour.delay_s:g} s later" if behaviour.delay_s is not None
                else f"wait until {behaviour.start_time_s:g} s and then set off")
        _check_delay_kept(draft, row, motion, free_plan, log, late, start.step, index, label)
    return motion


#: A lane change that would cut in too close waits for a gap in steps of this much driving, s ...
MERGE_WAIT_S = 0.5
#: ... as long as it still gets this share of its lateral move done before the log ends ...
MERGE_DONE_SHARE = 0.5
#: ... if need be slowing to these amounts below the speed of the vehicle it would squeeze, to merge behind it, m/s.
MERGE_DROP_MPS: tuple[float, ...] = (2.0, 4.0)


def _into_a_gap(draft: Draft, plan: PlannedTrajectory, delayed: Callable[[float, float | None], PlannedTrajectory],
                row: int, start: StartState, may_slow: bool) -> PlannedTrajectory:
    """A lane change that leaves every vehicle it cuts in front of room to brake behind it
    (``merge_gap.unsafe_merge``): ``plan`` when it does; else the first start of the move along the own lane
    (``delayed(metres, None)``, every :data:`MERGE_WAIT_S` of driving) from which it does and that still gets
    :data:`MERGE_DONE_SHARE` of the move done; else, when no speed was asked (``may_slow``), the same at a pace
    :data:`MERGE_DROP_MPS` below the squeezed vehicle's, letting it pass to merge behind it
    (``delayed(metres, pace)``); else ``plan`` (the validation reports the squeeze)."""
    states = draft.states
    exclude = (states.object_ids[row],)

    def squeezed(p: PlannedTrajectory) -> tuple[int, int] | None:
        return unsafe_merge(states, p.xy, p.heading, p.speed, p.valid, states.size[row], exclude, start.step)

    hit = squeezed(plan)
    if hit is None:
        return plan
    remaining = float(states.times[-1] - states.times[start.step])
    waits = np.arange(MERGE_WAIT_S, remaining - MERGE_DONE_SHARE * VehicleMotionRequest.lane_change_s + 1e-9,
                      MERGE_WAIT_S).tolist()
    own = abs(start.speed)
    paces: list[float | None] = [None]
    if may_slow:
        other = max(float(states.speed[hit[0], start.step]), 0.0)
        paces += [max(other - drop, 0.0) for drop in MERGE_DROP_MPS if other - drop < own]
    for pace in paces:
        for wait in waits:
            later = delayed(wait * max(own if pace is None else pace, 1.0), pace)
            if squeezed(later) is None:
                logger.info("%s: lane change begins %.1f s later%s, in a gap", states.object_ids[row], wait,
                            "" if pace is None else f" at {pace:.1f} m/s, behind {states.object_ids[hit[0]]}")
                return later
    return plan


#: A delayed start is carried out when the agent then covers at least this share of what the same delayed
#: start covers on a free road (no other agents).
DELAY_PROGRESS_SHARE = 0.5
#: An agent whose log moves less than this (m, first to last position) does not move in the log.
LOG_MOVES_M = 1.0


def _path_length(xy: np.ndarray) -> float:
    return float(np.linalg.norm(np.diff(xy, axis=0), axis=1).sum()) if len(xy) > 1 else 0.0


def first_overlap(states: AgentStates, motion: Motion, size: np.ndarray,
                  exclude: tuple[str, ...]) -> tuple[int, int] | None:
    """``(agent row, step)`` of the first agent of ``states`` (but ``exclude``) whose box overlaps ``motion`` 's
    (box ``size``) at a step where both exist, ``None`` when none does."""
    others = [r for r in range(states.num_agents) if states.object_ids[r] not in exclude]
    for k in np.flatnonzero(motion.valid):
        rows = np.array([r for r in others if states.valid[r, k]], dtype=np.int64)
        if not rows.size:
            continue
        hit = footprints_overlap(np.broadcast_to(motion.xy[k], (len(rows), 2)), np.full(len(rows), motion.heading[k]),
                                 np.asarray(size, np.float64)[:2], states.xy[rows, k], states.heading[rows, k],
                                 states.size[rows, :2])
        if hit.any():
            return int(rows[hit][0]), int(k)
    return None


def _check_delay_kept(draft: Draft, row: int, motion: Motion, free_plan: Callable[[], Motion], log: LogTrajectory,
                      late: str, start_step: int, index: int, label: str) -> None:
    """Refuse a delayed start (a delay or a start time; ``late`` says which: "set off 2 s later") that is
    meaningless or cannot be carried out: the agent neither moves in its log nor is set moving by the edit
    (nothing to start later: "cross the street 2 s later" sets a standing pedestrian off, "start 2 s later" alone
    does not), or, held back by the other agents (which replay their log and do not make room),
    it covers under :data:`DELAY_PROGRESS_SHARE` of what the same delayed start covers on a free road
    (``free_plan()``) -- naming the agent in its way."""
    states = draft.states
    valid = np.flatnonzero(log.valid)
    moved = float(np.linalg.norm(log.xy[valid[-1]] - log.xy[valid[0]])) if valid.size else 0.0
    free = free_plan()
    free_steps = np.flatnonzero(free.valid)
    expected = _path_length(free.xy[free_steps[free_steps >= start_step]])
    if moved < LOG_MOVES_M and expected <= LOG_MOVES_M:
        raise EditRefused(f"{label} does not move in the log (it stays within {moved:.1f} m): a delayed start needs "
                          "an agent that sets off; give it a speed to drive off instead", reason="infeasible_motion",
                          command_index=index)
    times = states.times
    steps = np.flatnonzero(motion.valid)
    steps = steps[steps >= start_step]
    got = _path_length(motion.xy[steps])
    if expected <= LOG_MOVES_M or got >= DELAY_PROGRESS_SHARE * expected:
        return
    hit = first_overlap(states, motion, states.size[row], (states.object_ids[row],))
    if hit is not None:
        other, k = hit
        why = f"{_name(draft, other)} runs into it at {times[k]:.1f} s"
    else:
        ahead = blocker_ahead(states, motion, int(steps[-1]), (states.object_ids[row],))
        why = (f"{_name(draft, ahead)} ahead of it holds it back" if ahead is not None
               else "the traffic around it holds it back")
    raise EditRefused(f"{label} cannot {late}: {why}; it would move {got:.1f} m where a free road "
                      f"lets it cover {expected:.1f} m ({no_room_note(draft)})",
                      reason="infeasible_motion", command_index=index)


def _name(draft: Draft, row: int) -> str:
    """How messages name agent ``row`` of the draft ("veh_01 (node 11): a white sedan", "the ego vehicle")."""
    states = draft.states
    oid = states.object_ids[row]
    if oid == EGO_ID:
        return "the ego vehicle"
    try:
        return draft.describe(int(states.node_ids[row]))
    except KeyError:
        return f"{states.categories[row]} {oid!r}"


#: A faster speed counts as reached when the plan ends at this share of the asked speed or more.
SPEED_REACHED_SHARE = 0.8
#: The speed a plan "ends at" is its mean over this last stretch of time, s (a plan still accelerating through
#: the asked speed at its last step does not drive at it).
END_WINDOW_S = 0.5


def end_speed(speed: np.ndarray, times: np.ndarray) -> float:
    """Mean absolute speed over the last :data:`END_WINDOW_S` of ``times``."""
    last = times >= times[-1] - END_WINDOW_S - 1e-9
    return float(np.mean(np.abs(speed[last])))


def _check_speed_reached(draft: Draft, plan: PlannedTrajectory, behaviour: Behaviour, start: StartState,
                         size: tuple[float, float, float], log: LogTrajectory | None, index: int, label: str,
                         object_id: str) -> None:
    """Refuse a speed-up (a faster speed, ``accelerate``) that the traffic ahead takes away, never a silent
    no-op or a slow-down: when the plan keeping its gap ends (:func:`end_speed`) short of the asked speed
    (``editing.motion.requests.target_speed``; within the tolerance of an inserted car's for an asked speed,
    :data:`SPEED_REACHED_SHARE` of it for a plain "speed up") but the same plan on a free road ends there, or
    clearly faster (a physical limit such as a curve is no refusal; traffic taking the speed is)."""
    target = target_speed(behaviour, start.speed, "vehicle")
    if target is None or behaviour.reverse or target <= abs(start.speed) + 0.5:
        return
    # an asked speed ("at 40 km/h", "50 % faster") is met within the tolerance of an inserted car's; a plain
    # "speed up" (whose target is a convention) needs a clear gain: SPEED_REACHED_SHARE of it
    need = (target - max(SPEED_HELD_TOL_MPS, SPEED_HELD_SHARE * target) if behaviour.speed is not None
            else SPEED_REACHED_SHARE * target)
    def ends_at(p: PlannedTrajectory) -> float:  # a plain speed-up: its last step, as it always was
        return end_speed(p.speed, p.times) if behaviour.speed is not None else abs(float(p.speed[-1]))

    reached = ends_at(plan)
    if reached >= need:
        return
    free = _plan(draft, VEHICLE, behaviour, start, size, log, index, label, backfill=False, object_id=object_id,
                 with_traffic=False)
    free_end = ends_at(free)
    taken = behaviour.speed is not None and free_end - reached > max(SPEED_HELD_TOL_MPS, SPEED_HELD_SHARE * target)
    if free_end >= need or taken:
        top = float(np.max(np.abs(plan.speed[start.step:]), initial=0.0))
        behind = np.flatnonzero(np.abs(free.speed) - np.abs(plan.speed) > SPEED_HELD_TOL_MPS)
        row = (blocker_ahead(draft.states, Motion.planned(plan, ""), int(behind[0]), (object_id,))
               if behind.size else None)
        who = f" ({_name(draft, row)})" if row is not None else ""
        raise EditRefused(f"{label} cannot reach {target:.1f} m/s ({describe_behaviour(behaviour)}): keeping its gap "
                          f"to the traffic ahead{who} it gets to {top:.1f} m/s at most and ends at {reached:.1f} m/s "
                          f"({no_room_note(draft)})",
                          reason="infeasible_motion", command_index=index)


def _resolve_for_agent(draft: Draft, placement: Placement, row: int, step: int, index: int,
                       crossing: bool = False) -> PlacedPose:
    """Where ``placement`` moves agent ``row`` at ``step`` (its own box ignored when checking for room; ``crossing``:
    it crosses the street from there)."""
    ctx, states = draft.ctx, draft.states
    anchor = None
    if placement.anchor is not None and not placement.anchor.is_ego:
        found = draft.grounder.ground(placement.anchor, removed=draft.gone, command_index=index, role="anchor")
        anchor = anchor_pose(draft, found.object_ids[0], draft.describe(found.node_ids[0]), step, index)
    try:
        return resolve_placement(placement, category=states.categories[row], size=tuple(states.size[row]),
                                 anchor=anchor, ego_pose=ctx.log.ego_poses[step], lanes=ctx.lanes, map_ctx=ctx.map_ctx,
                                 frame=int(states.frame_idx[step]), occupied=states,
                                 ignore=(states.object_ids[row],), crossing=crossing)
    except EditRefused as exc:
        raise EditRefused(str(exc), reason=exc.reason, command_index=index) from exc
