"""Many routes sampled on one uniform arc-length grid, so poses and projections vectorise over agents.

Route ``n`` is sampled at ``s = k * step`` for ``k < K`` (``Path.position`` extrapolates straight past its
ends, so every route reaches the grid's length). Poses at arbitrary ``s`` interpolate linearly between grid
points; other points are projected onto a window of ``W`` grid points around each agent (nearest grid point,
then along its tangent: exact on straight stretches, within ``step^2 * curvature / 2`` on bends).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from simsplat_core.scenario.path import Path


@dataclass(frozen=True)
class RouteGrid:
    """``N`` routes on an arc-length grid.

    Attributes:
        xy: ``[N, K, 2]`` route points at ``s = k * step``.
        heading: ``[N, K]`` tangent yaw there (unwrapped along each route).
        step: grid spacing, metres.
    """

    xy: np.ndarray
    heading: np.ndarray
    step: float

    @classmethod
    def from_paths(cls, paths: Sequence[Path], length_m: float, step: float) -> RouteGrid:
        """Sample ``paths`` every ``step`` metres over ``[0, length_m]``."""
        k = int(np.ceil(length_m / step)) + 2
        s = np.arange(k) * step
        if not paths:
            return cls(np.zeros((0, k, 2)), np.zeros((0, k)), step)
        xy = np.stack([p.position(s) for p in paths])
        heading = np.stack([p.heading(s) for p in paths])
        return cls(xy, heading, step)

    @property
    def num_points(self) -> int:
        return self.xy.shape[1]

    def _cell(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``([N] index of the grid point at or before s, [N] fraction to the next one)``."""
        u = np.clip(s / self.step, 0.0, self.num_points - 1.000001)
        k = np.floor(u).astype(np.int64)
        return k, u - k

    def pose(self, s: np.ndarray, rows: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``([N, ..., 2] position, [N, ...] tangent yaw)`` of routes ``rows`` (default: all, in order) at
        arc lengths ``s [N, ...]``."""
        k, f = self._cell(s)
        n = np.arange(len(s)) if rows is None else np.asarray(rows)
        n = n.reshape((-1,) + (1,) * (s.ndim - 1))
        xy = self.xy[n, k] * (1.0 - f)[..., None] + self.xy[n, k + 1] * f[..., None]
        heading = self.heading[n, k] * (1.0 - f) + self.heading[n, k + 1] * f
        return xy, heading

    def window_start(self, s: np.ndarray, behind_m: float, width: int) -> np.ndarray:
        """``[N]`` first grid index of each route's window of ``width`` points starting ``behind_m`` before ``s``."""
        k = np.floor((s - behind_m) / self.step).astype(np.int64)
        return np.clip(k, 0, self.num_points - width)

    def project(self, rows: np.ndarray, k0: np.ndarray, width: int,
                points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Project points onto windows of the routes.

        Args:
            rows: ``[P]`` route of each query.
            k0: ``[N]`` window starts (``window_start``); route ``rows[p]``'s window is ``k0[rows[p]] + [0, width)``.
            width: window length ``W`` (grid points).
            points: ``[P, H, 2]`` query points (``H`` points per query).

        Returns:
            ``([P, H] arc length along the route, [P, H] signed lateral offset (left positive), [P, H] route
            tangent yaw at the projection)``.
        """
        idx = k0[rows][:, None] + np.arange(width)[None]  # [P, W]
        win = self.xy[rows[:, None], idx]  # [P, W, 2]
        d2 = ((points[:, :, None, :] - win[:, None]) ** 2).sum(-1)  # [P, H, W]
        best = np.argmin(d2, axis=-1)  # [P, H]
        k = np.take_along_axis(idx, best, axis=1)  # [P, H]
        near = self.xy[rows[:, None], k]  # [P, H, 2]
        yaw = self.heading[rows[:, None], k]
        tx, ty = np.cos(yaw), np.sin(yaw)
        rel = points - near
        along = k * self.step + rel[..., 0] * tx + rel[..., 1] * ty
        lateral = tx * rel[..., 1] - ty * rel[..., 0]
        return along, lateral, yaw
