"""Arc-length parametrised 2D paths and the lane routes vehicles and the ego follow.

A ``Path`` is a dense world-space polyline; ``position(s)`` and ``heading(s)`` evaluate it at arc
lengths ``s`` (metres, vectorised) and extrapolate straight beyond both ends, so agents never run
off a path whatever the sequence length. Routes through the junction are built from an inbound lane,
a smooth connector (cubic Bezier approximating a circular arc for turns) and an outbound lane.
Each route records named arc lengths in ``marks`` (``"stop"``: stop line, ``"junction_in"``/
``"junction_out"``: start/end of the connector).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from simsplat_core.world.road import RoadLayout, arm_dir, arm_normal, left_of, opposite, right_of

#: Length of straight lane kept before the stop line and after the junction exit when building routes.
ROUTE_REACH = 150.0


@dataclass(frozen=True)
class Path:
    """A polyline with cumulative arc length.

    Attributes:
        points: ``[N, 2]`` world xy, N >= 2, consecutive points distinct.
        s: ``[N]`` cumulative arc length, ``s[0] == 0``.
        marks: named arc lengths along the path.
    """

    points: np.ndarray
    s: np.ndarray
    marks: dict[str, float] = field(default_factory=dict)

    @classmethod
    def from_points(cls, points: np.ndarray, marks_at: dict[str, np.ndarray] | None = None) -> "Path":
        """Build a path from ``[N, 2]`` points (duplicates removed); ``marks_at`` names points to locate."""
        pts = np.asarray(points, dtype=np.float64)
        keep = np.concatenate([[True], np.linalg.norm(np.diff(pts, axis=0), axis=1) > 1e-9])
        pts = pts[keep]
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
        path = cls(pts, s, {})
        for name, p in (marks_at or {}).items():
            path.marks[name] = path.project(np.asarray(p, dtype=np.float64))
        return path

    @property
    def length(self) -> float:
        return float(self.s[-1])

    def _tangents(self) -> np.ndarray:
        seg = np.diff(self.points, axis=0)
        return seg / np.linalg.norm(seg, axis=1, keepdims=True)

    def position(self, s: np.ndarray | float) -> np.ndarray:
        """``[..., 2]`` world xy at arc lengths ``s`` (straight extrapolation outside ``[0, length]``)."""
        s_arr = np.asarray(s, dtype=np.float64)
        flat = s_arr.reshape(-1)
        x = np.interp(flat, self.s, self.points[:, 0])
        y = np.interp(flat, self.s, self.points[:, 1])
        out = np.stack([x, y], axis=1)
        tan = self._tangents()
        before = flat < 0
        after = flat > self.length
        out[before] = self.points[0] + flat[before, None] * tan[0]
        out[after] = self.points[-1] + (flat[after, None] - self.length) * tan[-1]
        return out.reshape(*s_arr.shape, 2)

    def heading(self, s: np.ndarray | float) -> np.ndarray:
        """``[...]`` yaw (radians, unwrapped along the path) of the tangent at ``s``."""
        tan = self._tangents()
        ang = np.unwrap(np.arctan2(tan[:, 1], tan[:, 0]))
        mid = 0.5 * (self.s[:-1] + self.s[1:])
        s_arr = np.asarray(s, dtype=np.float64)
        return np.interp(s_arr, mid, ang)

    def project(self, p: np.ndarray) -> float:
        """Arc length of the closest point of the path to world point ``p`` ``[2]``."""
        a, b = self.points[:-1], self.points[1:]
        ab = b - a
        t = np.clip(np.einsum("ij,ij->i", p - a, ab) / np.einsum("ij,ij->i", ab, ab), 0.0, 1.0)
        closest = a + t[:, None] * ab
        i = int(np.argmin(np.linalg.norm(closest - p, axis=1)))
        return float(self.s[i] + t[i] * np.linalg.norm(ab[i]))


def _bezier(p0: np.ndarray, p1: np.ndarray, p2: np.ndarray, p3: np.ndarray, n: int) -> np.ndarray:
    t = np.linspace(0.0, 1.0, n)[:, None]
    return (1 - t) ** 3 * p0 + 3 * (1 - t) ** 2 * t * p1 + 3 * (1 - t) * t**2 * p2 + t**3 * p3


def target_arm(arm: str, turn: str) -> str:
    """Arm a vehicle leaves by after ``turn`` (``straight``/``left``/``right``) from ``arm``."""
    return {"straight": opposite, "left": left_of, "right": right_of}[turn](arm)


def target_lane(layout: RoadLayout, arm: str, lane: int, turn: str) -> int | None:
    """Outbound lane index for a manoeuvre, or ``None`` when the lane may not make it.

    Left turns leave from the innermost lane into the innermost lane, right turns from the outermost
    lane into the outermost lane; straight keeps the lane index.
    """
    out_arm = target_arm(arm, turn)
    if turn == "straight":
        return lane if lane < layout.lanes(out_arm) else None
    if turn == "left":
        return 0 if lane == 0 else None
    return layout.lanes(out_arm) - 1 if lane == layout.lanes(arm) - 1 else None


def connector_points(layout: RoadLayout, arm: str, lane: int, turn: str, n: int = 32) -> np.ndarray | None:
    """``[n, 2]`` world points of the junction connector from inbound ``lane`` of ``arm``, or ``None``.

    The connector runs from the inbound stop line to the outer edge of the exit arm's crosswalk.
    """
    out_lane = target_lane(layout, arm, lane, turn)
    if out_lane is None:
        return None
    out_arm = target_arm(arm, turn)
    d0, n0 = arm_dir(arm), arm_normal(arm)
    d1, n1 = arm_dir(out_arm), arm_normal(out_arm)
    p0 = d0 * layout.stopline_s(arm) + n0 * layout.lane_offset(arm, True, lane)
    p3 = d1 * layout.crosswalk_range(out_arm)[1] + n1 * layout.lane_offset(out_arm, False, out_lane)
    h0, h1 = -d0, d1
    if turn == "straight":
        pts = p0 + np.linspace(0.0, 1.0, n)[:, None] * (p3 - p0)
    else:
        # corner where the two lane lines meet: p0 + a*h0 == p3 - b*h1
        mat = np.stack([h0, h1], axis=1)
        a, b = np.linalg.solve(mat, p3 - p0)
        k = 0.5523
        pts = _bezier(p0, p0 + k * a * h0, p3 - k * b * h1, p3, n)
    return layout.to_world(pts)


def route(layout: RoadLayout, arm: str, lane: int, turn: str) -> Path:
    """Inbound lane of ``arm`` -> connector -> outbound lane, with marks ``stop``, ``junction_in``, ``junction_out``."""
    conn = connector_points(layout, arm, lane, turn)
    if conn is None:
        raise ValueError(f"lane {lane} of arm {arm} cannot turn {turn}")
    out_arm = target_arm(arm, turn)
    out_lane = target_lane(layout, arm, lane, turn)
    d0, n0 = arm_dir(arm), arm_normal(arm)
    d1, n1 = arm_dir(out_arm), arm_normal(out_arm)
    s_stop = layout.stopline_s(arm)
    start = layout.to_world(d0 * (s_stop + ROUTE_REACH) + n0 * layout.lane_offset(arm, True, lane))
    s_exit = layout.crosswalk_range(out_arm)[1]
    end = layout.to_world(d1 * (s_exit + ROUTE_REACH) + n1 * layout.lane_offset(out_arm, False, out_lane))
    pts = np.concatenate([start[None], conn, end[None]], axis=0)
    return Path.from_points(pts, {"stop": conn[0], "junction_in": conn[0], "junction_out": conn[-1]})


def lane_change_route(
    layout: RoadLayout, arm: str, lane_from: int, lane_to: int, s_start: float, change_len: float
) -> Path:
    """Straight route along the road of ``arm`` in the inbound direction, changing lanes on the way.

    The lateral offset blends from ``lane_from`` to ``lane_to`` with a smoothstep over
    ``[s_start, s_start + change_len]`` (arc length from the route start, which lies ``ROUTE_REACH``
    metres beyond the stop line). Marks: ``stop``, ``change_start``, ``change_end``.
    """
    d0, n0 = arm_dir(arm), arm_normal(arm)
    s_stop = layout.stopline_s(arm)
    total = 2 * (s_stop + ROUTE_REACH)
    s = np.arange(0.0, total + 0.25, 0.5)
    w = np.clip((s - s_start) / change_len, 0.0, 1.0)
    w = w * w * (3.0 - 2.0 * w)
    off = (1 - w) * layout.lane_offset(arm, True, lane_from) + w * layout.lane_offset(arm, True, lane_to)
    along = s_stop + ROUTE_REACH - s  # along-arm coordinate decreases while driving inbound
    pts = layout.to_world(d0 * along[:, None] + n0 * off[:, None])
    stop_pt = layout.to_world(d0 * s_stop + n0 * off[np.argmin(np.abs(along - s_stop))])
    path = Path.from_points(pts, {"stop": stop_pt})
    path.marks["change_start"] = path.project(pts[np.argmin(np.abs(s - s_start))])
    path.marks["change_end"] = path.project(pts[np.argmin(np.abs(s - s_start - change_len))])
    return path


def polyline_path(points: np.ndarray) -> Path:
    """A path through explicit world points (pedestrian walks)."""
    return Path.from_points(np.asarray(points, dtype=np.float64))
