"""Other agents seen from each driven agent's route: the nearest obstacle ahead (leader) or behind.

An agent ``j`` is in agent ``i``'s corridor when its box, projected across ``i``'s route, overlaps ``i``'s
width around the route shifted by ``i``'s lateral offset there: ``|lateral - offset| < half_width_i +
ext_lat_j + margin``. Its extent along the route is ``ext_along_j``; the gap to it is bumper to bumper
along the route. Everything is vectorised over candidate pairs (agents within reach of each other).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simsplat_core.motion.route_grid import RouteGrid


@dataclass(frozen=True)
class Pairs:
    """``P`` candidate (driven agent, other agent) pairs in the driven agent's route frame.

    Attributes:
        i: ``[P]`` driven-agent index (row of the grid).
        j: ``[P]`` other agent's index (row of the obstacle arrays).
        along: ``[P]`` arc length of ``j``'s centre on ``i``'s route.
        lateral: ``[P]`` its signed lateral offset (left positive).
        yaw: ``[P]`` route tangent yaw there.
        ext_along, ext_lat: ``[P]`` half extents of ``j``'s box along / across the route.
        v_along: ``[P]`` ``j``'s velocity along the route tangent.
    """

    i: np.ndarray
    j: np.ndarray
    along: np.ndarray
    lateral: np.ndarray
    yaw: np.ndarray
    ext_along: np.ndarray
    ext_lat: np.ndarray
    v_along: np.ndarray


@dataclass(frozen=True)
class Nearest:
    """Per driven agent, the nearest agent in its corridor on one side.

    Attributes:
        gap: ``[N]`` bumper-to-bumper gap along the route, ``inf`` where none.
        speed: ``[N]`` that agent's velocity along the route (0 where none).
        other: ``[N]`` its index, ``-1`` where none.
        pair: ``[N]`` the pair index, ``-1`` where none.
    """

    gap: np.ndarray
    speed: np.ndarray
    other: np.ndarray
    pair: np.ndarray


def box_extents(length: np.ndarray, width: np.ndarray, rel_yaw: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(half extent along, half extent across)`` of boxes turned ``rel_yaw`` from a direction."""
    c, s = np.abs(np.cos(rel_yaw)), np.abs(np.sin(rel_yaw))
    return 0.5 * (length * c + width * s), 0.5 * (length * s + width * c)


def route_pairs(grid: RouteGrid, k0: np.ndarray, width: int, agent_xy: np.ndarray, self_index: np.ndarray,  # noqa: PLR0913 -- struct-of-arrays step of the vectorised predictor
                xy: np.ndarray, heading: np.ndarray, size: np.ndarray, velocity: np.ndarray, valid: np.ndarray,
                reach_m: float) -> Pairs:
    """Candidate pairs and their geometry.

    Args:
        grid, k0, width: driven agents' routes and their windows (``RouteGrid.window_start``).
        agent_xy: ``[N, 2]`` driven agents' centres; self_index: ``[N]`` their own index among the others.
        xy, heading, size (``[M, 2]`` length, width), velocity (``[M, 2]``), valid: the other agents, ``[M]``.
        reach_m: others farther than this from a driven agent are not candidates.
    """
    d2 = ((agent_xy[:, None, :] - xy[None]) ** 2).sum(-1)  # [N, M]
    near = (d2 < reach_m**2) & valid[None]
    near[np.arange(len(agent_xy)), self_index] = False
    i, j = np.nonzero(near)
    along, lateral, yaw = grid.project(i, k0, width, xy[j][:, None])
    along, lateral, yaw = along[:, 0], lateral[:, 0], yaw[:, 0]
    ext_along, ext_lat = box_extents(size[j, 0], size[j, 1], heading[j] - yaw)
    v_along = velocity[j, 0] * np.cos(yaw) + velocity[j, 1] * np.sin(yaw)
    return Pairs(i, j, along, lateral, yaw, ext_along, ext_lat, v_along)


def group_min(groups: np.ndarray, values: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """``([n] min of values per group, [n] index of that value, -1 for empty groups)``; ties: lowest index."""
    best_val = np.full(n, np.inf)
    best_idx = np.full(n, -1, dtype=np.int64)
    finite = np.flatnonzero(np.isfinite(values))
    if finite.size:
        order = finite[np.lexsort((finite, values[finite], groups[finite]))]
        g, first = np.unique(groups[order], return_index=True)
        best_val[g] = values[order[first]]
        best_idx[g] = order[first]
    return best_val, best_idx


def in_corridor(pairs: Pairs, half_width: np.ndarray, offset: np.ndarray, margin: float) -> np.ndarray:
    """``[P]`` bool: ``j``'s box overlaps ``i``'s corridor shifted by ``offset [P]`` across the route."""
    return np.abs(pairs.lateral - offset) < half_width[pairs.i] + pairs.ext_lat + margin


def nearest_ahead(pairs: Pairs, s: np.ndarray, half_length: np.ndarray, half_width: np.ndarray, offset: np.ndarray,
                  margin: float, mask: np.ndarray | None = None) -> Nearest:
    """The leader of each driven agent: the nearest agent in its corridor whose centre is ahead of its own.

    Args:
        s, half_length, half_width: ``[N]`` driven agents' arc lengths and half box sizes.
        offset: ``[P]`` the driven agent's lateral offset at each pair's ``along``.
        mask: ``[P]`` pairs allowed (default all).
    """
    ok = in_corridor(pairs, half_width, offset, margin) & (pairs.along > s[pairs.i])
    if mask is not None:
        ok &= mask
    gap = np.where(ok, pairs.along - pairs.ext_along - (s[pairs.i] + half_length[pairs.i]), np.inf)
    return _pick(pairs, gap, len(s))


def nearest_behind(pairs: Pairs, s: np.ndarray, half_length: np.ndarray, half_width: np.ndarray, offset: np.ndarray,
                   margin: float, mask: np.ndarray | None = None) -> Nearest:
    """The follower of each driven agent in a corridor shifted by ``offset [P]`` (same arguments)."""
    ok = in_corridor(pairs, half_width, offset, margin) & (pairs.along <= s[pairs.i])
    if mask is not None:
        ok &= mask
    gap = np.where(ok, (s[pairs.i] - half_length[pairs.i]) - (pairs.along + pairs.ext_along), np.inf)
    return _pick(pairs, gap, len(s))


def _pick(pairs: Pairs, gap: np.ndarray, n: int) -> Nearest:
    best, idx = group_min(pairs.i, gap, n)
    has = idx >= 0
    speed = np.where(has, pairs.v_along[np.maximum(idx, 0)], 0.0) if len(gap) else np.zeros(n)
    other = np.where(has, pairs.j[np.maximum(idx, 0)], -1) if len(gap) else np.full(n, -1)
    return Nearest(best, speed, other, idx)
