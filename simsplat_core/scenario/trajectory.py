"""Object trajectories prepared for motion labelling and encoding: smoothed velocities, yaw rate and curvature,
resampling, ego frames, map facts.

Conventions (``types.py``): world frame = first ego pose, right-handed, z up; the ego frame has x
forward and y to the left, so a positive yaw change is a left (counter-clockwise) turn and a negative
ego-frame ``y`` velocity is motion from the ego's left to its right.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from simsplat_core.geometry import invert_transform, yaw_of_rotation
from simsplat_core.scenario.map_context import MapContext, MapFacts
from simsplat_core.scenario.vocabulary import MOTION_VOCABULARIES, PEDESTRIAN, VEHICLE
from simsplat_core.types import SceneLog, Track

if TYPE_CHECKING:
    from simsplat_core.scenario.agents import AgentStates

#: Agent kinds with a motion codebook (``VEHICLE``, ``PEDESTRIAN``: the order indexes training samples).
AGENT_KINDS: tuple[str, ...] = tuple(MOTION_VOCABULARIES)


def agent_kind(category: str) -> str | None:
    """Motion codebook of an object category: pedestrians walk; vehicles, cyclists and other movers drive;
    static objects and signs have none (``None``)."""
    if category == "pedestrian":
        return PEDESTRIAN
    if category in ("vehicle", "cyclist", "other"):
        return VEHICLE
    return None


def smoothed_velocity(t: np.ndarray, xy: np.ndarray, half_window_s: float) -> np.ndarray:
    """``[T, 2]`` velocity by a local least-squares line fit over samples within ``half_window_s``.

    Args:
        t: ``[T]`` seconds, strictly increasing.
        xy: ``[T, 2]`` positions.
    Rows whose window holds a single sample get zero velocity.
    """
    w = (np.abs(t[:, None] - t[None, :]) <= half_window_s + 1e-9).astype(np.float64)  # [T, T]
    count = w.sum(axis=1, keepdims=True)
    t_mean = (w @ t[:, None]) / count  # [T, 1]
    xy_mean = (w @ xy) / count  # [T, 2]
    dt = t[None, :] - t_mean  # [T, T]
    var = (w * dt * dt).sum(axis=1, keepdims=True)
    cov = np.einsum("ij,ij,jk->ik", w, dt, xy) - xy_mean * (w * dt).sum(axis=1, keepdims=True)
    return np.where(var > 1e-12, cov / np.maximum(var, 1e-12), 0.0)


def moving_average(values: np.ndarray, window: int) -> np.ndarray:
    """``values [T, ...]`` averaged over ``window`` consecutive samples along axis 0, centred, the ends
    padded with the first / last sample (``window // 2`` each side; same length as ``values``)."""
    values = np.asarray(values, dtype=np.float64)
    half = window // 2
    padded = np.concatenate([np.repeat(values[:1], half, 0), values, np.repeat(values[-1:], half, 0)])
    kernel = np.ones(window) / window
    flat = padded.reshape(len(padded), -1)
    out = np.stack([np.convolve(flat[:, c], kernel, mode="valid") for c in range(flat.shape[1])], axis=1)
    return out[:len(values)].reshape(values.shape)


def resample_series(t: np.ndarray, values: np.ndarray, at: np.ndarray) -> np.ndarray:
    """``[L, C]`` linear interpolation of ``values`` ``[T, C]`` observed at ``t`` ``[T]`` (increasing), at
    times ``at`` ``[L]``; held constant outside ``t``'s span. Unwrap angles before resampling them."""
    values = np.asarray(values, dtype=np.float64)
    if len(t) == 1:
        return np.repeat(values, len(at), axis=0)
    return np.stack([np.interp(at, t, values[:, c]) for c in range(values.shape[1])], axis=1)


def yaw_rate(t: np.ndarray, heading: np.ndarray, half_window_s: float) -> np.ndarray:
    """``[T]`` rad/s: slope of the unwrapped ``heading`` ``[T]`` over ``t`` ``[T]`` by the same local line
    fit as ``smoothed_velocity`` (positive = turning left)."""
    unwrapped = np.unwrap(np.asarray(heading, dtype=np.float64))[:, None]
    return smoothed_velocity(np.asarray(t, dtype=np.float64), unwrapped, half_window_s)[:, 0]


def curvature(t: np.ndarray, heading: np.ndarray, speed: np.ndarray, half_window_s: float,
              min_speed_mps: float = 0.5) -> np.ndarray:
    """``[T]`` signed path curvature (1/m, positive = left) ``= yaw_rate / speed``; 0 where the agent
    moves slower than ``min_speed_mps`` (a standing box's yaw jitter has no path to curve)."""
    speed = np.asarray(speed, dtype=np.float64)
    rate = yaw_rate(t, heading, half_window_s)
    return np.where(speed >= min_speed_mps, rate / np.maximum(speed, min_speed_mps), 0.0)


def ego_yaw(ego_pose: np.ndarray) -> float:
    """Yaw of a ``[4, 4]`` ego pose in the world frame."""
    return float(yaw_of_rotation(ego_pose[:3, :3]))


def to_ego_frame(xy: np.ndarray, ego_pose: np.ndarray) -> np.ndarray:
    """``[N, 2]`` world points in the ego frame of ``ego_pose`` ``[4, 4]`` (x forward, y left)."""
    inv = invert_transform(ego_pose)
    return np.asarray(xy)[:, :2] @ inv[:2, :2].T + inv[:2, 3]


def rotate_to_ego(vectors: np.ndarray, ego_pose: np.ndarray) -> np.ndarray:
    """``[N, 2]`` world direction vectors (velocities) expressed in the ego frame of ``ego_pose``."""
    return np.asarray(vectors)[:, :2] @ ego_pose[:2, :2]


@dataclass(frozen=True)
class ObjectTrajectory:
    """One movable object's trajectory, column-wise over the ``T`` frames where it exists.

    Attributes:
        object_id, category: from the log.
        kind: ``agent_kind(category)``.
        frame_idx: ``[T]`` log frame indices.
        t: ``[T]`` seconds since the log's first frame.
        xy: ``[T, 2]`` world box centres.
        heading: ``[T]`` unwrapped box yaw, radians.
        velocity: ``[T, 2]`` smoothed world velocity, m/s.
        visible: ``[T]`` seen by some camera.
        facts: per-row map facts, ``None`` when the log has no map.
    """

    object_id: str
    category: str
    kind: str
    frame_idx: np.ndarray
    t: np.ndarray
    xy: np.ndarray
    heading: np.ndarray
    velocity: np.ndarray
    visible: np.ndarray
    facts: MapFacts | None = None

    def __len__(self) -> int:
        return int(self.frame_idx.shape[0])

    @property
    def speed(self) -> np.ndarray:
        """``[T]`` smoothed speed, m/s."""
        return np.linalg.norm(self.velocity, axis=1)

    def curvature(self, half_window_s: float = 0.5) -> np.ndarray:
        """``[T]`` signed path curvature, 1/m (``curvature``)."""
        return curvature(self.t, self.heading, self.speed, half_window_s)

    @property
    def duration(self) -> float:
        return float(self.t[-1] - self.t[0]) if len(self) else 0.0

    def window(self, rows: slice) -> ObjectTrajectory:
        """The rows ``rows`` (a contiguous slice) as a trajectory of their own; velocities are kept."""
        return replace(
            self,
            frame_idx=self.frame_idx[rows],
            t=self.t[rows],
            xy=self.xy[rows],
            heading=self.heading[rows],
            velocity=self.velocity[rows],
            visible=self.visible[rows],
            facts=self.facts.take(rows) if self.facts is not None else None,
        )

    def reference_row(self) -> int:
        """Row that location refers to: the median visible row (lower median), else the middle row."""
        rows = np.flatnonzero(self.visible) if self.visible.any() else np.arange(len(self))
        return int(rows[(len(rows) - 1) // 2])

    @classmethod
    def from_track(
        cls,
        track: Track,
        category: str,
        timestamps_us: np.ndarray,
        map_context: MapContext | None = None,
        half_window_s: float = 0.5,
    ) -> ObjectTrajectory:
        """Prepare a ``Track`` (``timestamps_us`` ``[F]`` of the log; velocities smoothed over ``±half_window_s``)."""
        kind = agent_kind(category)
        if kind is None:
            raise ValueError(f"object {track.object_id!r} of category {category!r} has no motion")
        t = (timestamps_us[track.frame_idx] - timestamps_us[0]).astype(np.float64) * 1e-6
        xy = np.asarray(track.center[:, :2], dtype=np.float64)
        heading = np.unwrap(np.asarray(track.heading, dtype=np.float64))
        facts = map_context.facts(xy, heading) if map_context is not None else None
        return cls(
            object_id=track.object_id,
            category=category,
            kind=kind,
            frame_idx=np.asarray(track.frame_idx, dtype=np.int64),
            t=t,
            xy=xy,
            heading=heading,
            velocity=smoothed_velocity(t, xy, half_window_s),
            visible=np.asarray(track.visible, dtype=bool),
            facts=facts,
        )


def log_trajectories(
    log: SceneLog, map_context: MapContext | None = None, half_window_s: float = 0.5, min_frames: int = 2
) -> dict[str, ObjectTrajectory]:
    """Trajectories of the log's movable objects with at least ``min_frames`` frames, in log order.

    ``map_context`` defaults to one built from ``log.map_features`` (``None`` when the log has no map).
    """
    if map_context is None and log.map_features:
        map_context = MapContext.from_features(log.map_features)
    out: dict[str, ObjectTrajectory] = {}
    for obj in log.objects:
        if agent_kind(obj.category) is None:
            continue
        track = log.track(obj.object_id)
        if len(track) < min_frames:
            continue
        out[obj.object_id] = ObjectTrajectory.from_track(
            track, obj.category, log.timestamps_us, map_context, half_window_s
        )
    return out


def agent_trajectory(states: AgentStates, row: int, map_context: MapContext) -> ObjectTrajectory:
    """Agent ``row`` of ``states`` (e.g. an edited scenario's) as an ``ObjectTrajectory`` over its valid steps, with
    the map's facts: what the trajectory auto-labeller (``language.motion_labels``) reads.

    Raises:
        ValueError: the agent has no motion vocabulary (static objects) or fewer than two valid steps.
    """
    kind = agent_kind(states.categories[row])
    valid = states.valid[row]
    if kind is None or valid.sum() < 2:
        raise ValueError(f"agent {states.object_ids[row]!r} ({states.categories[row]}) has no trajectory to label")
    t, xy = states.times[valid], states.xy[row, valid]
    heading = np.unwrap(states.heading[row, valid])
    return ObjectTrajectory(states.object_ids[row], states.categories[row], kind, states.frame_idx[valid], t, xy,
                            heading, smoothed_velocity(t, xy, 0.5), np.ones(len(t), dtype=bool),
                            map_context.facts(xy, heading))
