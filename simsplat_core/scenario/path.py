"""Arc-length parametrised 2D paths: what agents follow, whatever built them (world routes, lane graphs).

A ``Path`` is a dense world-space polyline; ``position(s)`` and ``heading(s)`` evaluate it at arc
lengths ``s`` (metres, vectorised) and extrapolate straight beyond both ends, so agents never run
off a path whatever the sequence length. ``project(p)`` is the arc length of a point's closest path
point; ``marks`` names arc lengths (stop line, junction entry, ...).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


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
    def from_points(cls, points: np.ndarray, marks_at: dict[str, np.ndarray] | None = None) -> Path:
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
