"""Rule-based motion and location auto-labels from trajectories, ego poses and (optionally) the map.

These labels supervise the trajectory encoder (``alignment.motion_training``) and define the classes of the
grounding evaluation. Class names and their phrasings are in ``vocabulary.py``.

Vehicles (also cyclists and other movers), decided in this order:

1. *stationary* (median smoothed speed below ``moving_mps`` and all centres within ``static_spread_m``
   of their median; robust to the jitter of annotated boxes): ``parked`` when off the drivable area or
   ``curb_lane_m`` away from every lane centre line (at the kerb), else ``stopped``;
2. ``reversing``: more distance covered backwards (velocity against the box heading) than forwards,
   at least ``reverse_m``;
3. ``turning_left`` / ``turning_right``: heading change (mean of the last vs the first ``edge_s``
   seconds, unwrapped; positive = counter-clockwise = left) beyond ``turn_deg``;
4. ``changing_lane_left`` / ``changing_lane_right``: lateral displacement relative to the lanes beyond
   ``lane_change_m`` (positive = left; see ``road_lateral_displacement``: measured against the nearest
   aligned lane centre line, so following a curved road is not a lane change; without lanes against
   the initial heading); with lanes the vehicle must also have left its lane. The heading change
   must stay below ``veer_deg``;
5. speed profile, with ``v0`` / ``v1`` the mean speed over the first / last ``edge_s`` seconds:
   ``stopping`` (``v0 > from_mps`` and ``v1 < stop_mps``), ``slowing_down`` (``v1 < slow_ratio *
   v0``), ``speeding_up`` (``v0 < slow_ratio * v1``, ``v1 > from_mps``);
6. otherwise ``going_straight``.

Pedestrians: ``standing`` (stationary as above); ``crossing*`` when at least ``crossing_road_frac`` of
the moving frames are on the drivable area (without a drivable area in the map: when the walk is
mostly lateral to the ego, see below); the direction is the displacement between the first and last
moving positions in the ego frame at the reference frame: ``crossing_left_to_right`` when mostly
lateral (``|dy| > lateral_ratio * |dx|``) towards negative ``y`` (the ego's right),
``crossing_right_to_left`` towards positive ``y``, plain ``crossing`` when it is not mostly lateral
(e.g. crossing a side street parallel to the ego's path); otherwise ``walking_along``.

Location at the reference frame (median visible frame) has two parts:

* sector: angle of the object centre in the ego frame: ``in_front_of_ego`` within ``front_deg`` of
  straight ahead, ``behind_ego`` beyond ``behind_deg``, else ``left_of_ego`` / ``right_of_ego``;
* context (first match): ``on_the_crosswalk`` (pedestrian in a crosswalk, not on a sidewalk),
  ``at_the_intersection``, ``on_the_sidewalk`` (in a sidewalk polygon; for pedestrians in maps without
  sidewalks: off the drivable area), ``by_the_curb`` (vehicle off the drivable area or ``curb_lane_m``
  away from lane centres), ``in_the_oncoming_lane`` (vehicle heading within ``180 - oncoming_deg`` of
  opposite to the ego), else ``on_the_road``.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from simsplat_core.geometry import wrap_angle
from simsplat_core.scenario import vocabulary as voc
from simsplat_core.scenario.map_context import MapContext, MapFacts
from simsplat_core.scenario.trajectory import ObjectTrajectory, ego_yaw, log_trajectories, to_ego_frame
from simsplat_core.types import SceneLog

logger = logging.getLogger(__name__)

#: A nearest-lane switch at least this large (metres) is a move into the neighbouring lane.
MIN_LANE_WIDTH_M = 2.0
#: Starting or ending this far (metres) off a lane centre line is a lane change under way.
OFF_CENTRE_M = 1.5


@dataclass(frozen=True)
class LabelThresholds:
    """Thresholds of the rules in the module docstring (metres, seconds, m/s, degrees)."""

    moving_mps: float = 0.5
    static_spread_m: float = 1.5
    reverse_m: float = 2.0
    edge_s: float = 0.3
    turn_deg: float = 45.0
    veer_deg: float = 20.0
    lane_change_m: float = 1.5
    from_mps: float = 2.0
    stop_mps: float = 1.0
    slow_ratio: float = 0.65
    crossing_road_frac: float = 0.25
    lateral_ratio: float = 1.5
    curb_lane_m: float = 2.2
    front_deg: float = 45.0
    behind_deg: float = 135.0
    oncoming_deg: float = 135.0


@dataclass(frozen=True)
class MotionLabel:
    """Auto-labels of one object (or of one window of its trajectory).

    Attributes:
        object_id: the object.
        kind: ``"vehicle"`` or ``"pedestrian"`` (which motion vocabulary ``motion`` is from).
        motion: motion class name.
        sector: ``LOCATION_SECTOR`` class name.
        context: ``LOCATION_CONTEXT`` class name.
        ref_frame: log frame the location refers to.
        heading_change_deg, lateral_m, v_start, v_end: the measured quantities the rules used.
    """

    object_id: str
    kind: str
    motion: str
    sector: str
    context: str
    ref_frame: int
    heading_change_deg: float = 0.0
    lateral_m: float = 0.0
    v_start: float = 0.0
    v_end: float = 0.0

    @property
    def location(self) -> tuple[str, str]:
        return (self.sector, self.context)


def _edge_mean(values: np.ndarray, t: np.ndarray, edge_s: float, first: bool) -> float:
    """Mean of ``values`` over the first (or last) ``edge_s`` seconds (at least one row)."""
    mask = (t <= t[0] + edge_s) if first else (t >= t[-1] - edge_s)
    return float(np.mean(values[mask], axis=0))


def is_stationary(traj: ObjectTrajectory, th: LabelThresholds) -> bool:
    """Median speed below ``moving_mps`` and every centre within ``static_spread_m`` of the median centre."""
    spread = np.linalg.norm(traj.xy - np.median(traj.xy, axis=0), axis=1).max(initial=0.0)
    return bool(spread < th.static_spread_m and np.median(traj.speed) < th.moving_mps)


def heading_change_deg(traj: ObjectTrajectory, th: LabelThresholds) -> float:
    """Signed heading change, degrees (positive = left), between the first and last ``edge_s`` seconds."""
    return float(
        np.rad2deg(
            _edge_mean(traj.heading, traj.t, th.edge_s, False) - _edge_mean(traj.heading, traj.t, th.edge_s, True)
        )
    )


def road_lateral_displacement(
    traj: ObjectTrajectory, max_lateral_mps: float = 2.0, noise_m: float = 0.1
) -> tuple[float, bool]:
    """``(metres moved to the left relative to the lanes, whether it left its lane)``.

    With lanes (``MapFacts.lane_offset`` known in at least half the rows) the displacement sums the
    frame-to-frame changes of the signed offset from the nearest aligned lane centre line, skipping
    rows without a lane and changes faster than a vehicle can move sideways (``max_lateral_mps * dt
    + noise_m``: the nearest lane switched). Being position-based it does not drift on curved roads.
    The vehicle *left its lane* when the skipped jumps add up to at least ``MIN_LANE_WIDTH_M`` against
    the direction of motion (passing the line between two lanes: moving left, the offset jumps from
    about ``+w/2`` to ``-w/2``, possibly over a few frames where connectors overlap) or when it starts or
    ends at least ``OFF_CENTRE_M`` off a lane centre on that side (a lane change under way when the log
    starts or ends). Without lanes the displacement is along the left normal of the initial heading and
    leaving the lane cannot be checked (``True``).
    """
    if traj.facts is None or len(traj) < 2 or np.mean(np.isfinite(traj.facts.lane_offset)) < 0.5:
        h0 = traj.heading[0]
        return float((traj.xy[-1] - traj.xy[0]) @ np.array([-np.sin(h0), np.cos(h0)])), True
    offset = traj.facts.lane_offset
    step = np.diff(offset)
    finite = np.isfinite(step)
    smooth = finite & (np.abs(step) <= max_lateral_mps * np.diff(traj.t) + noise_m)
    lateral = float(step[smooth].sum())
    sign = np.sign(lateral)
    switched = bool(-sign * step[finite & ~smooth].sum() >= MIN_LANE_WIDTH_M)
    known = offset[np.isfinite(offset)]
    off_centre = bool(sign * known[-1] >= OFF_CENTRE_M or -sign * known[0] >= OFF_CENTRE_M)
    return lateral, switched or off_centre


def _backward_forward_m(traj: ObjectTrajectory) -> tuple[float, float]:
    fwd = traj.velocity[:, 0] * np.cos(traj.heading) + traj.velocity[:, 1] * np.sin(traj.heading)
    dt = np.gradient(traj.t) if len(traj) > 1 else np.zeros(1)
    return float(np.sum(np.maximum(-fwd, 0.0) * dt)), float(np.sum(np.maximum(fwd, 0.0) * dt))


def vehicle_off_lane(facts: MapFacts, map_context: MapContext, th: LabelThresholds) -> np.ndarray:
    """``[N]`` bool: a vehicle at these points is off the drivable area or ``curb_lane_m`` away from every
    lane centre line, i.e. at the kerb."""
    off = np.isfinite(facts.lane_dist) & (facts.lane_dist > th.curb_lane_m)
    if map_context.has_drivable:
        off |= ~facts.on_drivable
    return off


def vehicle_motion(
    traj: ObjectTrajectory, map_context: MapContext | None, th: LabelThresholds
) -> tuple[str, float, float, float, float]:
    """``(class, heading change deg, lateral m, v_start, v_end)`` of a vehicle trajectory."""
    speed = traj.speed
    v0 = _edge_mean(speed, traj.t, th.edge_s, True)
    v1 = _edge_mean(speed, traj.t, th.edge_s, False)
    if is_stationary(traj, th):
        parked = (
            traj.facts is not None
            and map_context is not None
            and bool(np.mean(vehicle_off_lane(traj.facts, map_context, th)) >= 0.5)
        )
        return (voc.PARKED if parked else voc.STOPPED), 0.0, 0.0, v0, v1
    dh = heading_change_deg(traj, th)
    lat, left_lane = road_lateral_displacement(traj)
    back, fwd = _backward_forward_m(traj)
    if back >= th.reverse_m and back > fwd:
        return voc.REVERSING, dh, lat, v0, v1
    if dh > th.turn_deg:
        return voc.TURNING_LEFT, dh, lat, v0, v1
    if dh < -th.turn_deg:
        return voc.TURNING_RIGHT, dh, lat, v0, v1
    if abs(dh) < th.veer_deg and abs(lat) > th.lane_change_m and left_lane:
        return (voc.CHANGING_LANE_LEFT if lat > 0 else voc.CHANGING_LANE_RIGHT), dh, lat, v0, v1
    if v0 > th.from_mps and v1 < th.stop_mps:
        return voc.STOPPING, dh, lat, v0, v1
    if v0 > th.from_mps and v1 < th.slow_ratio * v0:
        return voc.SLOWING_DOWN, dh, lat, v0, v1
    if v1 > th.from_mps and v0 < th.slow_ratio * v1:
        return voc.SPEEDING_UP, dh, lat, v0, v1
    return voc.GOING_STRAIGHT, dh, lat, v0, v1


def pedestrian_motion(
    traj: ObjectTrajectory, ego_poses: np.ndarray, map_context: MapContext | None, th: LabelThresholds
) -> str:
    """Motion class of a pedestrian trajectory (``ego_poses`` ``[F, 4, 4]``)."""
    if is_stationary(traj, th):
        return voc.STANDING
    moving = traj.speed >= th.moving_mps
    if moving.sum() < 2:
        moving = np.ones(len(traj), dtype=bool)
    pose = ego_poses[int(traj.frame_idx[traj.reference_row()])]
    ends = to_ego_frame(traj.xy[moving][[0, -1]], pose)
    dx, dy = ends[1] - ends[0]
    lateral = abs(dy) > th.lateral_ratio * abs(dx)
    if traj.facts is not None and map_context is not None and map_context.has_drivable:
        crossing = np.mean(traj.facts.on_drivable[moving]) >= th.crossing_road_frac
    else:
        crossing = lateral
    if not crossing:
        return voc.WALKING_ALONG
    if not lateral:
        return voc.CROSSING
    return voc.CROSSING_LEFT_TO_RIGHT if dy < 0 else voc.CROSSING_RIGHT_TO_LEFT


def location_sector(xy_ego: np.ndarray, th: LabelThresholds) -> str:
    """Sector of an ego-frame point ``[2]``."""
    ang = np.rad2deg(np.arctan2(xy_ego[1], xy_ego[0]))
    if abs(ang) <= th.front_deg:
        return voc.IN_FRONT_OF_EGO
    if abs(ang) >= th.behind_deg:
        return voc.BEHIND_EGO
    return voc.LEFT_OF_EGO if ang > 0 else voc.RIGHT_OF_EGO


def location_context(
    traj: ObjectTrajectory, row: int, ego_pose: np.ndarray, map_context: MapContext | None, th: LabelThresholds
) -> str:
    """Map context of ``traj`` at ``row`` (see the module docstring for the order of the rules)."""
    facts = traj.facts.take(slice(row, row + 1)) if traj.facts is not None else None
    if facts is not None and map_context is not None:
        if traj.kind == "pedestrian" and facts.in_crosswalk[0] and not facts.on_sidewalk[0]:
            return voc.ON_THE_CROSSWALK
        if facts.at_intersection[0]:
            return voc.AT_THE_INTERSECTION
        if facts.on_sidewalk[0] or (
            traj.kind == "pedestrian"
            and not map_context.has_sidewalks
            and map_context.has_drivable
            and not facts.on_drivable[0]
        ):
            return voc.ON_THE_SIDEWALK
        if traj.kind == "vehicle" and vehicle_off_lane(facts, map_context, th)[0]:
            return voc.BY_THE_CURB
    if traj.kind == "vehicle":
        rel = abs(float(np.rad2deg(wrap_angle(traj.heading[row] - ego_yaw(ego_pose)))))
        if rel >= th.oncoming_deg:
            return voc.IN_THE_ONCOMING_LANE
    return voc.ON_THE_ROAD


def motion_class(traj: ObjectTrajectory, ego_poses: np.ndarray, map_context: MapContext | None,
                 thresholds: LabelThresholds) -> str:
    """The motion class alone of ``label_trajectory`` (no sector or context: windows searched frame by frame)."""
    if traj.kind == "pedestrian":
        return pedestrian_motion(traj, ego_poses, map_context, thresholds)
    return vehicle_motion(traj, map_context, thresholds)[0]


def label_trajectory(
    traj: ObjectTrajectory,
    ego_poses: np.ndarray,
    map_context: MapContext | None = None,
    thresholds: LabelThresholds | None = None,
) -> MotionLabel:
    """Motion and location labels of one trajectory (or trajectory window); ``ego_poses`` is ``[F, 4, 4]``."""
    th = thresholds or LabelThresholds()
    row = traj.reference_row()
    ref_frame = int(traj.frame_idx[row])
    pose = ego_poses[ref_frame]
    sector = location_sector(to_ego_frame(traj.xy[row : row + 1], pose)[0], th)
    context = location_context(traj, row, pose, map_context, th)
    if traj.kind == "pedestrian":
        v0 = _edge_mean(traj.speed, traj.t, th.edge_s, True)
        v1 = _edge_mean(traj.speed, traj.t, th.edge_s, False)
        motion = pedestrian_motion(traj, ego_poses, map_context, th)
        return MotionLabel(traj.object_id, traj.kind, motion, sector, context, ref_frame, 0.0, 0.0, v0, v1)
    motion, dh, lat, v0, v1 = vehicle_motion(traj, map_context, th)
    return MotionLabel(traj.object_id, traj.kind, motion, sector, context, ref_frame, dh, lat, v0, v1)


def label_trajectories(trajectories: Mapping[str, ObjectTrajectory], ego_poses: np.ndarray,
                       map_context: MapContext | None, thresholds: LabelThresholds | None = None
                       ) -> dict[str, MotionLabel]:
    """``object_id -> MotionLabel`` of already built trajectories (``ego_poses`` ``[F, 4, 4]``)."""
    return {oid: label_trajectory(traj, ego_poses, map_context, thresholds) for oid, traj in trajectories.items()}


def label_log(log: SceneLog, thresholds: LabelThresholds | None = None) -> dict[str, MotionLabel]:
    """Auto-labels of every movable object of ``log`` (static objects and signs are skipped)."""
    map_context = MapContext.from_features(log.map_features) if log.map_features else None
    trajectories = log_trajectories(log, map_context, min_frames=1)
    labels = label_trajectories(trajectories, log.ego_poses, map_context, thresholds)
    logger.debug("%s: labelled %d objects", log.seq_id, len(labels))
    return labels
