"""The rule-based judge: explicit checks of an executed edit, and concrete parameter changes where one fails.

    judgement = judge_edit(request)        # request: JudgeRequest, best from judge_input.judge_request_from_edit

Checks, each a failure class (:data:`PENALTIES`):

* ``grounding`` -- every command acted on something: a target of a modify / replace / remove is among the
  trajectories (removed ones absent), an insert added an agent;
* ``change`` -- what each command asks shows in the trajectories (:data:`CHANGE_CHECKS`, one check per behaviour),
  against the log's (``request.before``) or, for an inserted agent, against its own start: a speed ask moves the
  mean speed at least half-way to the asked speed, a stop ends below :attr:`JudgeConfig.stop_mps`, braking lowers
  the end (or least) speed, a lane change shifts the agent sideways by :attr:`JudgeConfig.lateral_m` to the asked
  side, a turn changes its heading by :attr:`JudgeConfig.turn_deg` the asked way, reversing moves it backwards, a
  later start keeps it still until then, crossing moves a pedestrian off its log path, running raises its speed;
  anything else moves the target off its log path by :attr:`JudgeConfig.changed_m`; a removed target is gone; when
  the request carries the auto-labeller's motion classes (``request.motion_labels``, from ``judge_input``),
  reversing, lane changes, turns, going straight and crossing are checked on them with the behaviours' own label
  checks (``BehaviourDecl.label_check``), as the editing benchmark does, instead;
* ``collision``, ``offroad``, ``kinematic`` -- the validation's failures (``request.failures``);
* ``render`` -- no render is blank (constant) or mostly holes (near-black pixels);
* ``visibility`` -- each present target covers at least :attr:`JudgeConfig.min_visible_pixels` pixels of the
  renders (when ``request.visible_pixels`` is given).

The prompt is followed when no ``grounding``, ``change``, ``render`` or ``visibility`` check fails;
plausibility is 4 less the penalties of the failed classes (at least 1). Failed checks suggest parameter changes:
a collision -- start 2 s later, a lower speed, the inserted object further away; off-road -- an offset back
onto the road or another anchor; not visible -- a larger asset or a closer offset; a change too small -- a larger
speed change (or an earlier start for manoeuvres that do not complete).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from simsplat_core.editing.behaviours.registry import LABEL_CHECKED
from simsplat_core.editing.commands import Behaviour, EditCommand
from simsplat_core.mining.vlm_protocol import (
    PLAUSIBILITY_MAX,
    PLAUSIBILITY_MIN,
    AgentTrajectory,
    Judgement,
    JudgeRequest,
    ParameterChange,
    ValidationFailure,
)

logger = logging.getLogger(__name__)

#: Plausibility lost per failed check class.
PENALTIES: dict[str, int] = {"grounding": 1, "change": 1, "collision": 2, "offroad": 2, "kinematic": 1,
                             "render": 2, "visibility": 1}
#: Check classes whose failure means the prompt is not followed.
FOLLOW_CLASSES: frozenset[str] = frozenset({"grounding", "change", "render", "visibility"})


@dataclass(frozen=True)
class JudgeConfig:
    """Thresholds of the checks (metres, seconds, m/s, degrees, pixels)."""

    stop_mps: float = 0.5
    changed_m: float = 0.3
    lateral_m: float = 1.5
    turn_deg: float = 40.0
    moved_m: float = 1.0
    still_m: float = 0.5
    cross_m: float = 2.0
    speed_share: float = 0.5
    brake_mps: float = 1.0
    tail_s: float = 0.3
    min_visible_pixels: int = 30
    blank_std: float = 2.0 / 255.0
    dark_level: float = 0.02
    hole_share: float = 0.6


@dataclass(frozen=True)
class Finding:
    """One failed check: its class (:data:`PENALTIES` key), why, and what to change."""

    check: str
    reason: str
    suggestions: tuple[ParameterChange, ...] = field(default=())


# ---------------------------------------------------------------------------------------------- motion
@dataclass(frozen=True)
class Motion:
    """How an agent moves over its present steps (m, m/s, degrees; displacement in its start pose's frame)."""

    present: bool
    mean_speed: float = 0.0
    start_speed: float = 0.0
    end_speed: float = 0.0
    min_speed: float = 0.0
    max_speed: float = 0.0
    net_m: float = 0.0
    along_m: float = 0.0
    lateral_m: float = 0.0
    heading_change_deg: float = 0.0
    start_heading: float = math.nan


def _step_speeds(xy: np.ndarray, dt: float) -> np.ndarray:
    return np.linalg.norm(np.diff(xy, axis=0), axis=1) / dt if len(xy) > 1 else np.zeros(0)


def _directions(traj: AgentTrajectory, rows: np.ndarray) -> tuple[float, float]:
    """Start and end heading (radians) over ``rows`` (present steps): the given headings, else the direction of
    the first / last step that moves."""
    if traj.heading is not None and np.isfinite(traj.heading[rows]).all():
        h = np.unwrap(traj.heading[rows])
        return float(h[0]), float(h[-1])
    d = np.diff(traj.xy[rows], axis=0)
    moving = np.flatnonzero(np.linalg.norm(d, axis=1) > 0.02)
    if moving.size == 0:
        return math.nan, math.nan
    h = np.unwrap(np.arctan2(d[moving, 1], d[moving, 0]))
    return float(h[0]), float(h[-1])


def motion_of(traj: AgentTrajectory | None, dt: float, tail_s: float = 0.3) -> Motion:
    """The :class:`Motion` of ``traj`` (``present=False`` when absent or ``None``)."""
    if traj is None:
        return Motion(False)
    rows = np.flatnonzero(traj.present)
    if rows.size == 0:
        return Motion(False)
    xy = traj.xy[rows]
    speeds = _step_speeds(xy, dt)
    tail = max(1, int(round(tail_s / dt)))
    h0, h1 = _directions(traj, rows)
    disp = xy[-1] - xy[0]
    c, s = (math.cos(h0), math.sin(h0)) if math.isfinite(h0) else (math.nan, math.nan)
    duration = (rows[-1] - rows[0]) * dt
    return Motion(
        present=True,
        mean_speed=float(np.linalg.norm(np.diff(xy, axis=0), axis=1).sum() / duration) if duration > 0 else 0.0,
        start_speed=float(speeds[:tail].mean()) if speeds.size else 0.0,
        end_speed=float(speeds[-tail:].mean()) if speeds.size else 0.0,
        min_speed=float(speeds.min()) if speeds.size else 0.0,
        max_speed=float(speeds.max()) if speeds.size else 0.0,
        net_m=float(np.linalg.norm(disp)),
        along_m=float(c * disp[0] + s * disp[1]),
        lateral_m=float(-s * disp[0] + c * disp[1]),
        heading_change_deg=float(np.rad2deg(h1 - h0)) if math.isfinite(h0) else 0.0,
        start_heading=h0)


def deviation_m(after: AgentTrajectory, before: AgentTrajectory) -> float:
    """Largest distance between the two paths at steps where both are present (``inf``: none in common)."""
    n = min(len(after.xy), len(before.xy))
    both = after.present[:n] & before.present[:n]
    if not both.any():
        return math.inf
    return float(np.linalg.norm(after.xy[:n][both] - before.xy[:n][both], axis=1).max())


def _along(traj: AgentTrajectory, heading: float) -> float:
    """Net displacement of ``traj`` along ``heading`` (radians; ``nan`` when not finite)."""
    rows = np.flatnonzero(traj.present)
    if rows.size < 2 or not math.isfinite(heading):
        return math.nan
    disp = traj.xy[rows[-1]] - traj.xy[rows[0]]
    return float(disp[0] * math.cos(heading) + disp[1] * math.sin(heading))


def _moved_by(traj: AgentTrajectory, until_s: float, dt: float) -> float:
    """How far the agent gets from its first present position within ``until_s`` seconds of the start."""
    rows = np.flatnonzero(traj.present)
    rows = rows[rows * dt <= until_s + 1e-9]
    if rows.size < 2:
        return 0.0
    return float(np.linalg.norm(traj.xy[rows] - traj.xy[rows[0]], axis=1).max())


# ---------------------------------------------------------------------------------------------- change checks
def _speed_suggestion(target: float, reason: str) -> ParameterChange:
    return ParameterChange("speed", f"{max(target, 0.0):.1f} m/s", reason)


def _earlier(reason: str) -> ParameterChange:
    return ParameterChange("start_time", "1 s earlier", reason)


@dataclass(frozen=True)
class _Change:
    """One agent's edit as the change checks see it: ``after`` against ``before`` (``None``: an inserted agent,
    judged against its own start), their :class:`Motion` ``a`` and ``b`` (``ref``: ``b`` when ``before`` is
    present, else ``None``), and the auto-labeller's motion class ``label`` of ``after`` (``None``: not given)."""

    behaviour: Behaviour
    after: AgentTrajectory
    before: AgentTrajectory | None
    a: Motion
    b: Motion
    ref: Motion | None
    dt: float
    cfg: JudgeConfig
    label: str | None


#: A change check: what ``_Change.behaviour`` asks that the trajectory does not show, as (why, suggestions) pairs.
ChangeCheck = Callable[[_Change], list[tuple[str, tuple[ParameterChange, ...]]]]


def _speed_change(c: _Change) -> list[tuple[str, tuple[ParameterChange, ...]]]:
    """A said speed: the mean speed moves at least :attr:`JudgeConfig.speed_share` of the way to it (an inserted
    agent at an absolute speed: its mean or top speed near it)."""
    if c.behaviour.speed is None:
        return []
    a, ref = c.a, c.ref
    base = ref.mean_speed if ref is not None else a.start_speed
    target = c.behaviour.speed.target_mps(base)
    asked, got = target - base, a.mean_speed - base
    if ref is None and c.behaviour.speed.mode == "absolute":
        ok = abs(a.mean_speed - target) <= max(1.0, 0.3 * target) or a.max_speed >= 0.9 * target
    else:
        ok = abs(asked) < 0.3 or got / asked >= c.cfg.speed_share
    if ok:
        return []
    return [(f"mean speed {a.mean_speed:.1f} m/s, asked {target:.1f} m/s",
             (_speed_suggestion(target + 0.5 * asked, "the asked speed change does not show: ask for a larger one"),))]


def _longitudinal_change(c: _Change) -> list[tuple[str, tuple[ParameterChange, ...]]]:
    """Speeding up raises the end (or mean) speed; braking or slowing down (without a stop) lowers the end or least
    speed by :attr:`JudgeConfig.brake_mps`."""
    a, ref, cfg, longitudinal = c.a, c.ref, c.cfg, c.behaviour.longitudinal
    out: list[tuple[str, tuple[ParameterChange, ...]]] = []
    if longitudinal == "accelerate":
        base_end = ref.end_speed if ref is not None else a.start_speed
        if a.end_speed < base_end + cfg.brake_mps * 0.5 and (ref is None or a.mean_speed < ref.mean_speed + 0.5):
            out.append((f"does not speed up (ends at {a.end_speed:.1f} m/s)",
                        (_speed_suggestion(base_end + 3.0, "speeding up does not show: ask for a higher speed"),)))
    if longitudinal in ("decelerate", "brake_hard") and c.behaviour.stop is None:
        base_end = ref.end_speed if ref is not None else a.start_speed
        base_min = ref.min_speed if ref is not None else a.start_speed
        if a.end_speed > base_end - cfg.brake_mps and a.min_speed > base_min - cfg.brake_mps:
            out.append((f"does not brake (ends at {a.end_speed:.1f} m/s)",
                        (_speed_suggestion(0.5 * base_end, "braking does not show: ask for a lower speed"),)))
    return out


def _stop_change(c: _Change) -> list[tuple[str, tuple[ParameterChange, ...]]]:
    """A stop ends below :attr:`JudgeConfig.stop_mps`."""
    if c.behaviour.stop is not None and c.a.end_speed > c.cfg.stop_mps:
        return [(f"does not stop (ends at {c.a.end_speed:.1f} m/s)",
                 (_earlier("the stop does not complete in the log"),))]
    return []


#: Behaviour name -> the parameter change to suggest when the auto-labeller's class does not show the behaviour's
#: asked value (``BehaviourDecl.label_check``): one per behaviour of ``registry.LABEL_CHECKED``.
LABEL_SUGGESTIONS: dict[str, Callable[[Any], ParameterChange]] = {
    "reverse": lambda asked: _speed_suggestion(2.0, "reversing does not show: back up at this speed"),
    "lane_change": lambda side: _earlier("the lane change does not complete in the log"),
    "turn": lambda turn: _earlier("it turns before the intersection" if turn == "straight"
                                  else "the turn does not complete in the log"),
    "cross_street": lambda asked: _earlier("the crossing does not show in the log"),
}


def _label_change(c: _Change) -> list[tuple[str, tuple[ParameterChange, ...]]]:
    """The manoeuvres of ``c.behaviour`` (``registry.LABEL_CHECKED``: reversing, a lane change, a turn or going
    straight, crossing the street) that the auto-labeller's motion class does not show, as the editing benchmark
    checks them (``eval.editing.checks``). Without a label, the manoeuvres' own checks below decide."""
    if c.label is None:
        return []
    out: list[tuple[str, tuple[ParameterChange, ...]]] = []
    for decl in LABEL_CHECKED:
        check = decl.label_check
        assert check is not None  # LABEL_CHECKED holds the behaviours with one
        asked = getattr(c.behaviour, check.field)
        if asked and not check.shows(asked, c.label):
            out.append((f"labelled {c.label}, {check.missing(asked)}", (LABEL_SUGGESTIONS[decl.name](asked),)))
    return out


def _reverse_change(c: _Change) -> list[tuple[str, tuple[ParameterChange, ...]]]:
    """Without a label: reversing moves the agent backwards along its start heading by :attr:`JudgeConfig.moved_m`."""
    if not c.behaviour.reverse or c.label is not None:
        return []
    along = _along(c.after, c.a.start_heading if c.after.heading is not None else c.b.start_heading)
    backwards = along < -c.cfg.moved_m if math.isfinite(along) else c.a.net_m >= c.cfg.moved_m
    if backwards:
        return []
    return [(f"does not reverse (moves {along:+.1f} m along its heading)",
             (_speed_suggestion(2.0, "reversing does not show: back up at this speed"),))]


def _lane_change_change(c: _Change) -> list[tuple[str, tuple[ParameterChange, ...]]]:
    """Without a label: a lane change shifts the agent sideways by :attr:`JudgeConfig.lateral_m` to the asked side."""
    side = c.behaviour.lane_change
    if side is None or c.label is not None:
        return []
    sign = 1.0 if side == "left" else -1.0
    shift = c.a.lateral_m - (c.ref.lateral_m if c.ref is not None else 0.0)
    if not (not math.isfinite(shift) or sign * shift < c.cfg.lateral_m):
        return []
    return [(f"does not change lanes to the {side} (shifted {shift:+.1f} m sideways)",
             (_earlier("the lane change does not complete in the log"),))]


def _turn_change(c: _Change) -> list[tuple[str, tuple[ParameterChange, ...]]]:
    """Without a label: a turn changes the heading by :attr:`JudgeConfig.turn_deg` the asked way (going straight is
    not checked)."""
    turn = c.behaviour.turn
    if turn not in ("left", "right") or c.label is not None:
        return []
    sign = 1.0 if turn == "left" else -1.0
    if not sign * c.a.heading_change_deg < c.cfg.turn_deg:
        return []
    return [(f"does not turn {turn} (heading changes {c.a.heading_change_deg:+.0f} deg)",
             (_earlier("the turn does not complete in the log"),))]


def _timing_change(c: _Change) -> list[tuple[str, tuple[ParameterChange, ...]]]:
    """A start time keeps the agent within :attr:`JudgeConfig.still_m` until then; a delay keeps it still while
    the log moves."""
    behaviour, after, before, dt, cfg = c.behaviour, c.after, c.before, c.dt, c.cfg
    out: list[tuple[str, tuple[ParameterChange, ...]]] = []
    if behaviour.start_time_s is not None and _moved_by(after, behaviour.start_time_s - dt, dt) > cfg.still_m:
        out.append((f"moves before {behaviour.start_time_s:.1f} s",
                    (ParameterChange("start_time", f"{behaviour.start_time_s:.1f} s", "hold it still until then"),)))
    if behaviour.delay_s is not None and before is not None:
        window = behaviour.delay_s - dt
        if _moved_by(before, window, dt) > cfg.moved_m and _moved_by(after, window, dt) > cfg.still_m:
            out.append((f"does not start {behaviour.delay_s:.1f} s later",
                        (ParameterChange("start_time", f"{behaviour.delay_s + 1.0:.0f} s later",
                                         "the delay does not show"),)))
    return out


def _cross_street_change(c: _Change) -> list[tuple[str, tuple[ParameterChange, ...]]]:
    """Without a label: crossing moves the pedestrian :attr:`JudgeConfig.cross_m` off its log path and in all."""
    if not c.behaviour.cross_street or c.label is not None:
        return []
    moved = deviation_m(c.after, c.before) if c.before is not None else c.a.net_m
    if not (moved < c.cfg.cross_m or c.a.net_m < c.cfg.cross_m):
        return []
    return [(f"does not cross the street (moves {c.a.net_m:.1f} m)",
             (_earlier("the crossing does not show in the log"),))]


def _gait_change(c: _Change) -> list[tuple[str, tuple[ParameterChange, ...]]]:
    """Running raises the mean speed to at least 2 m/s and 1.3 times the log's."""
    if c.behaviour.gait != "run":
        return []
    want = max(2.0, 1.3 * c.ref.mean_speed) if c.ref is not None else 2.0
    if not c.a.mean_speed < want:
        return []
    return [(f"does not run (mean speed {c.a.mean_speed:.1f} m/s)", (_speed_suggestion(want + 1.0, "run faster"),))]


#: The change checks, in the order their findings are reported: (behaviour name, its check); ``"labels"`` checks
#: every behaviour of ``registry.LABEL_CHECKED`` on the auto-labeller's class.
CHANGE_CHECKS: tuple[tuple[str, ChangeCheck], ...] = (
    ("speed", _speed_change), ("longitudinal", _longitudinal_change), ("stop", _stop_change),
    ("labels", _label_change), ("reverse", _reverse_change), ("lane_change", _lane_change_change),
    ("turn", _turn_change), ("timing", _timing_change), ("cross_street", _cross_street_change),
    ("gait", _gait_change),
)
#: Behaviours the judge does not check on their own, and why.
UNCHECKED: dict[str, str] = {
    "follow": "following shows only as the motion of another agent; the trajectory must differ from the log",
    "jaywalk": "a jaywalk is checked as a street crossing",
    "lateral_offset": "a sideways shift shows only as a trajectory that differs from the log",
}


def _change_findings(oid: str, behaviour: Behaviour, after: AgentTrajectory, before: AgentTrajectory | None,
                     dt: float, cfg: JudgeConfig, label: str | None = None) -> list[Finding]:
    """What ``behaviour`` asks that ``after`` does not show (against ``before``, or its own start): the
    :data:`CHANGE_CHECKS` in order. Given the auto-labeller's motion class ``label`` of ``after``, the manoeuvres
    are checked on it instead of this judge's own thresholds; a trajectory that is the log's fails in any case."""
    a, b = motion_of(after, dt, cfg.tail_s), motion_of(before, dt, cfg.tail_s)
    change = _Change(behaviour, after, before, a, b, b if b.present else None, dt, cfg, label)
    out = [Finding("change", f"{oid}: {why}", suggestions)
           for _, check in CHANGE_CHECKS for why, suggestions in check(change)]
    if before is not None and not out and deviation_m(after, before) < cfg.changed_m:
        ref = change.ref
        out.append(Finding("change", f"{oid}: its trajectory is the log's", (_speed_suggestion(
            max(ref.mean_speed if ref else 0.0, 1.0) * 1.5, "the change is too small to show: ask for a larger one"),)))
    return out


def _command_findings(index: int, command: EditCommand, ids: tuple[str, ...], request: JudgeRequest,
                      cfg: JudgeConfig) -> tuple[list[Finding], list[str]]:
    """Findings of one command and the reasons it passed."""
    what = command.note or command.op
    if command.op == "remove":
        if not ids:
            return [Finding("grounding", f"command {index} ({what}): no target was removed",
                            (ParameterChange("anchor", "a description naming the object", "nothing was found"),))], []
        left = [o for o in ids if motion_of(request.trajectory(o), request.dt_s).present]
        if left:
            return [Finding("change", f"{', '.join(left)} still in the scene after removal",
                            (ParameterChange("other", "remove the object's whole track", "it is still there"),))], []
        return [], [f"removed {', '.join(ids)}"]
    present = [o for o in ids if motion_of(request.trajectory(o), request.dt_s).present]
    if not present:
        kind = "nothing was inserted" if command.op == "insert" else "the target is not in the scenario"
        change = (ParameterChange("offset", "another spot nearby", kind) if command.op == "insert"
                  else ParameterChange("anchor", "a description naming the object", kind))
        return [Finding("grounding", f"command {index} ({what}): {kind}", (change,))], []
    findings: list[Finding] = []
    for oid in present:
        after = request.trajectory(oid)
        assert after is not None  # present
        if command.behaviour is not None:
            label = None if request.motion_labels is None else request.motion_labels.get(oid)
            findings += _change_findings(oid, command.behaviour, after, request.log_trajectory(oid), request.dt_s,
                                         cfg, label)
        elif command.op == "modify":  # a move (placement only)
            before = request.log_trajectory(oid)
            if before is not None and deviation_m(after, before) < cfg.changed_m:
                findings.append(Finding("change", f"{oid}: not moved",
                                        (ParameterChange("offset", "2 m further", "the move is too small to show"),)))
    return findings, [] if findings else [f"{command.op} {', '.join(present)}: requested change present"]


def _targets(request: JudgeRequest, commands: list[EditCommand]) -> list[tuple[str, ...]]:
    """Object ids per command: ``request.command_targets``, else every target trajectory for each command."""
    if request.command_targets:
        return list(request.command_targets)
    targets = tuple(t.object_id for t in request.trajectories if t.is_target)
    return [targets] * len(commands)


def _generic_findings(request: JudgeRequest, cfg: JudgeConfig) -> tuple[list[Finding], list[str]]:
    """Without a program: some target exists and differs from its log (or is new, or is gone)."""
    targets = [t for t in request.trajectories if t.is_target]
    if not targets:
        return [Finding("grounding", "no target trajectory given",
                        (ParameterChange("anchor", "a description naming the object", "nothing was edited"),))], []
    for t in targets:
        before = request.log_trajectory(t.object_id)
        after_present = t.present.any()
        if before is None or not after_present or deviation_m(t, before) >= cfg.changed_m:
            return [], [f"{t.object_id} changed"]
    return [Finding("change", "no target differs from the log",
                    (_speed_suggestion(3.0, "the change is too small to show: ask for a larger one"),))], []


# ---------------------------------------------------------------------------------------------- validation
def _pace_asked(request: JudgeRequest, object_id: str) -> bool:
    """A command acting on ``object_id`` asks for its pace (a speed or a gait: "run", "at 30 km/h"): slowing it down
    would undo the prompt."""
    if request.program is None:
        return False
    for command, targets in zip(request.program.commands, request.command_targets):
        b = command.behaviour
        if object_id in targets and b is not None and (b.speed is not None or b.gait is not None):
            return True
    return False


def _may_slow(request: JudgeRequest, object_id: str) -> bool:
    """A slower ``object_id`` is a change the program can make: the program (when known) acts on it, and does not
    ask for its pace (a runner told to run is not slowed down; an agent the traffic model moved is no command's)."""
    if request.program is None:
        return True
    acted_on = {o for targets in request.command_targets for o in targets}
    return object_id in acted_on and not _pace_asked(request, object_id)


def _validation_findings(failures: Iterable[ValidationFailure], request: JudgeRequest) -> list[Finding]:
    out = []
    for f in failures:
        traj = request.trajectory(f.object_id)
        source = traj.source if traj is not None else ""
        speed = motion_of(traj, request.dt_s).mean_speed
        text = f.text or f"{f.object_id}: {f.kind}"
        if f.kind == "collision":
            other = f.other_id or "another agent"
            changes = [ParameterChange("start_time", "2 s later", f"{f.object_id} meets {other}")]
            if speed > 0.5 and _may_slow(request, f.object_id):
                changes.append(ParameterChange("speed", f"{0.7 * speed:.1f} m/s", f"slower, to keep clear of {other}"))
            if source in ("inserted", "refined", ""):
                changes.append(ParameterChange("offset", "5 m further away", f"place it clear of {other}"))
            out.append(Finding("collision", text, tuple(changes)))
        elif f.kind == "offroad":
            out.append(Finding("offroad", text, (
                ParameterChange("offset", "1 m back towards the lane centre", "it leaves the drivable area"),
                ParameterChange("anchor", "an object on the road, or the ego lane", "place it on the road"))))
        else:
            out.append(Finding("kinematic", text, (
                ParameterChange("speed", f"{max(0.7 * speed, 1.0):.1f} m/s", "a gentler motion"),)))
    return out


# ---------------------------------------------------------------------------------------------- renders
def render_problem(image: np.ndarray, cfg: JudgeConfig) -> str | None:
    """``"blank"`` (constant), ``"holes"`` (mostly near-black) or ``None`` for an ``[H, W, 3]`` image."""
    rgb = np.asarray(image)
    rgb = rgb.astype(np.float64) / 255.0 if rgb.dtype == np.uint8 else rgb.astype(np.float64)
    if float(rgb.std()) < cfg.blank_std:
        return "blank"
    if float((rgb.max(axis=-1) < cfg.dark_level).mean()) > cfg.hole_share:
        return "holes"
    return None


def _render_findings(request: JudgeRequest, targets: Iterable[str], cfg: JudgeConfig) -> list[Finding]:
    out = []
    problems = [(i, p) for i, p in ((i, render_problem(r, cfg)) for i, r in enumerate(request.renders)) if p]
    if problems:
        listed = ", ".join(f"render {i} {p}" for i, p in problems)
        out.append(Finding("render", f"degenerate renders: {listed}",
                           (ParameterChange("other", "render again from the stored scene", "the views show nothing"),)))
    if request.visible_pixels is not None:
        unseen = [o for o in dict.fromkeys(targets) if motion_of(request.trajectory(o), request.dt_s).present
                  and request.visible_pixels.get(o, 0) < cfg.min_visible_pixels]
        if unseen:
            shown = ", ".join(f"{o} ({request.visible_pixels.get(o, 0)} px)" for o in unseen)
            out.append(Finding("visibility", f"not visible in the renders: {shown}", (
                ParameterChange("asset", "a larger object", "the target covers too few pixels"),
                ParameterChange("offset", "10 m closer to the ego", "bring it into the cameras' view"))))
    return out


# ---------------------------------------------------------------------------------------------- verdict
def _unique(changes: Iterable[ParameterChange]) -> tuple[ParameterChange, ...]:
    seen: dict[tuple[str, str], ParameterChange] = {}
    for c in changes:
        seen.setdefault((c.parameter, c.value), c)
    return tuple(seen.values())


def judge_edit(request: JudgeRequest, config: JudgeConfig | None = None) -> Judgement:
    """The verdict on an executed edit from explicit checks (module docstring)."""
    cfg = config or JudgeConfig()
    findings: list[Finding] = []
    passed: list[str] = []
    if request.program is not None:
        commands = list(request.program.commands)
        targets = _targets(request, commands)
        for index, (command, ids) in enumerate(zip(commands, targets)):
            found, ok = _command_findings(index, command, ids, request, cfg)
            findings += found
            passed += ok
        all_targets = [o for ids in targets for o in ids]
    else:
        found, ok = _generic_findings(request, cfg)
        findings += found
        passed += ok
        all_targets = [t.object_id for t in request.trajectories if t.is_target]
    findings += _validation_findings(request.failures, request)
    findings += _render_findings(request, all_targets, cfg)
    failed = {f.check for f in findings}
    follows = not (failed & FOLLOW_CLASSES)
    plausibility = max(PLAUSIBILITY_MIN, PLAUSIBILITY_MAX - sum(PENALTIES[c] for c in failed))
    if not failed & {"collision", "offroad", "kinematic"}:
        passed.append("no collision, off-road or infeasible motion")
    if "render" not in failed:
        passed.append("renders not degenerate")
    reasons = tuple(f.reason for f in findings) + tuple(passed)
    logger.debug("judged %r: follows=%s plausibility=%d failed=%s", request.prompt, follows, plausibility,
                 sorted(failed))
    return Judgement(follows_prompt=follows, plausibility=plausibility, reasons=reasons or ("all checks passed",),
                     suggestions=_unique(c for f in findings for c in f.suggestions))


__all__ = ["CHANGE_CHECKS", "FOLLOW_CLASSES", "LABEL_SUGGESTIONS", "PENALTIES", "UNCHECKED", "Finding", "JudgeConfig",
           "Motion", "deviation_m", "judge_edit", "motion_of", "render_problem"]
