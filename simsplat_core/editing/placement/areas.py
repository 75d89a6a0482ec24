"""Map-area queries for the placement resolver (``editing.placement.resolve``): which points lie in a kind of map area,
where a box fits in one (nearest a point, or about a distance ahead of an anchor), and how far the road's edge
is to either side of a point.

Every function is pure numpy over ``[N, 2]`` world points and polygons ``[P, 2]`` (``MapContext``'s).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from simsplat_core.scenario.geometry import box_footprints, points_in_polygon
from simsplat_core.scenario.lane_graph import LaneGraph
from simsplat_core.scenario.map_context import MapContext

#: Search radius for spots in a map area, m.
AREA_SEARCH_M = 80.0
#: Grid step of the spot searches, m.
GRID_STEP_M = 0.5
#: A spot on the other side of the anchor than the one asked counts this much farther away, m.
OTHER_SIDE_PENALTY_M = 20.0
#: Missing a said distance ahead counts this many times as much as a sideways offset (the distance is what was
#: asked; the area lies wherever it lies to the side).
AHEAD_WEIGHT = 2.0
#: Headings tried, and how far a straight walk along each is followed, when orienting along an area, m.
RUN_HEADINGS = 72
RUN_M = 40.0
#: Corner samples around a box centre when checking a box of any heading fits.
_RING = 12
#: Candidates checked per vectorised block.
_CHUNK = 256


def area_polygons(map_ctx: MapContext, area: str) -> tuple[np.ndarray, ...]:
    """The polygons of ``area`` (``"crosswalk"``, ``"sidewalk"`` or ``"road"``: the drivable area)."""
    return {"crosswalk": map_ctx.crosswalks, "sidewalk": map_ctx.sidewalks, "road": map_ctx.drivable}[area]


def in_any(xy: np.ndarray, polys: Sequence[np.ndarray]) -> np.ndarray:
    """``[N]`` bool: the ``[N, 2]`` points inside any of ``polys``."""
    out = np.zeros(len(xy), dtype=bool)
    for poly in polys:
        lo, hi = poly.min(axis=0), poly.max(axis=0)
        near = ~out & np.all((xy >= lo) & (xy <= hi), axis=1)
        if near.any():
            out[near] |= points_in_polygon(xy[near], poly)
    return out


def box_points(xy: np.ndarray, heading: float, size: Sequence[float]) -> np.ndarray:
    """``[5, 2]``: the centre and the four corners of the box ``size (l, w, ...)`` at ``xy [2]`` facing ``heading``."""
    corners = box_footprints(np.asarray(xy, np.float64), np.asarray(heading, np.float64),
                             np.asarray(size, np.float64)[:2])
    return np.vstack([np.asarray(xy, np.float64)[None], corners])


def box_within(xy: np.ndarray, heading: float, size: Sequence[float], polys: Sequence[np.ndarray]) -> bool:
    """Whether the box ``size`` at ``xy [2]`` facing ``heading`` lies inside ``polys`` (centre and corners)."""
    return bool(in_any(box_points(xy, heading, size), polys).all())


def lane_samples(lanes: LaneGraph, step: float = GRID_STEP_M) -> tuple[np.ndarray, np.ndarray]:
    """``([M, 2] points every ~step along every lane centre line, [M] lane direction there)``."""
    d = lanes.seg_b - lanes.seg_a
    n = np.maximum(np.ceil(np.linalg.norm(d, axis=1) / step).astype(int), 1)
    seg = np.repeat(np.arange(len(d)), n)
    frac = (np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n) + 0.5) / np.repeat(n, n)
    return lanes.seg_a[seg] + frac[:, None] * d[seg], np.arctan2(d[seg, 1], d[seg, 0])


def _first_fitting(cand: np.ndarray, polys: Sequence[np.ndarray], size: Sequence[float]) -> np.ndarray | None:
    """The first of the ``[N, 2]`` candidate centres (all inside ``polys``) where a box of ``size`` fits at any
    heading (a ring of its half diagonal inside too), ``None`` when none does."""
    reach = float(np.hypot(size[0], size[1])) / 2.0
    angles = np.linspace(0, 2 * np.pi, _RING, endpoint=False)
    offsets = np.vstack([[0.0, 0.0], reach * np.stack([np.cos(angles), np.sin(angles)], axis=1)])  # [R+1, 2]
    for start in range(0, len(cand), _CHUNK):
        block = cand[start:start + _CHUNK]
        fits = in_any((block[:, None] + offsets[None]).reshape(-1, 2), polys).reshape(len(block), -1).all(axis=1)
        if fits.any():
            return block[int(np.argmax(fits))]
    return None


def fitting_point(query: np.ndarray, polys: Sequence[np.ndarray], size: Sequence[float],
                  step: float = GRID_STEP_M) -> np.ndarray | None:
    """The grid point nearest ``query [2]`` inside ``polys`` where a box of ``size`` (any heading) fits, within
    :data:`AREA_SEARCH_M`; ``None`` when none does."""
    for radius in (5.0, 20.0, AREA_SEARCH_M):
        g = np.arange(-radius, radius + step, step)
        grid = query + np.stack(np.meshgrid(g, g), axis=-1).reshape(-1, 2)
        grid = grid[np.argsort(np.linalg.norm(grid - query, axis=1))]
        found = _first_fitting(grid[in_any(grid, polys)], polys, size)
        if found is not None:
            return found
    return None


def fitting_point_ahead(origin: np.ndarray, heading: float, distance: float, tolerance: float,
                        polys: Sequence[np.ndarray], size: Sequence[float], side: int = 0,
                        step: float = GRID_STEP_M) -> np.ndarray | None:
    """A point about ``distance`` ahead of ``origin [2]`` (along ``heading``) inside ``polys`` where a box of
    ``size`` fits: of the grid points ``distance +- tolerance`` ahead and within :data:`AREA_SEARCH_M` to
    either side, the one nearest the point ``distance`` straight ahead (the error ahead weighted by
    :data:`AHEAD_WEIGHT`), those on the other side than ``side`` (``+1`` left, ``-1`` right, ``0`` either)
    counted :data:`OTHER_SIDE_PENALTY_M` farther. ``None`` when none fits."""
    forward = np.array([np.cos(heading), np.sin(heading)])
    left = np.array([-forward[1], forward[0]])
    along = distance + np.arange(-tolerance, tolerance + step / 2.0, step)
    lateral = np.arange(-AREA_SEARCH_M, AREA_SEARCH_M + step / 2.0, step)
    a, lat = (m.reshape(-1) for m in np.meshgrid(along, lateral))
    grid = np.asarray(origin, np.float64) + a[:, None] * forward + lat[:, None] * left
    score = np.hypot(AHEAD_WEIGHT * (a - distance), lat)
    if side:
        score += OTHER_SIDE_PENALTY_M * (np.sign(lat) == -side)
    inside = np.flatnonzero(in_any(grid, polys))
    order = inside[np.argsort(score[inside], kind="stable")]
    return _first_fitting(grid[order], polys, size)


def road_edge_offset(map_ctx: MapContext, xy: np.ndarray, left: np.ndarray, reach: float,
                     step: float = GRID_STEP_M / 2.0) -> float | None:
    """Signed distance along ``left [2]`` (positive: to the left) from ``xy [2]`` on the drivable area to the
    nearer of its edges on either side (the first point off it), ``None`` when ``xy`` is off the drivable area,
    the map has none, or the road runs on beyond ``reach`` metres both ways (an intersection)."""
    p = np.asarray(xy, np.float64)
    if not map_ctx.has_drivable or not in_any(p[None], map_ctx.drivable)[0]:
        return None
    u = np.arange(step, reach + step / 2.0, step)
    best: float | None = None
    for sign in (1.0, -1.0):
        off = np.flatnonzero(~in_any(p + sign * u[:, None] * np.asarray(left, np.float64), map_ctx.drivable))
        if off.size and (best is None or u[off[0]] < abs(best)):
            best = sign * float(u[off[0]])
    return best


def longest_run_heading(xy: np.ndarray, polys: Sequence[np.ndarray], prefer: float, step: float = GRID_STEP_M) -> float:
    """The heading (of :data:`RUN_HEADINGS`) along which a straight line from ``xy [2]`` stays inside ``polys`` the
    longest (up to :data:`RUN_M`): along a sidewalk band, round a corner onto the longer leg; ties go to the
    heading nearest ``prefer`` (radians)."""
    headings = np.linspace(-np.pi, np.pi, RUN_HEADINGS, endpoint=False)
    u = np.arange(step, RUN_M + step / 2.0, step)
    dirs = np.stack([np.cos(headings), np.sin(headings)], axis=1)  # [H, 2]
    pts = np.asarray(xy, np.float64) + u[None, :, None] * dirs[:, None, :]  # [H, U, 2]
    inside = in_any(pts.reshape(-1, 2), polys).reshape(len(headings), len(u))
    run = np.where(inside.all(axis=1), len(u), np.argmin(inside, axis=1))  # steps before first leaving
    turn = np.abs(np.angle(np.exp(1j * (headings - prefer))))
    best = np.lexsort((turn, -run))[0]
    return float(headings[best])
