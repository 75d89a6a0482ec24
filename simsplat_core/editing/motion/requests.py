"""What the motion controller is asked for: requests built from a ``commands.Behaviour`` and the agent's start
state or log trajectory, with every field resolved to numbers (m, s, m/s, rad).

* :class:`LogTrajectory` -- an agent's log on the step grid (what ``modify`` starts from);
* :class:`StartState` -- where and how fast the new motion begins (a log step, or a placed pose);
* :class:`OtherAgent` -- another agent the motion refers to (a leader to follow, an object to stop behind);
* :class:`VehicleMotionRequest` / :class:`PedestrianMotionRequest` -- ``from_behaviour`` checks the behaviour
  fits the category (``EditRefused(reason="wrong_category")`` / ``"infeasible_motion"``) and resolves speeds
  (``SpeedSpec.target_mps`` against the current speed, ``accelerate`` / ``decelerate`` / gaits), stops and
  delays.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simsplat_core.editing.behaviours.registry import PEDESTRIAN_ONLY, VEHICLE_ONLY
from simsplat_core.editing.commands import Behaviour
from simsplat_core.editing.motion.speed_profile import PEDESTRIAN_LIMITS, VEHICLE_LIMITS, LongitudinalLimits
from simsplat_core.editing.result import EditRefused
from simsplat_core.scenario.agents import AgentStates
from simsplat_core.scenario.trajectory import agent_kind
from simsplat_core.scenario.vocabulary import PEDESTRIAN, VEHICLE

#: Speed of a standing vehicle asked to drive (turn, change lanes, follow) without a speed, m/s (~30 km/h).
DEFAULT_CRUISE_MPS = 8.0
#: ``accelerate`` without a speed: this much faster, m/s; ``decelerate``: this fraction of the current speed.
ACCELERATE_DELTA_MPS = 5.0
DECELERATE_FACTOR = 0.5
#: Reversing speed, m/s.
REVERSE_MPS = 2.0
#: Pedestrian gaits, m/s.
WALK_MPS = 1.4
RUN_MPS = 3.0
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
        reverse: back up (along its own past path, else straight back) at ``target_speed_mps`` or
            :data:`REVERSE_MPS`.
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
        if behaviour.follow is not None and leader is None:
            raise EditRefused("follow: the agent to follow was not grounded", reason="invalid_command")
        shared = _common_fields(behaviour, times, start, log, stop_behind, label)
        target = vehicle_target_speed(behaviour, start.speed)
        return cls(times=np.asarray(times, np.float64), frame_idx=np.asarray(frame_idx, np.int64), start=start,
                   size=size, log=log, target_speed_mps=target, backfill=backfill, label=label,
                   stop=shared.stop, hold_until_s=shared.hold_until_s, log_shift_s=shared.log_shift_s,
                   lateral_offset_m=shared.lateral_offset_m, reverse=behaviour.reverse,
                   lane_change=behaviour.lane_change, turn=behaviour.turn, leader=leader, traffic=traffic)


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
        """Resolve ``behaviour`` for a pedestrian (gaits :data:`WALK_MPS` / :data:`RUN_MPS`; a standing
        person asked to cross or to change speed walks).

        Raises:
            EditRefused: ``reverse`` (``infeasible_motion``); lane changes, turns, following
                (``wrong_category``).
        """
        if behaviour.reverse:
            raise EditRefused(f"{label} is a pedestrian: pedestrians do not reverse (they can walk, run, stop, "
                              "cross the street or jaywalk)", reason="infeasible_motion")
        _refuse_fields(behaviour, VEHICLE_ONLY, "pedestrians", label)
        shared = _common_fields(behaviour, times, start, log, stop_behind, label)
        target = shared.target_speed_mps
        current = abs(start.speed)
        base = current if current > 0.3 else WALK_MPS
        if behaviour.speed is not None:
            target = behaviour.speed.target_mps(base)
        elif behaviour.gait is not None:
            target = RUN_MPS if behaviour.gait == "run" else WALK_MPS
        elif behaviour.longitudinal == "accelerate":
            target = max(base * 1.5, RUN_MPS if base > WALK_MPS else WALK_MPS * 1.5)
        elif behaviour.longitudinal == "decelerate":
            target = base * DECELERATE_FACTOR
        elif behaviour.cross_street and current < 0.3:
            target = WALK_MPS
        return cls(times=np.asarray(times, np.float64), frame_idx=np.asarray(frame_idx, np.int64), start=start,
                   size=size, log=log, target_speed_mps=target, backfill=backfill, label=label,
                   stop=shared.stop, hold_until_s=shared.hold_until_s, log_shift_s=shared.log_shift_s,
                   lateral_offset_m=shared.lateral_offset_m, limits=PEDESTRIAN_LIMITS,
                   cross_street=behaviour.cross_street, jaywalk=behaviour.jaywalk)


def vehicle_target_speed(behaviour: Behaviour, current: float) -> float | None:
    """The speed a vehicle driving at ``current`` m/s is asked for, m/s: the given speed (against the current
    one), ``accelerate`` :data:`ACCELERATE_DELTA_MPS` faster, ``decelerate`` :data:`DECELERATE_FACTOR` of it,
    reversing :data:`REVERSE_MPS`; ``None``: the behaviour keeps the log's (or the start) speed."""
    current = abs(current)
    if behaviour.speed is not None:
        return behaviour.speed.target_mps(current)
    if behaviour.longitudinal == "accelerate":
        return current + ACCELERATE_DELTA_MPS
    if behaviour.longitudinal == "decelerate":
        return current * DECELERATE_FACTOR
    return REVERSE_MPS if behaviour.reverse else None


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
class _Shared:
    """What both requests resolve alike (see ``_Common``)."""

    target_speed_mps: float | None
    stop: StopRequest | None
    hold_until_s: float | None
    log_shift_s: float
    lateral_offset_m: float


def _common_fields(behaviour: Behaviour, times: np.ndarray, start: StartState, log: LogTrajectory | None,
                   stop_behind: OtherAgent | None, label: str) -> _Shared:
    """Speed target, stop, hold and offset shared by both requests."""
    t_start = float(times[start.step])
    target = behaviour.speed.target_mps(abs(start.speed)) if behaviour.speed is not None else None
    stop = None
    if behaviour.stop is not None or behaviour.longitudinal == "brake_hard":
        spec = behaviour.stop
        if spec is not None and spec.behind is not None and stop_behind is None:
            raise EditRefused("stop behind: the object to stop behind was not grounded", reason="invalid_command")
        stop = StopRequest(at_time_s=spec.at_time_s if spec else None, before=spec.before if spec else None,
                           behind=stop_behind if spec and spec.behind is not None else None,
                           gap_m=spec.gap_m if spec else None, hard=behaviour.longitudinal == "brake_hard")
    hold, shift = None, 0.0
    if behaviour.delay_s is not None:
        hold, shift = t_start + behaviour.delay_s, behaviour.delay_s
    if behaviour.start_time_s is not None:
        if behaviour.start_time_s < t_start:
            raise EditRefused(f"{label} cannot start at {behaviour.start_time_s:g} s: the edit begins at "
                              f"{t_start:g} s", reason="infeasible_motion")
        hold, shift = behaviour.start_time_s, behaviour.start_time_s - t_start
    return _Shared(target, stop, hold, shift, behaviour.lateral_offset_m or 0.0)
