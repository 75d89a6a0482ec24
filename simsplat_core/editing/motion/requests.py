"""What the motion controller is asked for: requests built from a ``commands.Behaviour`` and the agent's start
state or log trajectory, with every field resolved to numbers (m, s, m/s, rad).

* :class:`LogTrajectory` -- an agent's log on the step grid (what ``modify`` starts from);
* :class:`StartState` -- where and how fast the new motion begins (a log step, or a placed pose);
* :class:`OtherAgent` -- another agent the motion refers to (a leader to follow, an object to stop behind);
* :class:`VehicleMotionRequest` / :class:`PedestrianMotionRequest` -- ``from_behaviour`` checks the behaviour
  fits the category (``EditRefused(reason="wrong_category")`` / ``"infeasible_motion"``) and resolves it,
  behaviour by behaviour: the speed asked (:func:`target_speed`: the behaviours' speed rules, declared in their
  modules, in ``registry.SPEED_ORDER``), the fields a behaviour resolves into request fields
  (:data:`RESOLVERS`: following, stops, timing, sideways shifts) and, as they are, the manoeuvre fields the
  request has a field of the same name for (reverse, lane change, turn; crossing, jaywalking).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from simsplat_core.editing.behaviours.declaration import AgentKind, BehaviourDecl
from simsplat_core.editing.behaviours.registry import BEHAVIOURS, PEDESTRIAN_ONLY, SPEED_ORDER, VEHICLE_ONLY
from simsplat_core.editing.commands import Behaviour
from simsplat_core.editing.motion.speed_profile import PEDESTRIAN_LIMITS, VEHICLE_LIMITS, LongitudinalLimits
from simsplat_core.editing.result import EditRefused
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.trajectory import agent_kind
from simsplat_core.scenario.vocabulary import PEDESTRIAN, VEHICLE

#: Speed of a standing vehicle asked to drive (turn, change lanes, follow) without a speed, m/s (~30 km/h). The
#: speeds behaviours ask (``ACCELERATE_DELTA_MPS``, ``DECELERATE_FACTOR``, ``REVERSE_MPS``, ``WALK_MPS``,
#: ``RUN_MPS``) are declared with them (``editing.behaviours``).
DEFAULT_CRUISE_MPS = 8.0
#: Gaps kept when stopping, metres (front of the agent to the area / the other's rear).
STOP_GAP_M = {"crosswalk": 1.5, "intersection": 1.0, "stop_line": 1.0, "behind": 2.0}
#: Standstill gap kept to a leader, metres.
FOLLOW_GAP_M = 2.0


@dataclass(frozen=True)
class LogTrajectory:
    """An agent's log on the step grid.

    Attributes:
        xy: ``[T, 2]`` box centres, m; heading: ``[T]`` yaw, rad; speed: ``[T]`` signed speed, m/s;
        valid: ``[T]`` bool.
    """

    xy: np.ndarray
    heading: np.ndarray
    speed: np.ndarray
    valid: np.ndarray

    @classmethod
    def from_states(cls, states: AgentStates, row: int) -> LogTrajectory:
        return cls(states.xy[row].copy(), states.heading[row].copy(), states.speed[row].copy(),
                   states.valid[row].copy())

    def speed_at(self, times: np.ndarray, t: float) -> float:
        """Signed log speed at time ``t`` (interpolated over valid steps, held beyond them)."""
        steps = np.flatnonzero(self.valid)
        if not steps.size:
            return 0.0
        return float(np.interp(t, times[steps], self.speed[steps]))


@dataclass(frozen=True)
class StartState:
    """Where the new motion begins.

    Attributes:
        step: index into the step times; the motion is planned from here on (earlier steps keep the log).
        xy: ``[2]`` world position, m; heading: yaw, rad; speed: signed m/s; accel: m/s^2.
    """

    step: int
    xy: np.ndarray
    heading: float
    speed: float = 0.0
    accel: float = 0.0

    @classmethod
    def from_log(cls, log: LogTrajectory, times: np.ndarray, step: int | None = None) -> StartState:
        """The log state at ``step`` (default: the first valid step; a later invalid step moves on to the next
        valid one). Raises ``ValueError`` when the log has no valid step there or after."""
        steps = np.flatnonzero(log.valid)
        later = steps[steps >= (0 if step is None else step)]
        if not later.size:
            raise ValueError(f"the log has no valid step at or after step {step}")
        k = int(later[0])
        prev = k - 1 if k > 0 and log.valid[k - 1] else k
        nxt = k + 1 if k + 1 < len(times) and log.valid[k + 1] else k
        accel = (log.speed[nxt] - log.speed[prev]) / (times[nxt] - times[prev]) if nxt != prev else 0.0
        return cls(k, log.xy[k].copy(), float(log.heading[k]), float(log.speed[k]), float(accel))


@dataclass(frozen=True)
class OtherAgent:
    """Another agent a motion refers to.

    Attributes:
        object_id: its id; label: how messages name it ("the white van").
        xy: ``[T, 2]``; heading: ``[T]``; valid: ``[T]``; size: ``(length, width, height)`` m.
    """

    object_id: str
    label: str
    xy: np.ndarray
    heading: np.ndarray
    valid: np.ndarray
    size: tuple[float, float, float]

    @classmethod
    def from_states(cls, states: AgentStates, row: int, label: str = "") -> OtherAgent:
        oid = states.object_ids[row]
        return cls(oid, label or f"{states.categories[row]} {oid!r}", states.xy[row].copy(),
                   states.heading[row].copy(), states.valid[row].copy(),
                   tuple(float(x) for x in states.size[row]))  # type: ignore[arg-type]


@dataclass(frozen=True)
class StopRequest:
    """A stop. At most one of ``at_time_s`` / ``before`` / ``behind`` / ``distance_m``; none: as soon as
    comfortably possible (``hard``: with hard braking).

    Attributes:
        at_time_s: be at rest by this time (s on the log's axis).
        before: stop before the next ``"crosswalk"`` / ``"intersection"`` / ``"stop_line"`` on the path.
        behind: stop behind this agent (its position at the start step).
        distance_m: the agent's centre comes to rest this far along its path from the start, m.
        gap_m: front of the agent to the area / the other's rear, m (default :data:`STOP_GAP_M`).
        hard: brake hard.
    """

    at_time_s: float | None = None
    before: str | None = None
    behind: OtherAgent | None = None
    distance_m: float | None = None
    gap_m: float | None = None
    hard: bool = False


@dataclass(frozen=True)
class _Common:
    """Fields shared by both requests.

    Attributes:
        times: ``[T]`` step times, s; frame_idx: ``[T]`` their log frames.
        start: where the new motion begins.
        size: the agent's box ``(length, width, height)``, m.
        log: the agent's log (``modify``), ``None`` for an inserted agent.
        target_speed_mps: wanted speed, m/s (``None``: the log's speed, or the start speed).
        stop: a stop to make.
        hold_until_s: stands still at the start until this time (delayed start), s.
        log_shift_s: after the hold, the log's speed is replayed this much later, s.
        lateral_offset_m: shift sideways (+ = left), m.
        backfill: steps before ``start.step`` are filled by running the start state backwards at constant
            speed along the route (an inserted agent placed at a later frame exists from the first step);
            otherwise they keep the log (or are invalid without one).
        label: how messages name the agent.
        limits: longitudinal limits of the plan (vehicle or pedestrian defaults).
    """

    times: np.ndarray
    frame_idx: np.ndarray
    start: StartState
    size: tuple[float, float, float]
    log: LogTrajectory | None = None
    target_speed_mps: float | None = None
    stop: StopRequest | None = None
    hold_until_s: float | None = None
    log_shift_s: float = 0.0
    lateral_offset_m: float = 0.0
    backfill: bool = False
    label: str = "the target"
    limits: LongitudinalLimits = VEHICLE_LIMITS


@dataclass(frozen=True)
class VehicleMotionRequest(_Common):
    """A vehicle's new motion (fields of ``_Common`` plus):

    Attributes:
        reverse: back up (along its own past path, else straight back) at ``target_speed_mps`` (by default
            ``reverse.REVERSE_MPS``).
        lane_change: ``"left"`` / ``"right"``; lane_change_s: its duration at the cruise speed, s;
            lane_change_after_m: how far it drives on in its own lane before the move begins (waiting for a gap
            in the target lane), m.
        turn: ``"left"`` / ``"right"`` / ``"straight"`` at the next intersection.
        leader: agent to follow; follow_gap_m: standstill gap to it (and to traffic), m; headway_s: time gap, s.
        traffic: other agents (replaying their logs) to keep a gap to whenever they are on the route ahead,
            so the planned car brakes for what is in its way instead of driving through it.
    """

    reverse: bool = False
    lane_change: str | None = None
    lane_change_s: float = 3.5
    lane_change_after_m: float = 0.0
    turn: str | None = None
    leader: OtherAgent | None = None
    traffic: tuple[OtherAgent, ...] = ()
    follow_gap_m: float = FOLLOW_GAP_M
    headway_s: float = 1.5

    @classmethod
    def from_behaviour(cls, behaviour: Behaviour, *, times: np.ndarray, frame_idx: np.ndarray, start: StartState,  # noqa: PLR0913 -- keyword-only: the grounded agents and times of one command
                       size: tuple[float, float, float], log: LogTrajectory | None = None,
                       leader: OtherAgent | None = None, stop_behind: OtherAgent | None = None,
                       traffic: tuple[OtherAgent, ...] = (), backfill: bool = False,
                       label: str = "the target") -> VehicleMotionRequest:
        """Resolve ``behaviour`` for a vehicle; ``leader`` / ``stop_behind`` are the grounded agents of
        ``behaviour.follow`` / ``behaviour.stop.behind``; ``traffic`` the agents to keep a gap to
        (:func:`traffic_from_states`).

        Raises:
            EditRefused: pedestrian-only fields (``wrong_category``); ``follow`` / ``stop.behind`` without
                the grounded agent (``invalid_command``).
        """
        _refuse_fields(behaviour, PEDESTRIAN_ONLY, "vehicles", label)
        resolved = _resolved(behaviour, "vehicle", cls, _Grounded(times, start, label, leader, stop_behind))
        return cls(times=np.asarray(times, np.float64), frame_idx=np.asarray(frame_idx, np.int64), start=start,
                   size=size, log=log, target_speed_mps=target_speed(behaviour, start.speed, "vehicle"),
                   backfill=backfill, label=label, traffic=traffic, **resolved)


@dataclass(frozen=True)
class PassingStep:
    """A walker's step aside to pass someone: ``offset_m`` sideways (+ left) from ``PASS_LEAD_M`` before the
    point of its path nearest ``from_xy`` [2] until ``PASS_TRAIL_M`` after the one nearest ``until_xy`` [2]
    (where its unshifted walk would meet the other person), then back onto its path."""

    from_xy: np.ndarray
    until_xy: np.ndarray
    offset_m: float


#: A passing step starts this far before the meeting and ends this far after it, m, easing over ``PASS_RAMP_M``.
PASS_LEAD_M = 1.5
PASS_TRAIL_M = 1.0
PASS_RAMP_M = 1.5


@dataclass(frozen=True)
class PedestrianMotionRequest(_Common):
    """A pedestrian's new motion (fields of ``_Common`` plus):

    Attributes:
        cross_street: cross the road at the nearest crosswalk; jaywalk: straight across, away from crosswalks.
        passing: a step aside to pass someone, back on the path afterwards (``None``: none).
    """

    cross_street: bool = False
    jaywalk: bool = False
    passing: PassingStep | None = None

    @classmethod
    def from_behaviour(cls, behaviour: Behaviour, *, times: np.ndarray, frame_idx: np.ndarray, start: StartState,
                       size: tuple[float, float, float], log: LogTrajectory | None = None,
                       stop_behind: OtherAgent | None = None, backfill: bool = False,
                       label: str = "the pedestrian") -> PedestrianMotionRequest:
        """Resolve ``behaviour`` for a pedestrian (gaits ``gait.WALK_MPS`` / ``gait.RUN_MPS``; a standing
        person asked to cross or to change speed walks).

        Raises:
            EditRefused: ``reverse`` (``infeasible_motion``); lane changes, turns, following
                (``wrong_category``).
        """
        if behaviour.reverse:
            raise EditRefused(f"{label} is a pedestrian: pedestrians do not reverse (they can walk, run, stop, "
                              "cross the street or jaywalk)", reason="infeasible_motion")
        _refuse_fields(behaviour, VEHICLE_ONLY, "pedestrians", label)
        resolved = _resolved(behaviour, "pedestrian", cls, _Grounded(times, start, label, None, stop_behind))
        return cls(times=np.asarray(times, np.float64), frame_idx=np.asarray(frame_idx, np.int64), start=start,
                   size=size, log=log, target_speed_mps=target_speed(behaviour, start.speed, "pedestrian"),
                   backfill=backfill, label=label, limits=PEDESTRIAN_LIMITS, **resolved)


def _may_do(decl: BehaviourDecl, kind: AgentKind) -> bool:
    """Whether an agent of ``kind`` may do the behaviour (it is not restricted to the other kind)."""
    return decl.agent is None or decl.agent == kind


def target_speed(behaviour: Behaviour, current: float, kind: AgentKind) -> float | None:
    """The speed an agent of ``kind`` moving at ``current`` m/s (signed) is asked for, m/s: the first speed given by
    the speed rules of ``registry.SPEED_ORDER`` (``BehaviourDecl.speed_rule``; a said speed, a gait, speeding up or
    slowing down, reversing, a standing person crossing) of the behaviours ``kind`` may do; ``None``: the behaviour
    keeps the log's (or the start) speed."""
    pace = abs(current)
    for decl in SPEED_ORDER:
        if decl.speed_rule is not None and _may_do(decl, kind):
            speed = decl.speed_rule(behaviour, pace, kind)
            if speed is not None:
                return speed
    return None


def traffic_from_states(states: AgentStates, exclude: tuple[str, ...] | list[str] = ()) -> tuple[OtherAgent, ...]:
    """Every moving-kind agent of ``states`` (vehicles, cyclists, pedestrians and the ego; not static objects)
    except ``exclude``, as traffic to keep a gap to."""
    return tuple(OtherAgent.from_states(states, r) for r in range(states.num_agents)
                 if states.object_ids[r] not in exclude and agent_kind(states.categories[r]) is not None)


def motion_kind(category: str, label: str = "the target") -> str:
    """``"vehicle"`` or ``"pedestrian"``: which planner moves an agent of ``category``.

    Raises:
        EditRefused(reason="wrong_category"): static objects (cones, signs, ...) do not move.
    """
    kind = agent_kind(category)
    if kind is None:
        raise EditRefused(f"{label} is a static object ({category}): static objects cannot move; they can be "
                          "inserted, removed or replaced", reason="wrong_category")
    return VEHICLE if kind == VEHICLE else PEDESTRIAN


def _refuse_fields(behaviour: Behaviour, fields: tuple[str, ...], who: str, label: str) -> None:
    given = [f for f in fields if getattr(behaviour, f) not in (None, False)]
    if given:
        other = "vehicles" if who == "pedestrians" else "pedestrians"
        ok = ("speed, accelerate/decelerate, stop, start time/delay, lateral offset" + (
            ", lane change, turn, reverse, follow" if who == "vehicles" else ", walk/run, cross the street, jaywalk"))
        raise EditRefused(f"{label}: {', '.join(given).replace('_', ' ')} is for {other} only; {who} support "
                          f"{ok}", reason="wrong_category")


@dataclass(frozen=True)
class _Grounded:
    """What a command's behaviour is resolved against: the step times ``[T]`` (s), where the motion begins, how
    messages name the agent, and the grounded agents of ``follow`` / ``stop.behind`` (``None``: not grounded)."""

    times: np.ndarray
    start: StartState
    label: str
    leader: OtherAgent | None
    stop_behind: OtherAgent | None


#: Resolves a behaviour's fields into request fields (``{request field: value}``).
Resolver = Callable[[Behaviour, _Grounded], dict[str, Any]]


def _follow_fields(behaviour: Behaviour, g: _Grounded) -> dict[str, Any]:
    """The leader (the grounded agent of ``follow``)."""
    if behaviour.follow is not None and g.leader is None:
        raise EditRefused("follow: the agent to follow was not grounded", reason="invalid_command")
    return {"leader": g.leader}


def _stop_fields(behaviour: Behaviour, g: _Grounded) -> dict[str, Any]:
    """The stop (``StopSpec`` with the grounded agent to stop behind); braking hard is a hard stop."""
    if behaviour.stop is None and behaviour.longitudinal != "brake_hard":
        return {"stop": None}
    spec = behaviour.stop
    if spec is not None and spec.behind is not None and g.stop_behind is None:
        raise EditRefused("stop behind: the object to stop behind was not grounded", reason="invalid_command")
    return {"stop": StopRequest(at_time_s=spec.at_time_s if spec else None, before=spec.before if spec else None,
                                behind=g.stop_behind if spec and spec.behind is not None else None,
                                gap_m=spec.gap_m if spec else None, hard=behaviour.longitudinal == "brake_hard")}


def _timing_fields(behaviour: Behaviour, g: _Grounded) -> dict[str, Any]:
    """A delayed start: standing until the delay is over (or the start time), the log replayed that much later."""
    t_start = float(g.times[g.start.step])
    hold, shift = None, 0.0
    if behaviour.delay_s is not None:
        hold, shift = t_start + behaviour.delay_s, behaviour.delay_s
    if behaviour.start_time_s is not None:
        if behaviour.start_time_s < t_start:
            raise EditRefused(f"{g.label} cannot start at {behaviour.start_time_s:g} s: the edit begins at "
                              f"{t_start:g} s", reason="infeasible_motion")
        hold, shift = behaviour.start_time_s, behaviour.start_time_s - t_start
    return {"hold_until_s": hold, "log_shift_s": shift}


def _offset_fields(behaviour: Behaviour, g: _Grounded) -> dict[str, Any]:
    """The sideways shift, m (none: 0)."""
    return {"lateral_offset_m": behaviour.lateral_offset_m or 0.0}


#: The behaviours whose fields are resolved into other request fields, in the order they are resolved (the first
#: refusal wins): behaviour name -> its resolver. The fields of the other behaviours reach the request as they are,
#: where it has a field of the same name (:func:`_resolved`); speeds come from the speed rules (:func:`target_speed`).
RESOLVERS: tuple[tuple[str, Resolver], ...] = (
    ("follow", _follow_fields), ("stop", _stop_fields), ("timing", _timing_fields), ("lateral_offset", _offset_fields),
)
_RESOLVED = {name for name, _ in RESOLVERS}
_DECLARED: dict[str, BehaviourDecl] = {d.name: d for d in BEHAVIOURS}


def copied_fields(kind: AgentKind, request: type[_Common]) -> tuple[str, ...]:
    """The ``Behaviour`` fields that reach a ``request`` of an agent of ``kind`` as they are: the fields of the
    behaviours it may do, not resolved by :data:`RESOLVERS`, that the request has a field of the same name for."""
    names = {f.name for f in dataclasses.fields(request)}
    return tuple(f for d in BEHAVIOURS if _may_do(d, kind) and d.name not in _RESOLVED for f in d.fields
                 if f in names)


def _resolved(behaviour: Behaviour, kind: AgentKind, request: type[_Common], g: _Grounded) -> dict[str, Any]:
    """The request fields of ``behaviour`` for an agent of ``kind``: the :data:`RESOLVERS` of the behaviours it may
    do, then the :func:`copied_fields`."""
    out: dict[str, Any] = {}
    for name, resolve in RESOLVERS:
        if _may_do(_DECLARED[name], kind):
            out.update(resolve(behaviour, g))
    out.update({f: getattr(behaviour, f) for f in copied_fields(kind, request)})
    return out
