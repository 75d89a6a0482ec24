"""Per-frame facts of every movable object of a log: what the description's clauses are checked against.

For each object and log frame (``-1`` / ``False`` where the object is absent):

* ``motion``: the auto-labeller's motion class (``language.motion_labels.motion_class``) of the
  trajectory window of ``±half_window_s`` around the frame, so a car that turns only in frames 20-35 is
  ``turning_*`` there and ``going_straight`` elsewhere. Windows use ``WINDOW_THRESHOLDS`` (a turn of a
  2 s window needs 30 degrees, not the whole log's 45);
* ``sector``: ``motion_labels.location_sector`` of the box centre in the ego frame of that frame;
* contexts (several may hold): in a crosswalk, at the intersection, on the sidewalk, by the curb (a
  vehicle off its lane), oncoming (heading against the ego's), on the road (on the drivable area);
* ego-frame position and heading, for relations; the position along and beside the ego's own path ahead
  (``EgoPath``: the ego's future poses of the log, then straight on from its last pose), for "our lane":
  through a turn the ego's lane bends with its path, not with the heading it has now;
* a deceleration that ends in a halt is ``stopping`` over all of it (``mark_halts``): the ±1 s window
  labels call only its last second ``stopping`` and the rest ``slowing_down``.

The ego is an object of its own (``EGO_ID``, ``ego_trajectory``): its motion from its poses by the same window
rules, so "while we turn left" or "a car following us" are answered like any other agent.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from simsplat_core.geometry import wrap_angle
from simsplat_core.language.motion_labels import (
    LabelThresholds,
    location_sector,
    motion_class,
    vehicle_off_lane,
)
from simsplat_core.scenario import vocabulary as voc
from simsplat_core.scenario.agents import EGO_ID
from simsplat_core.scenario.geometry import segment_distances
from simsplat_core.scenario.map_context import MapContext
from simsplat_core.scenario.trajectory import (
    ObjectTrajectory,
    ego_yaw,
    log_trajectories,
    smoothed_velocity,
    to_ego_frame,
)
from simsplat_core.types import SceneLog

#: Thresholds of the window labels (shorter than a whole log: smaller turns and lane shifts count).
WINDOW_THRESHOLDS = LabelThresholds(turn_deg=30.0, lane_change_m=1.0)
#: Context classes, the column order of ``ObjectFrames.contexts``.
CONTEXTS: tuple[str, ...] = voc.LOCATION_CONTEXT.names
#: How far ahead the ego's path is followed, metres.
EGO_PATH_M = 60.0


@dataclass(frozen=True)
class ObjectFrames:
    """Per-frame facts of one object over the ``F`` log frames.

    Attributes:
        object_id, category, kind: from the log (``kind``: ``vehicle`` / ``pedestrian``).
        present: ``[F]`` the object has a box in the frame.
        motion: ``[F]`` object array of motion class names (``""`` where absent).
        sector: ``[F]`` object array of sector names.
        contexts: ``[F, len(CONTEXTS)]`` bool.
        xy: ``[F, 2]`` world centre (``nan`` where absent); ``xy_ego`` ``[F, 2]`` in that frame's ego frame.
        heading: ``[F]`` world yaw; ``speed`` ``[F]`` smoothed m/s.
        lane_along, lane_offset: ``[F]`` metres along the ego's path ahead of that frame (negative: behind the
            ego) and signed metres beside it (positive: left), ``nan`` where absent (``EgoPath.locate``).
        frame_s: seconds between log frames.
    """

    object_id: str
    category: str
    kind: str
    present: np.ndarray
    motion: np.ndarray
    sector: np.ndarray
    contexts: np.ndarray
    xy: np.ndarray
    xy_ego: np.ndarray
    heading: np.ndarray
    speed: np.ndarray
    lane_along: np.ndarray
    lane_offset: np.ndarray
    frame_s: float = 0.1

    def context(self, name: str) -> np.ndarray:
        """``[F]`` bool: the map context ``name`` holds."""
        return self.contexts[:, CONTEXTS.index(name)]


class EgoPath:
    """The ego's path ahead of every log frame: its poses from that frame on, then straight on from the last one,
    up to ``ahead_m`` metres (``ego_poses`` ``[F, 4, 4]``)."""

    def __init__(self, ego_poses: np.ndarray, ahead_m: float = EGO_PATH_M) -> None:
        xy = np.asarray(ego_poses)[:, :2, 3]
        yaw = ego_yaw(ego_poses[-1])
        self._xy = xy
        self._tail = xy[-1] + ahead_m * np.array([np.cos(yaw), np.sin(yaw)])
        self._ahead_m = ahead_m

    def locate(self, frame: int, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(along, offset)`` ``[N]`` of world ``points`` ``[N, 2]`` against the path ahead of ``frame``: metres
        along it (projections before its start or past its end run on along its first / last segment) and
        signed metres beside it (positive: left of the path)."""
        pts = np.r_[self._xy[frame:], self._tail[None]]
        step = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        keep = np.r_[True, step > 1e-6]  # a standing ego repeats its position
        pts = pts[keep]
        a, b = pts[:-1], pts[1:]
        length = np.linalg.norm(b - a, axis=1)
        s0 = np.r_[0.0, np.cumsum(length)[:-1]]
        inside = s0 < self._ahead_m
        a, b, length, s0 = a[inside], b[inside], length[inside], s0[inside]
        p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        k = np.argmin(segment_distances(p, a, b), axis=1)  # [N] nearest segment
        u = (b[k] - a[k]) / length[k, None]
        rel = p - a[k]
        t = (rel * u).sum(axis=1)
        t = np.where((k == 0) | (k == len(a) - 1), t, np.clip(t, 0.0, length[k]))
        return s0[k] + t, u[:, 0] * rel[:, 1] - u[:, 1] * rel[:, 0]


def mark_halts(motion: np.ndarray, speed: np.ndarray, moving_mps: float = WINDOW_THRESHOLDS.moving_mps) -> np.ndarray:
    """``motion`` ``[T]`` with every run of ``slowing_down`` / ``stopping`` rows that holds a ``stopping`` row made
    ``stopping`` while the object still moves (``speed`` ``[T]`` m/s) and ``stopped`` once it does not."""
    out = motion.copy()
    braking = np.isin(motion, (voc.SLOWING_DOWN, voc.STOPPING))
    row = 0
    while row < len(out):
        if not braking[row]:
            row += 1
            continue
        end = row
        while end < len(out) and braking[end]:
            end += 1
        if (motion[row:end] == voc.STOPPING).any():
            out[row:end] = np.where(speed[row:end] >= moving_mps, voc.STOPPING, voc.STOPPED)
        row = end
    return out


def _window_motion(traj: ObjectTrajectory, ego_poses: np.ndarray, map_context: MapContext | None,
                   half_rows: int) -> np.ndarray:
    """``[T]`` motion class of the window of ``±half_rows`` rows around each row (halts marked, ``mark_halts``);
    a window cut short by the trajectory's ends asks for a turn in proportion to its length (half a window
    sees half a turn)."""
    out = np.empty(len(traj), dtype=object)
    size = 2 * half_rows + 1
    for row in range(len(traj)):
        rows = slice(max(row - half_rows, 0), min(row + half_rows + 1, len(traj)))
        frac = (rows.stop - rows.start) / size
        th = WINDOW_THRESHOLDS if frac >= 1.0 else replace(
            WINDOW_THRESHOLDS, turn_deg=WINDOW_THRESHOLDS.turn_deg * max(frac, 0.5))
        out[row] = motion_class(traj.window(rows), ego_poses, map_context, th)
    return mark_halts(out, traj.speed) if traj.kind == voc.VEHICLE else out


def _contexts(traj: ObjectTrajectory, ego_poses: np.ndarray, map_context: MapContext | None) -> np.ndarray:
    """``[T, len(CONTEXTS)]`` bool map contexts of every row (module docstring)."""
    out = np.zeros((len(traj), len(CONTEXTS)), dtype=bool)
    th = WINDOW_THRESHOLDS
    if traj.facts is not None and map_context is not None:
        f = traj.facts
        out[:, CONTEXTS.index(voc.ON_THE_CROSSWALK)] = f.in_crosswalk & ~f.on_sidewalk
        out[:, CONTEXTS.index(voc.AT_THE_INTERSECTION)] = f.at_intersection
        sidewalk = f.on_sidewalk.copy()
        if traj.kind == voc.PEDESTRIAN and not map_context.has_sidewalks and map_context.has_drivable:
            sidewalk |= ~f.on_drivable
        out[:, CONTEXTS.index(voc.ON_THE_SIDEWALK)] = sidewalk
        if traj.kind == voc.VEHICLE:
            out[:, CONTEXTS.index(voc.BY_THE_CURB)] = vehicle_off_lane(f, map_context, th)
        out[:, CONTEXTS.index(voc.ON_THE_ROAD)] = f.on_drivable if map_context.has_drivable else True
    else:
        out[:, CONTEXTS.index(voc.ON_THE_ROAD)] = True
    if traj.kind == voc.VEHICLE:
        ego_h = np.array([ego_yaw(ego_poses[int(f)]) for f in traj.frame_idx])
        rel = np.abs(np.rad2deg(wrap_angle(traj.heading - ego_h)))
        out[:, CONTEXTS.index(voc.IN_THE_ONCOMING_LANE)] = (rel >= th.oncoming_deg) & (traj.speed >= th.moving_mps)
    return out


def object_frames(traj: ObjectTrajectory, num_frames: int, ego_poses: np.ndarray, map_context: MapContext | None,
                  half_window_s: float = 1.0, ego_path: EgoPath | None = None) -> ObjectFrames:
    """Per-frame facts of one trajectory (``ego_poses`` ``[F, 4, 4]``; module docstring)."""
    path = ego_path or EgoPath(ego_poses)
    rows = traj.frame_idx
    dt = float(np.median(np.diff(traj.t))) if len(traj) > 1 else 0.1
    half_rows = max(int(round(half_window_s / max(dt, 1e-6))), 1)
    present = np.zeros(num_frames, dtype=bool)
    present[rows] = True
    motion = np.full(num_frames, "", dtype=object)
    motion[rows] = _window_motion(traj, ego_poses, map_context, half_rows)
    sector = np.full(num_frames, "", dtype=object)
    xy = np.full((num_frames, 2), np.nan)
    xy_ego = np.full((num_frames, 2), np.nan)
    lane = np.full((num_frames, 2), np.nan)
    xy[rows] = traj.xy
    for r, f in enumerate(rows):
        xy_ego[f] = to_ego_frame(traj.xy[r: r + 1], ego_poses[int(f)])[0]
        sector[f] = location_sector(xy_ego[f], WINDOW_THRESHOLDS)
        along, offset = path.locate(int(f), traj.xy[r: r + 1])
        lane[f] = along[0], offset[0]
    contexts = np.zeros((num_frames, len(CONTEXTS)), dtype=bool)
    contexts[rows] = _contexts(traj, ego_poses, map_context)
    heading = np.full(num_frames, np.nan)
    heading[rows] = traj.heading
    speed = np.zeros(num_frames)
    speed[rows] = traj.speed
    return ObjectFrames(traj.object_id, traj.category, traj.kind, present, motion, sector, contexts, xy, xy_ego,
                        heading, speed, lane[:, 0], lane[:, 1], dt)


def ego_trajectory(log: SceneLog, map_context: MapContext | None, half_window_s: float = 0.5) -> ObjectTrajectory:
    """The ego as a vehicle trajectory over every log frame (positions and yaw of ``log.ego_poses``)."""
    t = (log.timestamps_us - log.timestamps_us[0]).astype(np.float64) * 1e-6
    xy = np.asarray(log.ego_poses[:, :2, 3], dtype=np.float64)
    heading = np.unwrap(np.array([ego_yaw(p) for p in log.ego_poses]))
    return ObjectTrajectory(EGO_ID, "vehicle", voc.VEHICLE, np.arange(log.num_frames), t, xy, heading,
                            smoothed_velocity(t, xy, half_window_s), np.ones(log.num_frames, dtype=bool),
                            map_context.facts(xy, heading) if map_context is not None else None)


def log_frames(log: SceneLog, half_window_s: float = 1.0) -> dict[str, ObjectFrames]:
    """``object_id -> ObjectFrames`` of every movable object of ``log`` with at least two boxes, and of the ego
    (``EGO_ID``, last)."""
    map_context = MapContext.from_features(log.map_features) if log.map_features else None
    trajs = log_trajectories(log, map_context, min_frames=2)
    path = EgoPath(log.ego_poses)
    out = {oid: object_frames(t, log.num_frames, log.ego_poses, map_context, half_window_s, path)
           for oid, t in trajs.items()}
    if log.num_frames > 1:
        out[EGO_ID] = object_frames(ego_trajectory(log, map_context), log.num_frames, log.ego_poses, map_context,
                                    half_window_s, path)
    return out
