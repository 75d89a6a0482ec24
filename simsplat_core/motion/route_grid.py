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

#: Stride of the coarse nearest-point search in ``RouteGrid.project`` (grid points).
COARSE = 4


@dataclass(frozen=True)
class RouteGrid:
    """``N`` routes on an arc-length grid.

    Attributes:
        x, y: ``[N, K]`` route point coordinates at ``s = k * step``.
        heading: ``[N, K]`` tangent yaw there (unwrapped along each route).
        step: grid spacing, metres.
    """

    x: np.ndarray
    y: np.ndarray
    heading: np.ndarray
    step: float

    @classmethod
    def from_paths(cls, paths: Sequence[Path], length_m: float, step: float) -> RouteGrid:
        """Sample ``paths`` every ``step`` metres over ``[0, length_m]``."""
        k = int(np.ceil(length_m / step)) + 2
        s = np.arange(k) * step
        if not paths:
            return cls(np.zeros((0, k)), np.zeros((0, k)), np.zeros((0, k)), step)
        xy = np.stack([p.position(s) for p in paths])
        heading = np.stack([p.heading(s) for p in paths])
        return cls(np.ascontiguousarray(xy[..., 0]), np.ascontiguousarray(xy[..., 1]), heading, step)

    @property
    def num_points(self) -> int:
        return self.x.shape[1]

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
        x = self.x[n, k] * (1.0 - f) + self.x[n, k + 1] * f
        y = self.y[n, k] * (1.0 - f) + self.y[n, k + 1] * f
        heading = self.heading[n, k] * (1.0 - f) + self.heading[n, k + 1] * f
        return np.stack([x, y], axis=-1), heading

    def window_start(self, s: np.ndarray, behind_m: float, width: int) -> np.ndarray:
        """``[N]`` first grid index of each route's window of ``width`` points starting ``behind_m`` before ``s``."""
        k = np.floor((s - behind_m) / self.step).astype(np.int64)
        return np.clip(k, 0, self.num_points - width)

    def project(self, rows: np.ndarray, k0: np.ndarray, width: int,
                points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Project points onto windows of the routes.

        The nearest grid point is found coarse to fine (every ``COARSE``-th point of the window, then the
        points around the best one), then the point is projected along that grid point's tangent.

        Args:
            rows: ``[P]`` route of each query.
            k0: ``[N]`` window starts (``window_start``); route ``rows[p]``'s window is ``k0[rows[p]] + [0, width)``.
            width: window length ``W`` (grid points).
            points: ``[P, H, 2]`` query points (``H`` points per query).

        Returns:
            ``([P, H] arc length along the route, [P, H] signed lateral offset (left positive), [P, H] route
            tangent yaw at the projection)``.
        """
        px, py = points[..., 0], points[..., 1]  # [P, H]
        start = k0[rows]  # [P]
        coarse = start[:, None] + np.arange(0, width, COARSE)[None]  # [P, Wc]
        best = self._nearest(rows, coarse, px, py)  # [P, H] grid index
        last = start[:, None, None] + width - 1
        fine = np.clip(best[..., None] + np.arange(-COARSE, COARSE + 1), start[:, None, None], last)  # [P, H, F]
        k = self._nearest(rows, fine, px, py)
        r = rows[:, None]
        yaw = self.heading[r, k]
        tx, ty = np.cos(yaw), np.sin(yaw)
        rx, ry = px - self.x[r, k], py - self.y[r, k]
        along = k * self.step + rx * tx + ry * ty
        lateral = tx * ry - ty * rx
        return along, lateral, yaw

    def _nearest(self, rows: np.ndarray, cand: np.ndarray, px: np.ndarray, py: np.ndarray) -> np.ndarray:
        """``[P, H]`` the candidate grid index (``cand [P, C]`` shared by a query's points, or ``[P, H, C]``)
        nearest to each point ``(px, py) [P, H]`` on route ``rows [P]``."""
        r = rows.reshape((-1,) + (1,) * (cand.ndim - 1))
        gx, gy = self.x[r, cand], self.y[r, cand]
        if cand.ndim == 2:
            gx, gy = gx[:, None, :], gy[:, None, :]
            cand = np.broadcast_to(cand[:, None, :], px.shape + cand.shape[-1:])
        dx, dy = gx - px[..., None], gy - py[..., None]
        pick = np.argmin(dx * dx + dy * dy, axis=-1)
        return np.take_along_axis(cand, pick[..., None], axis=-1)[..., 0]
