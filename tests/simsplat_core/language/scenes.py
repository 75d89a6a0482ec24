"""Hand-built driving logs for the labeller tests: an ego on a known pose and objects on analytic paths."""

from __future__ import annotations

import numpy as np

from simsplat_core.geometry import pose_from_yaw
from simsplat_core.types import MapFeature, ObjectInfo, SceneLog, Track, node_type_for_category

FPS = 10.0
FRAMES = 40


def times() -> np.ndarray:
    return np.arange(FRAMES) / FPS


def straight(start: tuple[float, float], heading: float, speed: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """``([T, 2] xy, [T] heading)`` of a straight path with a per-frame (or constant) speed."""
    speed = np.broadcast_to(np.asarray(speed, dtype=np.float64), (FRAMES,))
    s = np.concatenate([[0.0], np.cumsum(0.5 * (speed[1:] + speed[:-1]) / FPS)])
    d = np.array([np.cos(heading), np.sin(heading)])
    return np.asarray(start) + s[:, None] * d, np.full(FRAMES, heading)


def arc(radius: float, degrees: float, speed: float = 6.0) -> tuple[np.ndarray, np.ndarray]:
    """A turn starting at (10, 0) heading +x; positive ``degrees`` turn left (counter-clockwise)."""
    sign = np.sign(degrees)
    total = np.deg2rad(abs(degrees))
    ang = np.minimum(speed * times() / radius, total)
    centre = np.array([10.0, sign * radius])
    xy = centre + radius * np.stack([np.sin(ang), -sign * np.cos(ang)], axis=1)
    return xy, sign * ang


def lane_change(direction: float, width: float = 3.5, speed: float = 8.0) -> tuple[np.ndarray, np.ndarray]:
    """Drive +x from (5, 0) and move ``direction * width`` sideways with a smooth S-curve over 3 s."""
    t = times()
    u = np.clip((t - 0.5) / 3.0, 0.0, 1.0)
    y = direction * width * (u * u * (3 - 2 * u))
    x = 5.0 + speed * t
    heading = np.arctan2(np.gradient(y), np.gradient(x))
    return np.stack([x, y], axis=1), heading


def scene(
    objects: dict[str, tuple[str, np.ndarray, np.ndarray]],
    ego_yaw: float = 0.0,
    ego_speed: float = 0.0,
    map_features: tuple[MapFeature, ...] = (),
) -> SceneLog:
    """A log whose ego drives straight at ``ego_speed`` from the origin with world yaw ``ego_yaw``.

    ``objects`` maps an id to ``(category, xy [T, 2], heading [T])`` and, like ``map_features``, is
    given in the frame ``E`` of the ego's start (x along ``ego_yaw``, y to its left); the helper
    rotates everything into the world. The world frame is the first ego pose, so frame 0 keeps the
    identity pose and the rotation applies from frame 1 on (objects are labelled at frame 19).
    """
    c, s = np.cos(ego_yaw), np.sin(ego_yaw)
    rot = np.array([[c, -s], [s, c]])
    poses = np.stack([pose_from_yaw(*(rot @ [ego_speed * t, 0.0]), 0.0, ego_yaw) for t in times()])
    poses[0] = np.eye(4)
    tracks, infos = [], []
    for k, (oid, (category, xy, heading)) in enumerate(objects.items()):
        tracks.append(
            Track(
                oid,
                np.arange(FRAMES),
                np.concatenate([xy @ rot.T, np.full((FRAMES, 1), 0.8)], axis=1),
                np.tile([4.5, 1.9, 1.6], (FRAMES, 1)),
                heading + ego_yaw,
                np.full(FRAMES, np.nan),
                np.ones(FRAMES, dtype=bool),
            )
        )
        infos.append(ObjectInfo(oid, category, node_type_for_category(category), k + 1))
    feats = tuple(
        MapFeature(f.feature_id, f.kind, np.concatenate([f.points[:, :2] @ rot.T, f.points[:, 2:]], axis=1))
        for f in map_features
    )
    return SceneLog(
        "hand-built",
        "test",
        np.round(times() * 1e6).astype(np.int64),
        poses,
        tracks=tuple(tracks),
        objects=tuple(infos),
        map_features=feats,
    ).validate()


def polygon(kind: str, fid: str, x0: float, x1: float, y0: float, y1: float) -> MapFeature:
    return MapFeature(fid, kind, np.array([[x0, y0, 0.0], [x1, y0, 0.0], [x1, y1, 0.0], [x0, y1, 0.0]]))


def lane(fid: str, y: float, x0: float = -50.0, x1: float = 150.0, reverse: bool = False) -> MapFeature:
    xs = np.linspace(x0, x1, 21)
    pts = np.stack([xs, np.full_like(xs, y), np.zeros_like(xs)], axis=1)
    return MapFeature(fid, "lane", pts[::-1] if reverse else pts)
