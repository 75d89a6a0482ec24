"""Success checks of edits against ground truth, measured on the edited trajectories (SIMSplat Table 3).

A check never trusts the editor's report: objects are identified by their ground-truth ids (the log's
object ids, which ``AgentStates`` keeps), what changed is measured by comparing the agents before and
after (``observation.state_changes``), and every requested change is measured on the edited
trajectories:

* **who**: remove drops exactly the targets; modify changes exactly the targets; replace redraws exactly
  the targets (a new node on the unchanged trajectory, or the target swapped for a new agent driving it);
  insert adds exactly ``count`` agents of the asked category (a static object of a catalogue kind with that
  kind's box size); the ego never moves; other agents may only react (multi-agent refinement: slow down,
  stop, yield or detour, every position within ``REACTION_PATH_M`` of their logged path, present where the
  log has them), anything more is an edit of the wrong object.
* **where** (inserts, at the new agent's first step, relative to the ground-truth anchor -- the ego or a
  scene object -- at that step): in a lane (the anchor's lane, its left / right neighbour or the
  oncoming lane, about ``d`` metres ahead along any lane-following path from the anchor, aligned with
  the lane), behind / in front of / left of / right of the anchor at about ``d`` (gap or centre
  distance, either reading), next to it (within 3 m, not overlapping), on the sidewalk / crosswalk /
  road of the world's layout; overlapping no other agent; vehicles on the road.
* **how** (``MotionIntent``): speeds reached (vehicles: the mean over the last 0.5 s; pedestrians: the
  median over moving steps), standstill reached and held (by a time; before the crosswalk with the front
  bumper short of it), braking hard (peak deceleration), accelerating / decelerating (start vs end
  speed), reversing, lane changes, turns and going straight, crossing the street (the trajectory
  auto-labeller, ``language.motion_labels``, on the edited trajectory with the world's map), jaywalking
  (off the crosswalks), running, delays (standing until the delay, then moving along the original path).

Speeds are measured from positions (a local line fit over 0.25 s, signed along the heading), not read
from the editor's speed column. Thresholds are module constants; :func:`check_states` returns every
failed condition in its reason.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from simsplat_core.editing.assets.procedural import STATIC_KINDS
from simsplat_core.editing.behaviours.declaration import LabelCheck
from simsplat_core.editing.behaviours.registry import LABEL_CHECKED
from simsplat_core.eval.editing.intents import EGO, EditIntent, MotionIntent, PlacementIntent
from simsplat_core.eval.editing.observation import EditObservation, StateChanges, state_changes, trajectory_changed
from simsplat_core.eval.editing.truth import SceneTruth
from simsplat_core.geometry import wrap_angle
from simsplat_core.language.motion_labels import MotionLabel, label_trajectory
from simsplat_core.scenario.agents import EGO_ID, AgentStates
from simsplat_core.scenario.geometry import box_footprints, footprints_overlap, segment_distances
from simsplat_core.scenario.trajectory import ObjectTrajectory, agent_trajectory, smoothed_velocity

#: Half a lane: an object is in a lane when this close to a lane-following path (metres).
IN_LANE_M = 1.75
#: Heading agreement with the lane / anchor for inserted vehicles (degrees).
ALIGN_DEG = 25.0
#: Standstill: speed below this (m/s) from some step to the end, moving less than ``STILL_DRIFT_M``.
STILL_MPS = 0.3
STILL_DRIFT_M = 0.5
#: Hard braking: peak deceleration at least this (m/s^2).
HARD_BRAKE_MPS2 = 4.0
#: Running pedestrians: median moving speed at least this (m/s); walking at most this.
RUN_MPS = 2.2
#: "Next to": footprints at most this far apart (metres).
NEXT_TO_M = 3.0
#: A delayed agent keeps to its original path within this (metres).
PATH_TOL_M = 0.75
#: An agent that reacts to an edit keeps within this of its logged path (a detour of at most a lane), metres.
REACTION_PATH_M = 4.0
#: A walker keeps to its path within this (metres) ...
WALK_PATH_TOL_M = 0.5
#: ... but may step up to this far aside (metres) while passing another pedestrian, one within
#: ``PASSING_NEAR_M`` of it (metres, centres), as people do on a pavement.
PASSING_ASIDE_M = 1.3
PASSING_NEAR_M = 4.0
#: The direction a path ends in is taken over its last this many metres (``_across_beyond_end``).
END_DIRECTION_M = 1.0
#: An inserted static object's box is within this share of its kind's catalogue box, per dimension.
KIND_SIZE_TOL = 0.2


@dataclass(frozen=True)
class CheckResult:
    """Outcome of checking one edit.

    Attributes:
        passed: every condition held.
        reason: ``"ok"`` plus what was measured, or the failed conditions separated by ``"; "``.
        measured: named measurements (speeds, distances, labels as 1.0 flags ...).
    """

    passed: bool
    reason: str
    measured: dict[str, float] = field(default_factory=dict)


class Verdict:
    """Collects failed conditions, notes and measurements of one check."""

    def __init__(self) -> None:
        self.failures: list[str] = []
        self.notes: list[str] = []
        self.measured: dict[str, float] = {}

    def require(self, condition: bool, failure: str) -> bool:
        if not condition:
            self.failures.append(failure)
        return bool(condition)

    def note(self, text: str) -> None:
        self.notes.append(text)

    def result(self) -> CheckResult:
        if self.failures:
            return CheckResult(False, "; ".join(self.failures), dict(self.measured))
        return CheckResult(True, "; ".join(["ok", *self.notes]), dict(self.measured))


# ---------------------------------------------------------------------------------------------- measuring
def measured_speed(states: AgentStates, row: int, half_window_s: float = 0.25) -> np.ndarray:
    """``[T]`` speed along the heading (m/s, negative when reversing) from positions; 0 at invalid steps."""
    valid = states.valid[row]
    out = np.zeros(states.num_steps)
    if valid.sum() < 2:
        return out
    t, xy = states.times[valid], states.xy[row, valid]
    vel = smoothed_velocity(t, xy, half_window_s)
    h = states.heading[row, valid]
    out[valid] = vel[:, 0] * np.cos(h) + vel[:, 1] * np.sin(h)
    return out


def edited_trajectory(truth: SceneTruth, states: AgentStates, row: int) -> ObjectTrajectory:
    """One agent of ``states`` as an ``ObjectTrajectory`` over its valid steps, with the world's map facts.

    Raises:
        ValueError: the agent has no motion vocabulary (static objects) or fewer than two valid steps.
    """
    return agent_trajectory(states, row, truth.map_context)


def motion_label(truth: SceneTruth, states: AgentStates, row: int) -> MotionLabel:
    """The auto-labeller's verdict on an edited trajectory (``motion_labels.label_trajectory``)."""
    return label_trajectory(edited_trajectory(truth, states, row), truth.world.ego_poses, truth.map_context)


def _edge(values: np.ndarray, times: np.ndarray, seconds: float, last: bool) -> float:
    pick = times >= times[-1] - seconds if last else times <= times[0] + seconds
    return float(np.mean(values[pick]))


def _still_from(speed: np.ndarray, xy: np.ndarray, limit: float) -> int | None:
    """First index from which the agent stays below ``limit`` m/s and within ``STILL_DRIFT_M`` to the end."""
    slow = np.abs(speed) <= limit
    if not slow[-1]:
        return None
    k = len(slow) - 1
    while k > 0 and slow[k - 1]:
        k -= 1
    while k < len(slow) - 1 and np.linalg.norm(xy[-1] - xy[k]) > STILL_DRIFT_M:
        k += 1
    return k


def _path_distance(xy: np.ndarray, path_xy: np.ndarray) -> np.ndarray:
    """``[N]`` distance of points to the polyline ``path_xy`` ``[P, 2]``."""
    if len(path_xy) < 2:
        return np.linalg.norm(xy - path_xy[:1], axis=1)
    return segment_distances(xy, path_xy[:-1], path_xy[1:]).min(axis=1)


def _anchor_pose(truth: SceneTruth, anchor: str, step: int) -> tuple[np.ndarray, float, tuple[float, float, float]]:
    """``(xy [2], heading, size)`` of the ground-truth anchor (or the ego) at ``step``."""
    if anchor == EGO:
        from simsplat_core.world.agents import EGO_SIZE  # noqa: PLC0415  # the numba-heavy world package

        return truth.ego_xy[step], float(truth.ego_heading[step]), EGO_SIZE
    agent = truth.agent(anchor)
    return agent.traj["xy"][step], float(agent.traj["heading"][step]), agent.size


def _in_frame(xy: np.ndarray, origin: np.ndarray, heading: float) -> np.ndarray:
    """``[..., 2]`` points in the frame at ``origin`` facing ``heading`` (x forward, y left)."""
    c, s = np.cos(heading), np.sin(heading)
    rel = np.asarray(xy, dtype=np.float64) - origin
    return np.stack([c * rel[..., 0] + s * rel[..., 1], -s * rel[..., 0] + c * rel[..., 1]], axis=-1)


def footprint_gap(xy_a: np.ndarray, h_a: float, size_a: tuple[float, ...], xy_b: np.ndarray, h_b: float,
                  size_b: tuple[float, ...]) -> float:
    """Smallest distance between two box footprints (0 when they overlap)."""
    a = box_footprints(np.asarray(xy_a, float), np.asarray(h_a, float), np.asarray(size_a[:2], float))
    b = box_footprints(np.asarray(xy_b, float), np.asarray(h_b, float), np.asarray(size_b[:2], float))
    if footprints_overlap(np.asarray(xy_a)[None], np.array([h_a]), (float(size_a[0]), float(size_a[1])),
                          np.asarray(xy_b)[None], np.array([h_b]), (float(size_b[0]), float(size_b[1])))[0]:
        return 0.0
    d_ab = segment_distances(a, b, np.roll(b, -1, axis=0)).min()
    d_ba = segment_distances(b, a, np.roll(a, -1, axis=0)).min()
    return float(min(d_ab, d_ba))


def _distance_ok(measured_centre: float, measured_gap: float, wanted: float | None, tol_frac: float = 0.3,
                 tol_min: float = 1.5, default: tuple[float, float] = (-0.3, 15.0)) -> bool:
    """A said distance matches the centre distance or the gap (either reading); unsaid: gap in ``default``."""
    if wanted is None:
        return default[0] <= measured_gap <= default[1]
    tol = max(tol_min, tol_frac * wanted)
    return abs(measured_centre - wanted) <= tol or abs(measured_gap - wanted) <= tol


# ---------------------------------------------------------------------------------------------- who changed
def _check_reactions(before: AgentStates, after: AgentStates, others: Sequence[str], v: Verdict) -> None:
    """Agents the request is not about may only react to it (multi-agent refinement): keep to their logged path
    (every position within :data:`REACTION_PATH_M` of it: slowing, stopping, yielding or a detour of at most a
    lane) and be present where the log has them. Anything else is an edit of the wrong object."""
    strayed = []
    for oid in others:
        i, j = before.index(oid), after.index(oid)
        path = before.xy[i, before.valid[i]]
        now = after.xy[j, after.valid[j]]
        if not np.array_equal(before.valid[i], after.valid[j]) or len(path) < 2:
            strayed.append(oid)
            continue
        seg_a, seg_b = path[:-1], path[1:]
        off = segment_distances(now, seg_a, seg_b).min(axis=1) if len(seg_a) else np.zeros(len(now))
        moved = float(np.abs(path - now).max(initial=0.0)) > 1e-6
        if moved and float(off.max(initial=0.0)) > REACTION_PATH_M:
            strayed.append(oid)
    if others:
        v.measured["reacted"] = float(len(others))
    v.require(not strayed, f"changed {strayed}, which the request is not about, beyond reacting to it")


def _check_who(intent: EditIntent, before: AgentStates, after: AgentStates, changes: StateChanges,
               v: Verdict) -> tuple[str, ...]:
    """Conditions on which agents changed; returns the agents whose motion / look the request is about."""
    targets = set(intent.targets)
    v.require(EGO_ID not in changes.removed + changes.moved, "the ego was edited")
    if intent.op == "remove":
        v.require(set(changes.removed) == targets,
                  f"removed {sorted(changes.removed) or 'nothing'}, asked for {sorted(targets)}")
        v.require(not changes.added, f"also added {list(changes.added)}")
        _check_reactions(before, after, changes.moved, v)
        return ()
    if intent.op == "modify":
        v.require(not changes.removed and not changes.added,
                  f"removed {list(changes.removed)} / added {list(changes.added)} in a modify")
        v.require(targets <= set(changes.moved),
                  f"changed the trajectory of {sorted(changes.moved) or 'nothing'}, asked for {sorted(targets)}")
        _check_reactions(before, after, [o for o in changes.moved if o not in targets], v)
        return tuple(t for t in intent.targets if t in after.object_ids)
    if intent.op == "replace":
        kept = [t for t in intent.targets if t in changes.redrawn]
        swapped = [t for t in intent.targets if t in changes.removed]
        v.require(len(kept) + len(swapped) == len(targets),
                  f"targets {sorted(targets - set(kept) - set(swapped))} were neither redrawn nor swapped")
        v.require(len(changes.added) == len(swapped), f"{len(swapped)} targets removed but {len(changes.added)} "
                  "agents added")
        others = [o for o in changes.removed if o not in targets] + [o for o in changes.redrawn if o not in targets]
        v.require(not others, f"also changed {others}")
        _check_reactions(before, after, [o for o in changes.moved if o not in targets], v)
        for t in kept:
            v.require(not trajectory_changed(before, after, t, tol=0.05), f"replace moved {t}")
        for t, new in zip(swapped, changes.added):
            i, j = before.index(t), after.index(new)
            same = np.array_equal(before.valid[i], after.valid[j]) and np.abs(
                before.xy[i, before.valid[i]] - after.xy[j, after.valid[j]]).max(initial=0.0) <= 0.05
            v.require(bool(same), f"the replacement {new} does not drive {t}'s trajectory")
        return tuple(kept) + tuple(changes.added)
    count = intent.asset.count if intent.asset is not None else 1
    v.require(len(changes.added) == count, f"added {len(changes.added)} agents, asked for {count}")
    v.require(not changes.removed, f"also removed {list(changes.removed)}")
    _check_reactions(before, after, changes.moved, v)
    if intent.asset is not None:
        wrong = [o for o in changes.added if after.categories[after.index(o)] != intent.asset.category]
        v.require(not wrong, f"inserted {[after.categories[after.index(o)] for o in wrong]}, asked for a "
                  f"{intent.asset.category}")
        _check_static_kind(intent, after, changes.added, v)
    return changes.added


def _check_static_kind(intent: EditIntent, after: AgentStates, added: tuple[str, ...], v: Verdict) -> None:
    """A static object of a catalogue kind has that kind's box (within ``KIND_SIZE_TOL``): the captioner tells
    cones from barriers by the box, not e.g. a barrel from a cone."""
    asset = intent.asset
    if asset is None or asset.category != "static" or asset.subtype not in STATIC_KINDS:
        return
    nominal = np.asarray(STATIC_KINDS[asset.subtype].size, dtype=np.float64)
    want = np.concatenate([np.sort(nominal[:2]), nominal[2:]])
    for o in added:
        size = after.size[after.index(o)]
        got = np.concatenate([np.sort(size[:2]), size[2:]])
        v.require(bool(np.all(np.abs(got - want) <= KIND_SIZE_TOL * want)),
                  f"{o} has a {got[1]:.2f} x {got[0]:.2f} x {got[2]:.2f} m box, a {asset.subtype} is "
                  f"{want[1]:.2f} x {want[0]:.2f} x {want[2]:.2f} m")


# ---------------------------------------------------------------------------------------------- where
def _lane_paths(truth: SceneTruth, xy: np.ndarray, heading: float, choice: str) -> list[np.ndarray]:
    """Lane-following paths (``[P, 2]`` points from the start point) of the anchor's lane or its
    ``left`` / ``right`` neighbour, every manoeuvre at the branches."""
    lanes = truth.lanes
    match = lanes.nearest(np.asarray(xy)[None], np.array([heading]))
    lane = int(match.lane[0])
    if lane < 0:
        return []
    if choice in ("left", "right"):
        lane = int((lanes.left if choice == "left" else lanes.right)[lane])
        if lane < 0:
            return []
        neighbour = lanes.lanes[lane].points
        s_on, _ = _along_path(neighbour, np.asarray(xy, float))
        xy = np.stack([np.interp(s_on, _arc(neighbour), neighbour[:, k]) for k in range(2)])
    out = []
    for manoeuvre in ("straight", "left", "right"):
        try:
            path = lanes.follow(np.asarray(xy, float), heading, manoeuvre)
        except ValueError:
            continue
        keep = path.path.s >= path.start_s - 1e-6
        pts = np.concatenate([path.path.position(path.start_s)[None], path.path.points[keep]])
        out.append(pts)
    return out


def _along_path(pts: np.ndarray, xy: np.ndarray) -> tuple[float, float]:
    """``(arc length from the path start to the closest point, distance to the path)``."""
    seg_a, seg_b = pts[:-1], pts[1:]
    d = segment_distances(np.asarray(xy, float)[None], seg_a, seg_b)[0]
    i = int(np.argmin(d))
    ab = seg_b[i] - seg_a[i]
    t = float(np.clip(np.dot(xy - seg_a[i], ab) / max(float(np.dot(ab, ab)), 1e-12), 0.0, 1.0))
    s = float(np.linalg.norm(np.diff(pts[: i + 1], axis=0), axis=1).sum() + t * np.linalg.norm(ab))
    return s, float(d[i])


def _arc(pts: np.ndarray) -> np.ndarray:
    """``[P]`` cumulative arc length of a polyline."""
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])


def _path_heading(pts: np.ndarray, s: float) -> float:
    seg = np.diff(pts, axis=0)
    cum = _arc(pts)
    i = int(np.clip(np.searchsorted(cum, s, side="right") - 1, 0, len(seg) - 1))
    return float(np.arctan2(seg[i, 1], seg[i, 0]))


def _check_in_lane(truth: SceneTruth, p: PlacementIntent, rows: list[int], after: AgentStates, step: int,
                   vehicle: bool, v: Verdict) -> None:
    axy, ah, _ = _anchor_pose(truth, p.anchor, step)
    xy = after.xy[rows, step]
    lane = p.lane or "same"
    if lane == "opposite":
        for r in rows:
            local = _in_frame(after.xy[r, step], axy, ah)
            opposite = abs(float(wrap_angle(after.heading[r, step] - ah))) >= np.deg2rad(180 - ALIGN_DEG)
            lane_dist = float(truth.map_context.facts(after.xy[r, step][None], after.heading[r, step:step + 1])
                              .lane_dist[0])
            v.measured.update(ahead_m=float(local[0]), left_m=float(local[1]))
            v.require(local[1] > 0 and lane_dist <= IN_LANE_M, f"not in an oncoming lane (left {local[1]:.1f} m, "
                      f"{lane_dist:.1f} m from a lane centre)")
            v.require(opposite or not vehicle, "not facing the oncoming direction")
            if p.distance_m is not None:
                tol = max(3.0, 0.25 * p.distance_m)
                v.require(abs(local[0] - p.distance_m) <= tol, f"{local[0]:.1f} m ahead, asked {p.distance_m:g} m")
        return
    paths = _lane_paths(truth, axy, ah, lane)
    if not v.require(bool(paths), f"no {lane} lane at the anchor"):
        return
    best: tuple[float, float, float] | None = None  # (score, arc, lateral)
    for pts in paths:
        arcs, lats = zip(*(_along_path(pts, q) for q in xy))
        arc = min(arcs)  # a row starts at the said distance (or is centred on it: checked below)
        lat = max(lats)
        centre_arc = float(np.mean(arcs))
        wanted = p.distance_m
        if wanted is not None:
            tol = max(3.0, 0.25 * wanted)
            dist_err = min(abs(arc - wanted), abs(centre_arc - wanted)) - tol
        else:
            dist_err = 0.0 if 0 < arc <= 60 else abs(arc)
        aligned = all(abs(float(wrap_angle(after.heading[r, step] - _path_heading(pts, a)))) <= np.deg2rad(ALIGN_DEG)
                      for r, a in zip(rows, arcs)) or not vehicle
        score = max(dist_err, 0.0) + max(lat - IN_LANE_M, 0.0) + (0.0 if aligned else 100.0)
        if best is None or score < best[0]:
            best = (score, centre_arc, lat)
    assert best is not None
    v.measured.update(lane_arc_m=best[1], lane_offset_m=best[2])
    v.require(best[0] <= 0.0, f"not in the {lane} lane at the said distance (best: {best[1]:.1f} m along, "
              f"{best[2]:.1f} m off the centre line{', misaligned' if best[0] >= 100 else ''}"
              f"{'' if p.distance_m is None else f', asked {p.distance_m:g} m'})")


def _check_relative(truth: SceneTruth, p: PlacementIntent, row: int, after: AgentStates, step: int,
                    vehicle: bool, v: Verdict) -> None:
    axy, ah, asize = _anchor_pose(truth, p.anchor, step)
    xy, h, size = after.xy[row, step], float(after.heading[row, step]), tuple(after.size[row])
    local = _in_frame(xy, axy, ah)
    gap = footprint_gap(axy, ah, asize, xy, h, size)
    v.measured.update(anchor_x_m=float(local[0]), anchor_y_m=float(local[1]), anchor_gap_m=gap)
    if p.relation in ("behind", "in_front_of"):
        ahead = p.relation == "in_front_of"
        v.require(local[0] > 0 if ahead else local[0] < 0,
                  f"{'behind' if ahead else 'in front of'} the anchor (x {local[0]:.1f} m)")
        v.require(abs(local[1]) <= IN_LANE_M, f"{abs(local[1]):.1f} m beside the anchor's line")
        v.require(_distance_ok(abs(float(local[0])), gap, p.distance_m),
                  f"gap {gap:.1f} m / centres {abs(local[0]):.1f} m, asked {p.distance_m or 'close'}")
        if vehicle:
            v.require(abs(float(wrap_angle(h - ah))) <= np.deg2rad(ALIGN_DEG + 5), "not facing the anchor's way")
    elif p.relation in ("left_of", "right_of"):
        left = p.relation == "left_of"
        v.require(local[1] > 0 if left else local[1] < 0,
                  f"on the {'right' if left else 'left'} of the anchor (y {local[1]:.1f} m)")
        v.require(abs(local[0]) <= asize[0] / 2 + size[0] / 2 + 2.0, f"{local[0]:.1f} m along the anchor")
        v.require(_distance_ok(abs(float(local[1])), gap, p.distance_m, tol_min=1.0, default=(-0.1, 4.0)),
                  f"gap {gap:.1f} m / centres {abs(local[1]):.1f} m, asked {p.distance_m or 'close'}")
    elif p.relation == "next_to":
        v.require(0.0 < gap <= NEXT_TO_M if p.distance_m is None else _distance_ok(
            float(np.linalg.norm(local)), gap, p.distance_m), f"gap to the anchor {gap:.1f} m")


def _check_area(truth: SceneTruth, p: PlacementIntent, rows: list[int], after: AgentStates, step: int,
                v: Verdict) -> None:
    layout = truth.layout
    xy = after.xy[rows, step]
    if p.relation == "on_sidewalk":
        regions = [truth.road_position(q, 0.0).region for q in xy]
        v.require(all(r == "sidewalk" for r in regions), f"on {regions}, asked for the sidewalk")
    elif p.relation == "on_crosswalk":
        v.require(bool(layout.in_crosswalk(xy).all()), "not on a crosswalk")
    elif p.relation == "on_road":
        v.require(bool(layout.on_road(xy).all()), "not on the road")
    axy, ah, _ = _anchor_pose(truth, p.anchor, step)
    local = _in_frame(xy, axy, ah)
    v.measured["ahead_m"] = float(local[:, 0].mean())
    if p.distance_m is not None:
        tol = max(4.0, 0.3 * p.distance_m)
        v.require(bool(np.all(np.abs(local[:, 0] - p.distance_m) <= tol)),
                  f"{local[:, 0].mean():.1f} m ahead, asked {p.distance_m:g} m")
    elif p.relation == "on_crosswalk":
        v.require(bool(np.all(local[:, 0] > 0)), "the crosswalk is not ahead")


def _footprint(states: AgentStates, row: int) -> tuple[float, float]:
    return float(states.size[row, 0]), float(states.size[row, 1])


def _check_placement(truth: SceneTruth, intent: EditIntent, after: AgentStates, new: tuple[str, ...],
                     v: Verdict) -> None:
    p = intent.placement
    rows = [after.index(o) for o in new]
    steps = np.flatnonzero(after.valid[rows].all(axis=0))
    if not v.require(steps.size > 0, "the inserted agents never exist at the same step"):
        return
    step = int(steps[0])
    category = intent.asset.category if intent.asset is not None else after.categories[rows[0]]
    vehicle = category == "vehicle"
    if vehicle:
        v.require(bool(truth.layout.on_road(after.xy[rows, step]).all()), "vehicle placed off the road")
    others = [r for r in range(after.num_agents) if r not in rows and after.valid[r, step]]
    for r in rows:
        hits = [after.object_ids[o] for o in others if footprints_overlap(
            after.xy[r, step][None], after.heading[r, step:step + 1], _footprint(after, r),
            after.xy[o, step][None], after.heading[o, step:step + 1], _footprint(after, o))[0]]
        v.require(not hits, f"placed overlapping {hits}")
    if p is None:
        return
    if intent.motion is not None and intent.motion.cross_street:
        _check_crossing_spot(truth, p, rows[0], after, v)
    elif p.relation == "in_lane":
        _check_in_lane(truth, p, rows, after, step, vehicle, v)
    elif p.relation in ("behind", "in_front_of", "left_of", "right_of", "next_to"):
        _check_relative(truth, p, rows[0], after, step, vehicle, v)
    else:
        _check_area(truth, p, rows, after, step, v)


def _check_crossing_spot(truth: SceneTruth, p: PlacementIntent, row: int, after: AgentStates, v: Verdict) -> None:
    """An inserted crossing pedestrian crosses about ``d`` ahead: measured where it first steps on the road, from
    the anchor's centre or its front (either reading, as for every said distance: ``_distance_ok``)."""
    valid = np.flatnonzero(after.valid[row])
    on_road = valid[truth.layout.on_road(after.xy[row, valid])]
    if not v.require(on_road.size > 0, "the crossing pedestrian never steps on the road"):
        return
    step = int(on_road[0])
    axy, ah, asize = _anchor_pose(truth, p.anchor, int(valid[0]))
    ahead = float(_in_frame(after.xy[row, step], axy, ah)[0])
    v.measured["crossing_ahead_m"] = ahead
    if p.distance_m is not None:  # centre to centre, or from the anchor's front to the person (either reading)
        gap = ahead - float(asize[0]) / 2.0 - float(after.size[row, 0]) / 2.0
        v.require(_distance_ok(ahead, gap, p.distance_m, tol_frac=0.35, tol_min=4.0),
                  f"crosses {ahead:.1f} m ahead (centres; {gap:.1f} m from the front), asked {p.distance_m:g} m")
    else:
        v.require(ahead > 0, "crosses behind the ego")


# ---------------------------------------------------------------------------------------------- how
@dataclass(frozen=True)
class _Sample:
    """One edited agent as the motion checks see it: its valid steps' times ``t [K]`` (s), positions ``xy [K, 2]``
    and measured ``speed [K]`` (m/s), the mean speed over its first 0.3 s / last 0.5 s, whether it is a pedestrian,
    and the auto-labeller's verdict (``None``: no manoeuvre asked)."""

    truth: SceneTruth
    before: AgentStates
    after: AgentStates
    object_id: str
    row: int
    t: np.ndarray
    xy: np.ndarray
    speed: np.ndarray
    pedestrian: bool
    v_start: float
    v_end: float
    label: MotionLabel | None


#: A motion check: the conditions one behaviour of ``MotionIntent`` puts on the edited agent.
MotionCheck = Callable[[MotionIntent, _Sample, Verdict], None]
#: Behaviour name -> its label check (``registry.LABEL_CHECKED``).
_LABEL_CHECKS: dict[str, LabelCheck] = {d.name: d.label_check for d in LABEL_CHECKED if d.label_check is not None}


def _manoeuvre_asked(m: MotionIntent) -> bool:
    """``m`` asks a manoeuvre the auto-labeller checks (``registry.LABEL_CHECKED``: reverse, lane change, turn,
    crossing)."""
    return any(getattr(m, check.field) for check in _LABEL_CHECKS.values())


def _moving_speed(s: _Sample) -> float:
    """Median absolute speed over the steps the agent moves (m/s; 0 when it never does)."""
    moving = np.abs(s.speed) >= STILL_MPS
    return float(np.median(np.abs(s.speed[moving]))) if moving.any() else 0.0


def _check_speed(m: MotionIntent, s: _Sample, v: Verdict) -> None:
    """The asked speed is reached: vehicles' end speed within 10 % (at least 0.75 m/s), pedestrians' median moving
    speed within 20 % (at least 0.25 m/s)."""
    if m.speed_mps is None:
        return
    if s.pedestrian:
        got = _moving_speed(s)
        tol = max(0.25, 0.2 * m.speed_mps)
    else:
        got, tol = s.v_end, max(0.75, 0.1 * m.speed_mps)
    v.measured["speed_mps"] = got
    v.require(abs(got - m.speed_mps) <= tol, f"speed {got:.2f} m/s, asked {m.speed_mps:.2f} m/s")


def _check_gait(m: MotionIntent, s: _Sample, v: Verdict) -> None:
    """A runner's median moving speed is at least :data:`RUN_MPS`."""
    if m.gait == "run":
        got = _moving_speed(s)
        v.measured["speed_mps"] = got
        v.require(got >= RUN_MPS, f"moves at {got:.2f} m/s: not running")


def _check_stop(m: MotionIntent, s: _Sample, v: Verdict) -> None:
    """A standstill is reached and held (by the asked time; before the crosswalk with the front bumper short of it)."""
    if not m.stop:
        return
    k = _still_from(s.speed, s.xy, STILL_MPS if not s.pedestrian else 0.2)
    if v.require(k is not None, f"does not come to a standstill (end speed {s.v_end:.2f} m/s)"):
        assert k is not None
        v.measured["stopped_at_s"] = float(s.t[k])
        if m.stop_by_s is not None:
            v.require(s.t[k] <= m.stop_by_s + 1.0, f"standing only from {s.t[k]:.1f} s, asked by {m.stop_by_s:g} s")
        if m.stop_before == "crosswalk":
            valid = s.after.valid[s.row]
            _check_stop_before_crosswalk(s.truth, s.xy[-1], float(s.after.heading[s.row, valid][-1]),
                                         float(s.after.size[s.row, 0]), v)


def _check_longitudinal(m: MotionIntent, s: _Sample, v: Verdict) -> None:
    """``m.longitudinal`` (brake hard / accelerate / decelerate) on the measured speed."""
    v_start, v_end = s.v_start, s.v_end
    if m.longitudinal == "brake_hard":
        decel = -np.gradient(s.speed, s.t)
        v.measured["peak_decel_mps2"] = float(decel.max())
        v.require(decel.max() >= HARD_BRAKE_MPS2, f"peak deceleration {decel.max():.1f} m/s^2, hard braking is "
                  f">= {HARD_BRAKE_MPS2:g}")
        v.require(v_end <= 0.5 * v_start, f"speed only fell from {v_start:.1f} to {v_end:.1f} m/s")
    elif m.longitudinal == "accelerate":
        v.require(v_end >= v_start + max(1.5, 0.2 * v_start), f"speed {v_start:.1f} -> {v_end:.1f} m/s: not faster")
    elif m.longitudinal == "decelerate":
        v.require(v_end <= v_start - max(1.5, 0.2 * v_start), f"speed {v_start:.1f} -> {v_end:.1f} m/s: not slower")


def _label_verdict(m: MotionIntent, s: _Sample, name: str) -> tuple[Any, MotionLabel, bool, str] | None:
    """When ``m`` asks behaviour ``name`` (a ``registry.LABEL_CHECKED`` one): the asked value, the agent's label,
    whether the label shows the value (``BehaviourDecl.label_check``) and what it lacks in words; else ``None``."""
    check = _LABEL_CHECKS[name]
    asked = getattr(m, check.field)
    if not asked:
        return None
    assert s.label is not None  # a manoeuvre is asked: the sample is labelled
    return asked, s.label, check.shows(asked, s.label.motion), check.missing(asked)


def _check_reverse(m: MotionIntent, s: _Sample, v: Verdict) -> None:
    """Reversing is labelled reversing."""
    found = _label_verdict(m, s, "reverse")
    if found is not None:
        _, label, ok, missing = found
        v.require(ok, f"labelled {label.motion}, {missing}")


def _check_lane_change(m: MotionIntent, s: _Sample, v: Verdict) -> None:
    """A lane change is labelled a lane change to the asked side."""
    found = _label_verdict(m, s, "lane_change")
    if found is not None:
        _, label, ok, missing = found
        v.require(ok, f"labelled {label.motion}, {missing} (lateral {label.lateral_m:.1f} m)")


def _check_turn(m: MotionIntent, s: _Sample, v: Verdict) -> None:
    """A turn is labelled a turn to the asked side; going straight is labelled anything but a turn, with a heading
    change under 20 degrees."""
    found = _label_verdict(m, s, "turn")
    if found is None:
        return
    turn, label, ok, missing = found
    if turn == "straight":
        v.require(ok and abs(label.heading_change_deg) < 20.0,
                  f"labelled {label.motion}, heading change {label.heading_change_deg:.0f} deg: not straight")
    else:
        v.require(ok, f"labelled {label.motion} (heading change {label.heading_change_deg:.0f} deg), {missing}")


def _check_cross_street(m: MotionIntent, s: _Sample, v: Verdict) -> None:
    """Crossing is labelled crossing; jaywalking keeps at most a fifth of the road steps on a crosswalk."""
    found = _label_verdict(m, s, "cross_street")
    if found is None:
        return
    _, label, ok, missing = found
    v.require(ok, f"labelled {label.motion}, {missing}")
    if m.jaywalk:
        road = s.truth.layout.on_road(s.xy)
        share = float(s.truth.layout.in_crosswalk(s.xy[road]).mean()) if road.any() else 1.0
        v.measured["crosswalk_share"] = share
        v.require(share <= 0.2, f"{share:.0%} of the road steps on a crosswalk: not jaywalking")


def _check_timing(m: MotionIntent, s: _Sample, v: Verdict) -> None:
    """A delay: standing until it is over, then moving along the original path."""
    if m.delay_s is not None:
        _check_delay(s.truth, m.delay_s, s.before, s.after, s.object_id, s.speed, s.pedestrian, v)


#: The motion checks, in the order their failures are reported: (behaviour name, its check).
MOTION_CHECKS: tuple[tuple[str, MotionCheck], ...] = (
    ("speed", _check_speed), ("gait", _check_gait), ("stop", _check_stop), ("longitudinal", _check_longitudinal),
    ("reverse", _check_reverse), ("lane_change", _check_lane_change), ("turn", _check_turn),
    ("cross_street", _check_cross_street), ("timing", _check_timing),
)
#: Behaviours the benchmark asks no motion check of, and why.
UNCHECKED: dict[str, str] = {
    "follow": "the benchmark's prompts do not ask for following",
    "jaywalk": "a jaywalk is checked with the street crossing",
    "lateral_offset": "the benchmark's prompts do not ask for sideways shifts",
}


def _check_motion(truth: SceneTruth, m: MotionIntent, before: AgentStates, after: AgentStates, object_id: str,
                  v: Verdict) -> None:
    """The :data:`MOTION_CHECKS` of ``m`` on one edited agent (at least 5 valid steps)."""
    row = after.index(object_id)
    valid = after.valid[row]
    if not v.require(valid.sum() >= 5, f"{object_id} exists at {int(valid.sum())} steps only"):
        return
    t, xy = after.times[valid], after.xy[row, valid]
    speed = measured_speed(after, row)[valid]
    v_start, v_end = _edge(speed, t, 0.3, False), _edge(speed, t, 0.5, True)
    v.measured.update(v_start=v_start, v_end=v_end)
    label: MotionLabel | None = None
    if _manoeuvre_asked(m):
        label = motion_label(truth, after, row)
        v.measured["heading_change_deg"] = label.heading_change_deg
        v.note(f"labelled {label.motion}")
    sample = _Sample(truth, before, after, object_id, row, t, xy, speed, after.categories[row] == "pedestrian",
                     v_start, v_end, label)
    for _, check in MOTION_CHECKS:
        check(m, sample, v)


def _check_stop_before_crosswalk(truth: SceneTruth, xy: np.ndarray, heading: float, length: float,
                                 v: Verdict) -> None:
    pos = truth.road_position(xy, heading)
    if not v.require(pos.arm is not None and pos.inbound is True,
                     f"stopped in the {pos.region}{'' if pos.arm is None else ' driving away'}, not before a "
                     "crosswalk"):
        return
    assert pos.arm is not None
    front = pos.along - length / 2.0
    gap = front - truth.layout.crosswalk_range(pos.arm)[1]
    v.measured["crosswalk_gap_m"] = gap
    v.require(-0.3 <= gap <= 12.0, f"front bumper {gap:.1f} m before the crosswalk")


def _check_delay(truth: SceneTruth, delay: float, before: AgentStates, after: AgentStates, object_id: str,
                 speed: np.ndarray, pedestrian: bool, v: Verdict) -> None:
    del truth
    i, j = before.index(object_id), after.index(object_id)
    valid = after.valid[j]
    t, xy = after.times[valid], after.xy[j, valid]
    early = t <= delay - 0.2
    log_moved = float(np.linalg.norm(before.xy[i, before.valid[i]][-1] - before.xy[i, before.valid[i]][0]))
    if early.any() and log_moved > 1.0:
        drift = float(np.linalg.norm(xy[early] - xy[0], axis=1).max())
        v.measured["drift_before_delay_m"] = drift
        v.require(drift <= STILL_DRIFT_M and np.abs(speed[early]).max() <= STILL_MPS + 0.2,
                  f"moves {drift:.1f} m before the delay of {delay:g} s is over")
    moved = float(np.linalg.norm(xy[-1] - xy[0]))
    v.measured["moved_m"] = moved
    v.require(moved > 1.0 or log_moved <= 1.0, f"moves {moved:.1f} m in total after the delay")
    off, kept = _path_kept(before, after, object_id, WALK_PATH_TOL_M if pedestrian else PATH_TOL_M)
    v.measured["off_path_m"] = off
    v.require(kept, f"leaves its path by {off:.1f} m")


def _check_path_kept(before: AgentStates, after: AgentStates, object_id: str, m: MotionIntent, v: Verdict) -> None:
    """Speed-only edits keep the agent on its original path."""
    if _manoeuvre_asked(m) or m.delay_s is not None:
        return
    i, j = before.index(object_id), after.index(object_id)
    path = before.xy[i, before.valid[i]]
    if len(path) < 2 or np.linalg.norm(path[-1] - path[0]) < 1.0:
        return
    off, kept = _path_kept(before, after, object_id,
                           WALK_PATH_TOL_M if after.categories[j] == "pedestrian" else PATH_TOL_M)
    v.measured["off_path_m"] = off
    v.require(kept, f"leaves its path by {off:.1f} m")


def _path_kept(before: AgentStates, after: AgentStates, object_id: str, tol: float) -> tuple[float, bool]:
    """``(largest distance of the agent's new positions from its logged path, m; whether it kept to it)``: every
    position within ``tol`` of the path, or, past the path's end, of its straight continuation (a faster agent
    runs on beyond it: only the part within it is comparable); a pedestrian may be up to
    :data:`PASSING_ASIDE_M` off while passing another pedestrian."""
    i, j = before.index(object_id), after.index(object_id)
    path = before.xy[i, before.valid[i]]
    steps = np.flatnonzero(after.valid[j])
    xy = after.xy[j, steps]
    off = _path_distance(xy, path)
    deviation = np.minimum(off, _across_beyond_end(path, xy))
    allowed = np.full(len(steps), tol)
    if after.categories[j] == "pedestrian":
        allowed[_passing_someone(after, j, steps)] = max(tol, PASSING_ASIDE_M)
    return float(off.max(initial=0.0)), bool(np.all(deviation <= allowed))


def _passing_someone(states: AgentStates, row: int, steps: np.ndarray) -> np.ndarray:
    """``[K]`` whether another pedestrian is within :data:`PASSING_NEAR_M` of agent ``row`` at each of ``steps``."""
    others = np.array([r != row and c == "pedestrian" for r, c in enumerate(states.categories)])
    if not others.any():
        return np.zeros(len(steps), dtype=bool)
    gap = np.linalg.norm(states.xy[others][:, steps] - states.xy[row, steps][None], axis=2)  # [O, K]
    return ((gap <= PASSING_NEAR_M) & states.valid[others][:, steps]).any(axis=0)


def _across_beyond_end(path: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """``[K]`` how far each point lies to the side of ``path`` 's straight continuation past its end, along its
    last heading (the direction of its last ``END_DIRECTION_M``: a log that ends standing repeats its last
    point); ``inf`` for points not past the end."""
    out = np.full(len(xy), np.inf)
    end = path[-1]
    back = np.flatnonzero(np.linalg.norm(path - end, axis=1) >= END_DIRECTION_M)
    if not back.size:
        return out
    direction = end - path[back[-1]]
    direction = direction / float(np.linalg.norm(direction))
    rel = xy - end
    past = rel @ direction > 0
    out[past] = np.abs(rel[past, 0] * direction[1] - rel[past, 1] * direction[0])
    return out


# ---------------------------------------------------------------------------------------------- entry point
def check_states(truth: SceneTruth, intent: EditIntent, obs: EditObservation) -> CheckResult:
    """Check a carried-out edit on the agents before and after (module docstring).

    A refused or infeasible prompt is judged by :func:`check_refusal`, not here.
    """
    v = Verdict()
    if not obs.carried_out:
        return CheckResult(False, f"refused ({obs.refused}): {obs.message}")
    before, after = obs.before, obs.after
    assert before is not None and after is not None
    changes = state_changes(before, after)
    acting = _check_who(intent, before, after, changes, v)
    if intent.op == "insert" and len(acting) == (intent.asset.count if intent.asset else 1):
        _check_placement(truth, intent, after, acting, v)
    if intent.motion is not None:
        for object_id in acting:
            _check_motion(truth, intent.motion, before, after, object_id, v)
            if intent.op == "modify":
                _check_path_kept(before, after, object_id, intent.motion, v)
    return v.result()


def check_refusal(intent: EditIntent, obs: EditObservation) -> CheckResult:
    """An infeasible prompt passes when refused (any reason; whether it is an expected one is reported)."""
    if obs.refused is None:
        return CheckResult(False, "carried out an infeasible request" + (f": {obs.message}" if obs.message else ""))
    expected = obs.refused in intent.expected_refusals
    return CheckResult(True, f"refused ({obs.refused}{'' if expected else ', unexpected reason'}): {obs.message}",
                       {"expected_reason": float(expected)})


__all__ = ["ALIGN_DEG", "MOTION_CHECKS", "UNCHECKED", "CheckResult", "HARD_BRAKE_MPS2", "IN_LANE_M", "NEXT_TO_M",
           "RUN_MPS", "STILL_MPS", "Verdict",
           "check_refusal", "check_states", "edited_trajectory", "footprint_gap", "measured_speed", "motion_label"]
