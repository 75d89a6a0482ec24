"""Per-frame facts of every movable object of a log: what the description's clauses are checked against.

For each object and log frame (``-1`` / ``False`` where the object is absent):

* ``motion``: the auto-labeller's motion class (``language.motion_labels.label_trajectory``) of the
  trajectory window of ``±half_window_s`` around the frame, so a car that turns only in frames 20-35 is
  ``turning_*`` there and ``going_straight`` elsewhere. Windows use ``WINDOW_THRESHOLDS`` (a turn of a
  2 s window needs 30 degrees, not the whole log's 45);
* ``sector``: ``motion_labels.location_sector`` of the box centre in the ego frame of that frame;
* contexts (several may hold): in a crosswalk, at the intersection, on the sidewalk, by the curb (a
  vehicle off its lane), oncoming (heading against the ego's), on the road (on the drivable area);
* ego-frame position and heading, for relations and the ego lane.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simsplat_core.geometry import wrap_angle
from simsplat_core.language.motion_labels import (
    LabelThresholds,
    label_trajectory,
    location_sector,
    vehicle_off_lane,
)
from simsplat_core.scenario import vocabulary as voc
from simsplat_core.scenario.map_context import MapContext
from simsplat_core.scenario.trajectory import ObjectTrajectory, ego_yaw, log_trajectories, to_ego_frame
from simsplat_core.types import SceneLog

#: Thresholds of the window labels (shorter than a whole log: smaller turns and lane shifts count).
WINDOW_THRESHOLDS = LabelThresholds(turn_deg=30.0, lane_change_m=1.0)
#: Context classes, the column order of ``ObjectFrames.contexts``.
CONTEXTS: tuple[str, ...] = voc.LOCATION_CONTEXT.names


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

    def context(self, name: str) -> np.ndarray:
        """``[F]`` bool: the map context ``name`` holds."""
        return self.contexts[:, CONTEXTS.index(name)]


def _window_motion(traj: ObjectTrajectory, ego_poses: np.ndarray, map_context: MapContext | None,
                   half_rows: int) -> np.ndarray:
    """``[T]`` motion class of the window of ``±half_rows`` rows around each row."""
    out = np.empty(len(traj), dtype=object)
    for row in range(len(traj)):
        window = traj.window(slice(max(row - half_rows, 0), min(row + half_rows + 1, len(traj))))
        out[row] = label_trajectory(window, ego_poses, map_context, WINDOW_THRESHOLDS).motion
    return out


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
                  half_window_s: float = 1.0) -> ObjectFrames:
    """Per-frame facts of one trajectory (``ego_poses`` ``[F, 4, 4]``; module docstring)."""
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
    xy[rows] = traj.xy
    for r, f in enumerate(rows):
        xy_ego[f] = to_ego_frame(traj.xy[r: r + 1], ego_poses[int(f)])[0]
        sector[f] = location_sector(xy_ego[f], WINDOW_THRESHOLDS)
    contexts = np.zeros((num_frames, len(CONTEXTS)), dtype=bool)
    contexts[rows] = _contexts(traj, ego_poses, map_context)
    heading = np.full(num_frames, np.nan)
    heading[rows] = traj.heading
    speed = np.zeros(num_frames)
    speed[rows] = traj.speed
    return ObjectFrames(traj.object_id, traj.category, traj.kind, present, motion, sector, contexts, xy, xy_ego,
                        heading, speed)


def log_frames(log: SceneLog, half_window_s: float = 1.0) -> dict[str, ObjectFrames]:
    """``object_id -> ObjectFrames`` of every movable object of ``log`` with at least two boxes."""
    map_context = MapContext.from_features(log.map_features) if log.map_features else None
    trajs = log_trajectories(log, map_context, min_frames=2)
    return {oid: object_frames(t, log.num_frames, log.ego_poses, map_context, half_window_s)
            for oid, t in trajs.items()}
