"""Captions derived from trajectory geometry: what an object looks like, how it moves, where it is.

Motion and location phrases are computed from a ``Track`` (and the ego poses and ``RoadLayout``),
never from the generator's intended behaviour, so a caption is true of the trajectory that was
actually produced. The same functions can describe any log whose layout is known, and tests use
them to check the stored captions.

Motion (vehicles): ``parked`` / ``stopped`` (never moves; at the kerb vs. in a lane), ``turning
left`` / ``turning right`` (unwrapped heading change beyond ``TURN_DEG``), ``veering left/right``
(between ``VEER_DEG`` and ``TURN_DEG``), ``changing lanes to the left/right`` (lateral displacement
relative to the initial heading beyond ``LANE_CHANGE_M``), ``coming to a stop``, ``slowing down``,
``speeding up``, ``going straight``.

Motion (pedestrians): ``standing``, ``crossing the street from left to right`` / ``from right to
left`` (relative to the ego at the reference frame) / ``crossing the street``, ``walking along the
sidewalk``, ``walking``.

Location at the reference frame (median visible frame): the ego-relative sector (``in front of
ego``, ``behind ego``, ``on the left of ego``, ``on the right of ego``; 45-degree boundaries) plus a
map context (``at the intersection``, ``on the crosswalk``, ``on the sidewalk``, ``by the curb``,
``in the oncoming lane``, ``on the road``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simsplat_core.geometry import yaw_of_rotation
from simsplat_core.types import Track
from simsplat_core.world.palette import article
from simsplat_core.world.road import INTERSECTION, OFFROAD, PARKING, SIDEWALK, TRAVEL, RoadLayout

STATIONARY_SPEED = 0.3  # m/s: below this everywhere (and almost no displacement) an object is not moving
STATIONARY_DISP = 0.5  # m
TURN_DEG = 60.0
VEER_DEG = 25.0
LANE_CHANGE_M = 1.5
STOP_FROM_SPEED = 2.0  # m/s: "coming to a stop" / "slowing down" need at least this initial speed
SLOW_RATIO = 0.65
CROSSING_ROAD_FRACTION = 0.25
FRONT_DEG = 45.0
BEHIND_DEG = 135.0
ONCOMING_DEG = 135.0


@dataclass(frozen=True)
class TrackDescription:
    """Motion and location phrases of one track and the frame the location refers to."""

    motion: str
    location: str
    ref_frame: int


def reference_frame(track: Track) -> int:
    """Frame a location caption refers to: the median visible frame, else the middle of the track."""
    frames = track.frame_idx[track.visible] if track.visible.any() else track.frame_idx
    return int(frames[(len(frames) - 1) // 2])


def _edge_speed(speed: np.ndarray, first: bool, n: int = 3) -> float:
    part = speed[:n] if first else speed[-n:]
    return float(np.mean(part))


def is_stationary(track: Track) -> bool:
    """True when the object never moves during the track."""
    disp = np.linalg.norm(track.center[:, :2] - track.center[0, :2], axis=1).max(initial=0.0)
    return bool(track.speed.max(initial=0.0) < STATIONARY_SPEED and disp < STATIONARY_DISP)


def heading_change_deg(track: Track) -> float:
    """Signed total heading change over the track in degrees (positive = counter-clockwise = left)."""
    h = np.unwrap(track.heading)
    return float(np.rad2deg(h[-1] - h[0]))


def lateral_displacement(track: Track) -> float:
    """Displacement from the first to the last centre, along the initial heading's left normal (metres)."""
    h0 = track.heading[0]
    normal = np.array([-np.sin(h0), np.cos(h0)])
    return float((track.center[-1, :2] - track.center[0, :2]) @ normal)


def ego_frame_xy(points_xy: np.ndarray, ego_pose: np.ndarray) -> np.ndarray:
    """``[N, 2]`` world xy expressed in the ego frame of ``ego_pose`` ``[4, 4]``."""
    rel = np.atleast_2d(points_xy) - ego_pose[:2, 3]
    yaw = float(yaw_of_rotation(ego_pose[:3, :3]))
    c, s = np.cos(yaw), np.sin(yaw)
    return np.stack([c * rel[:, 0] + s * rel[:, 1], -s * rel[:, 0] + c * rel[:, 1]], axis=1)


def describe_motion(track: Track, category: str, layout: RoadLayout, ego_poses: np.ndarray) -> str:
    """Motion phrase of a track (see the module docstring for the vocabulary)."""
    if category in ("static", "sign"):
        return "stationary"
    stationary = is_stationary(track)
    if category == "pedestrian":
        if stationary:
            return "standing"
        moving = track.speed >= STATIONARY_SPEED
        xy = track.center[moving, :2]
        on_road = layout.on_road(xy)
        if on_road.mean() >= CROSSING_ROAD_FRACTION:
            ref = reference_frame(track)
            pose = ego_poses[ref]
            a, b = ego_frame_xy(xy[[0, -1]], pose) if len(xy) > 1 else (np.zeros(2), np.zeros(2))
            delta = b - a
            if abs(delta[1]) > 1.5 * abs(delta[0]):
                return (
                    "crossing the street from left to right"
                    if delta[1] < 0
                    else "crossing the street from right to left"
                )
            return "crossing the street"
        if (layout.region(xy) == SIDEWALK).mean() >= 0.5:
            return "walking along the sidewalk"
        return "walking"
    # vehicles, cyclists, other
    if stationary:
        region = layout.region(track.center[:, :2].mean(axis=0)[None])[0]
        return "parked" if region in (PARKING, OFFROAD, SIDEWALK) else "stopped"
    dh = heading_change_deg(track)
    if dh > TURN_DEG:
        return "turning left"
    if dh < -TURN_DEG:
        return "turning right"
    if abs(dh) > VEER_DEG:
        return "veering left" if dh > 0 else "veering right"
    lat = lateral_displacement(track)
    if abs(lat) > LANE_CHANGE_M:
        return "changing lanes to the left" if lat > 0 else "changing lanes to the right"
    v_start, v_end = _edge_speed(track.speed, True), _edge_speed(track.speed, False)
    if v_start > STOP_FROM_SPEED and v_end < STATIONARY_SPEED:
        return "coming to a stop"
    if v_start > STOP_FROM_SPEED and v_end < SLOW_RATIO * v_start:
        return "slowing down"
    if v_end > STOP_FROM_SPEED and v_start < SLOW_RATIO * v_end:
        return "speeding up"
    return "going straight"


def ego_relation(xy: np.ndarray, ego_pose: np.ndarray) -> str:
    """Sector of world point ``xy`` ``[2]`` around the ego: front / behind / left / right."""
    q = ego_frame_xy(np.asarray(xy)[None], ego_pose)[0]
    ang = np.rad2deg(np.arctan2(q[1], q[0]))
    if abs(ang) <= FRONT_DEG:
        return "in front of ego"
    if abs(ang) >= BEHIND_DEG:
        return "behind ego"
    return "on the left of ego" if ang > 0 else "on the right of ego"


def map_context(xy: np.ndarray, heading: float, category: str, layout: RoadLayout, ego_pose: np.ndarray) -> str:
    """Map-based location phrase of a point (may be empty)."""
    p = np.asarray(xy, dtype=np.float64)[None]
    region = int(layout.region(p)[0])
    if category == "pedestrian" and layout.in_crosswalk(p)[0] and region != SIDEWALK:
        return "on the crosswalk"
    if region == INTERSECTION:
        return "at the intersection"
    if region == SIDEWALK:
        return "on the sidewalk"
    if region == PARKING:
        return "by the curb"
    if region == TRAVEL:
        if category in ("vehicle", "cyclist", "other"):
            ego_yaw = float(yaw_of_rotation(ego_pose[:3, :3]))
            rel = abs(float(np.rad2deg(np.angle(np.exp(1j * (heading - ego_yaw))))))
            return "in the oncoming lane" if rel >= ONCOMING_DEG else ""
        return "on the road"
    return ""


def describe_location(track: Track, category: str, layout: RoadLayout, ego_poses: np.ndarray, frame_idx: int) -> str:
    """Location phrase of a track at ``frame_idx`` (which must be one of the track's frames)."""
    row = track.index_of(frame_idx)
    if row is None:
        raise ValueError(f"track {track.object_id!r} has no frame {frame_idx}")
    xy = track.center[row, :2]
    pose = ego_poses[frame_idx]
    parts = [ego_relation(xy, pose), map_context(xy, float(track.heading[row]), category, layout, pose)]
    return " ".join(p for p in parts if p)


def describe_track(track: Track, category: str, layout: RoadLayout, ego_poses: np.ndarray) -> TrackDescription:
    """Motion and location of a track, the location taken at ``reference_frame(track)``."""
    ref = reference_frame(track)
    return TrackDescription(
        describe_motion(track, category, layout, ego_poses),
        describe_location(track, category, layout, ego_poses, ref),
        ref,
    )


def describe_appearance(category: str, attributes: dict[str, str]) -> str:
    """Appearance phrase from attributes, e.g. ``"a black sedan"``, ``"a pedestrian in a red top and blue pants"``."""
    if category == "pedestrian":
        upper, lower = attributes["upper_color"], attributes["lower_color"]
        return f"a pedestrian in {article(upper)} {upper} top and {lower} pants"
    color, subtype = attributes["color"], attributes["subtype"]
    return f"{article(color)} {color} {subtype}"


def compose_caption(category: str, appearance: str, motion: str, location: str) -> str:
    """Full sentence; static objects get appearance and location only."""
    if category in ("static", "sign"):
        words = [appearance, location]
    else:
        if motion.endswith("sidewalk") and location.endswith(" on the sidewalk"):
            location = location[: -len(" on the sidewalk")]  # "walking along the sidewalk on the sidewalk"
        words = [appearance, motion, location]
    return " ".join(w for w in words if w)
