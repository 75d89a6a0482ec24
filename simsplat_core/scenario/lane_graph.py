"""A directed lane graph over the ``"lane"`` ``MapFeature`` s of any source (synthetic world, Waymo, AV2).

Lanes are centre lines in the direction of travel. The graph answers:

* successors / predecessors: given explicitly (AV2's map archive lists them; pass ``successors``) or
  inferred from geometry: lane ``j`` follows lane ``i`` when their headings agree (within
  ``connect_deg``) and either ``i`` ends where ``j`` starts (within ``connect_m``), ``j`` starts on
  the last half of ``i`` or ``i`` ends on the first half of ``j`` (maps whose junction connectors
  overlap the lanes they join, like the synthetic world's, which start at the stop line);
* left / right neighbours: the nearest parallel lane (same direction within ``parallel_deg``) whose
  centre line lies ``min_width_m``..``max_width_m`` to the side at the lane's mid point;
* the nearest lane to poses ``(x, y[, heading])``: lane, arc length along it, signed lateral offset;
* lane-following paths: from a pose, follow successors and take ``"left"`` / ``"right"`` /
  ``"straight"`` at the next branch (a lane with several successors) that offers that manoeuvre,
  straight on otherwise; the path is a ``scenario.path.Path`` over the joined centre lines, so
  distances along it are its arc lengths.

The turn of a lane is its signed heading change from start to end (positive = left); a successor is a
left (right) turn beyond ``turn_deg``. All queries are vectorised with numpy over points and segments.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from simsplat_core.geometry import wrap_angle
from simsplat_core.scenario.path import Path
from simsplat_core.types import MapFeature

logger = logging.getLogger(__name__)

#: Manoeuvres at a branch of the lane graph.
MANOEUVRES: tuple[str, ...] = ("straight", "left", "right")


@dataclass(frozen=True)
class Lane:
    """One lane centre line.

    Attributes:
        lane_id: the ``MapFeature.feature_id``.
        points: ``[P, 2]`` world xy in the direction of travel (consecutive duplicates removed).
        s: ``[P]`` cumulative arc length, ``s[0] == 0``.
    """

    lane_id: str
    points: np.ndarray
    s: np.ndarray

    @property
    def length(self) -> float:
        return float(self.s[-1])

    def heading_at(self, s: np.ndarray | float) -> np.ndarray:
        """``[...]`` yaw of the segment holding arc length ``s`` (clamped to the lane)."""
        seg = np.diff(self.points, axis=0)  # [P-1, 2]
        idx = np.clip(np.searchsorted(self.s, np.asarray(s, dtype=np.float64), side="right") - 1, 0, len(seg) - 1)
        return np.arctan2(seg[idx, 1], seg[idx, 0])

    @property
    def turn(self) -> float:
        """Signed heading change from start to end, radians (positive = left)."""
        return float(wrap_angle(self.heading_at(self.length) - self.heading_at(0.0)))


@dataclass(frozen=True)
class LaneMatch:
    """Nearest lanes of ``N`` query poses.

    Attributes:
        lane: ``[N]`` lane index, ``-1`` where none is within reach.
        s: ``[N]`` arc length of the closest point along that lane.
        offset: ``[N]`` signed lateral offset from the centre line (positive = left of the lane).
        distance: ``[N]`` distance to the centre line (``inf`` without a lane).
    """

    lane: np.ndarray
    s: np.ndarray
    offset: np.ndarray
    distance: np.ndarray


@dataclass(frozen=True)
class LanePath:
    """A lane-following path.

    Attributes:
        path: the joined centre lines; ``path.project`` / ``position`` / ``heading`` measure along it.
        lanes: lane indices in order.
        lane_start: ``[len(lanes)]`` arc length on ``path`` where each lane's part begins.
        start_s: arc length on ``path`` of the start pose's projection.
        turn_taken: the manoeuvre was made at some branch (always ``True`` for ``"straight"``).
    """

    path: Path
    lanes: tuple[int, ...]
    lane_start: np.ndarray
    start_s: float
    turn_taken: bool

    def lane_span(self, k: int) -> tuple[float, float]:
        """Arc lengths ``(start, end)`` on ``path`` of the ``k``-th lane's part."""
        end = float(self.lane_start[k + 1]) if k + 1 < len(self.lanes) else self.path.length
        return float(self.lane_start[k]), end

    def heading_change(self, s0: float | None = None, s1: float | None = None) -> float:
        """Signed heading change along the path between arc lengths ``s0`` (default: the start pose) and
        ``s1`` (default: the end), radians (positive = left)."""
        s0 = self.start_s if s0 is None else s0
        s1 = self.path.length if s1 is None else s1
        return float(self.path.heading(s1) - self.path.heading(s0))


def _polyline(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``([P, 2] points without consecutive duplicates, [P] arc length)``."""
    pts = np.asarray(points, dtype=np.float64)[:, :2]
    keep = np.concatenate([[True], np.linalg.norm(np.diff(pts, axis=0), axis=1) > 1e-6])
    pts = pts[keep]
    return pts, np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])


def _project(points: np.ndarray, seg_a: np.ndarray, seg_b: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Closest segment of ``[N, 2]`` points among ``[S, 2]`` segments ``a -> b``.

    Returns ``([N, S] distances, [N, S] clamped segment parameter t in [0, 1], [N, S] signed offsets)``.
    """
    ab = seg_b - seg_a  # [S, 2]
    rel = points[:, None, :] - seg_a[None]  # [N, S, 2]
    len2 = np.maximum((ab * ab).sum(-1), 1e-12)  # [S]
    t = np.clip((rel * ab[None]).sum(-1) / len2[None], 0.0, 1.0)  # [N, S]
    dist = np.linalg.norm(rel - t[..., None] * ab[None], axis=-1)
    cross = ab[None, :, 0] * rel[..., 1] - ab[None, :, 1] * rel[..., 0]  # [N, S], > 0 left of a -> b
    return dist, t, cross / np.sqrt(len2)[None]


@dataclass(frozen=True)
class LaneGraph:
    """Lanes, their connections and a segment index for nearest-lane queries.

    Build with ``LaneGraph.from_features``.

    Attributes:
        lanes: the lanes, in feature order.
        successors, predecessors: per lane, indices of the lanes it continues into / comes from.
        left, right: per lane, index of the parallel neighbour on that side, ``-1`` when none.
        seg_a, seg_b: ``[S, 2]`` all centre-line segments; seg_lane ``[S]`` their lane; seg_s ``[S]``
            arc length of ``seg_a`` along its lane.
    """

    lanes: tuple[Lane, ...]
    successors: tuple[tuple[int, ...], ...]
    predecessors: tuple[tuple[int, ...], ...]
    left: np.ndarray
    right: np.ndarray
    seg_a: np.ndarray
    seg_b: np.ndarray
    seg_lane: np.ndarray
    seg_s: np.ndarray

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_features(
        cls,
        features: Sequence[MapFeature],
        successors: Mapping[str, Sequence[str]] | None = None,
        connect_m: float = 1.5,
        connect_deg: float = 30.0,
        parallel_deg: float = 15.0,
        min_width_m: float = 2.0,
        max_width_m: float = 5.0,
    ) -> LaneGraph:
        """The graph of the ``"lane"`` features (other kinds are ignored).

        Args:
            features: map features of any source.
            successors: explicit ``lane_id -> successor lane ids`` (ids missing from the map are
                dropped); inferred from geometry when ``None`` (see the module docstring).
            connect_m, connect_deg: endpoint gap and heading tolerance of inferred connections.
            parallel_deg, min_width_m, max_width_m: what counts as a neighbouring lane.
        """
        lanes = []
        for feat in features:
            if feat.kind != "lane" or len(feat.points) < 2:
                continue
            pts, s = _polyline(feat.points)
            if len(pts) >= 2:
                lanes.append(Lane(feat.feature_id, pts, s))
        seg_a = np.concatenate([ln.points[:-1] for ln in lanes]) if lanes else np.zeros((0, 2))
        seg_b = np.concatenate([ln.points[1:] for ln in lanes]) if lanes else np.zeros((0, 2))
        counts = [len(ln.points) - 1 for ln in lanes]
        seg_lane = np.repeat(np.arange(len(lanes)), counts) if lanes else np.zeros(0, int)
        seg_s = np.concatenate([ln.s[:-1] for ln in lanes]) if lanes else np.zeros(0)
        if successors is not None:
            index = {ln.lane_id: i for i, ln in enumerate(lanes)}
            succ = [tuple(index[j] for j in successors.get(ln.lane_id, ()) if j in index) for ln in lanes]
        else:
            succ = _infer_successors(lanes, seg_a, seg_b, seg_lane, seg_s, connect_m, np.deg2rad(connect_deg))
        pred: list[list[int]] = [[] for _ in lanes]
        for i, nxt in enumerate(succ):
            for j in nxt:
                pred[j].append(i)
        left, right = _neighbours(lanes, seg_a, seg_b, seg_lane, np.deg2rad(parallel_deg), min_width_m, max_width_m)
        logger.debug("lane graph: %d lanes, %d connections", len(lanes), sum(len(s) for s in succ))
        return cls(tuple(lanes), tuple(succ), tuple(tuple(p) for p in pred), left, right, seg_a, seg_b, seg_lane, seg_s)

    def __len__(self) -> int:
        return len(self.lanes)

    def index(self, lane_id: str) -> int:
        """Index of the lane with feature id ``lane_id``."""
        for i, ln in enumerate(self.lanes):
            if ln.lane_id == lane_id:
                return i
        raise KeyError(lane_id)

    # ------------------------------------------------------------------ queries
    def nearest(
        self, xy: np.ndarray, heading: np.ndarray | None = None, align_deg: float = 45.0, max_dist_m: float = np.inf
    ) -> LaneMatch:
        """Nearest lane of ``[N, 2]`` points; with ``[N]`` headings only lanes whose direction of travel is
        within ``align_deg`` of the heading count. ``lane == -1`` where nothing is within ``max_dist_m``."""
        xy = np.atleast_2d(np.asarray(xy, dtype=np.float64))[:, :2]
        n = len(xy)
        out = LaneMatch(np.full(n, -1), np.full(n, np.nan), np.full(n, np.nan), np.full(n, np.inf))
        if not len(self.seg_a):
            return out
        dist, t, offset = _project(xy, self.seg_a, self.seg_b)  # [N, S]
        if heading is not None:
            seg_dir = self.seg_b - self.seg_a
            seg_yaw = np.arctan2(seg_dir[:, 1], seg_dir[:, 0])  # [S]
            diff = np.abs(wrap_angle(np.asarray(heading, dtype=np.float64).reshape(-1, 1) - seg_yaw[None]))
            dist = np.where(diff <= np.deg2rad(align_deg), dist, np.inf)
        best = np.argmin(dist, axis=1)  # [N]
        rows = np.arange(n)
        d = dist[rows, best]
        ok = d <= max_dist_m
        seg_len = np.linalg.norm(self.seg_b - self.seg_a, axis=1)
        out.lane[ok] = self.seg_lane[best[ok]]
        out.s[ok] = (self.seg_s[best] + t[rows, best] * seg_len[best])[ok]
        out.offset[ok] = offset[rows, best][ok]
        out.distance[ok] = d[ok]
        return out

    def turn_of(self, lane: int, turn_deg: float = 30.0) -> str:
        """``"left"``, ``"right"`` or ``"straight"``: the lane's own heading change against ``turn_deg``."""
        dh = np.rad2deg(self.lanes[lane].turn)
        return "left" if dh > turn_deg else "right" if dh < -turn_deg else "straight"

    def _choose(self, options: tuple[int, ...], manoeuvre: str, turn_deg: float) -> tuple[int, bool]:
        """The successor to take at a branch and whether it makes ``manoeuvre``."""
        turns = np.array([self.lanes[j].turn for j in options])
        kinds = [self.turn_of(j, turn_deg) for j in options]
        if manoeuvre != "straight" and manoeuvre in kinds:
            pick = int(np.argmax(turns)) if manoeuvre == "left" else int(np.argmin(turns))
            return options[pick], True
        return options[int(np.argmin(np.abs(turns)))], manoeuvre == "straight"

    def follow(
        self,
        xy: np.ndarray,
        heading: float,
        manoeuvre: str = "straight",
        max_length_m: float = 200.0,
        turn_deg: float = 30.0,
    ) -> LanePath:
        """Lane-following path from the pose ``(xy [2], heading)``.

        Starts on the nearest lane aligned with ``heading``; at every lane with several successors (a
        branch, e.g. an intersection entry) takes the first that makes ``manoeuvre`` (``"left"``: the
        largest left turn, ``"right"``: the largest right turn) until it is made, the straightest
        successor otherwise; a single successor is always taken. Stops after ``max_length_m`` past the
        start or where the lanes end.
        """
        if manoeuvre not in MANOEUVRES:
            raise ValueError(f"manoeuvre must be one of {MANOEUVRES}, got {manoeuvre!r}")
        match = self.nearest(np.asarray(xy, dtype=np.float64)[None, :2], np.array([heading]))
        lane = int(match.lane[0])
        if lane < 0:
            raise ValueError("no lane near the start pose")
        start_on_lane = float(match.s[0])
        chain, taken = [lane], manoeuvre == "straight"
        ahead = self.lanes[lane].length - start_on_lane
        while ahead < max_length_m:
            options = self.successors[chain[-1]]
            options = tuple(j for j in options if j not in chain)
            if not options:
                break
            if len(options) == 1:
                nxt = options[0]
            else:
                nxt, made = self._choose(options, manoeuvre if not taken else "straight", turn_deg)
                taken = taken or made
            chain.append(nxt)
            ahead += self.lanes[nxt].length
        return self._join(chain, start_on_lane, taken)

    def _join(self, chain: list[int], start_on_lane: float, taken: bool) -> LanePath:
        """Concatenate the centre lines of ``chain``, trimming overlaps where a lane starts on its predecessor."""
        parts: list[np.ndarray] = []
        cut_from = 0.0  # arc length on the current lane where its part begins
        for k, i in enumerate(chain):
            ln = self.lanes[i]
            cut_to = ln.length
            if k + 1 < len(chain):
                nxt = self.lanes[chain[k + 1]]
                s_on = self._project_on(i, nxt.points[0])  # next lane starts on this one
                if s_on is not None and cut_from < s_on < ln.length - 1e-6:
                    cut_to = s_on
            parts.append(_slice(ln, cut_from, cut_to))
            cut_from = 0.0
            if k + 1 < len(chain):
                nxt_i = chain[k + 1]
                s_back = self._project_on(nxt_i, parts[-1][-1])  # this lane ends on the next one
                if s_back is not None and s_back > 1e-6:
                    cut_from = s_back
        lengths = [float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum()) for p in parts]
        lane_start = np.concatenate([[0.0], np.cumsum(lengths)[:-1]])
        path = Path.from_points(np.concatenate(parts))
        first = self.lanes[chain[0]]
        start_pt = np.array([np.interp(start_on_lane, first.s, first.points[:, c]) for c in range(2)])
        start_s = float(path.project(start_pt))
        return LanePath(path, tuple(chain), lane_start, start_s, taken)

    def _project_on(self, lane: int, point: np.ndarray, tol_m: float = 0.5) -> float | None:
        """Arc length of ``point`` ``[2]`` along ``lane`` when it lies within ``tol_m`` of its centre line."""
        ln = self.lanes[lane]
        dist, t, _ = _project(np.asarray(point, dtype=np.float64)[None, :2], ln.points[:-1], ln.points[1:])
        k = int(np.argmin(dist[0]))
        if dist[0, k] > tol_m:
            return None
        return float(ln.s[k] + t[0, k] * (ln.s[k + 1] - ln.s[k]))


def _slice(lane: Lane, s0: float, s1: float) -> np.ndarray:
    """``[K, 2]`` points of ``lane`` between arc lengths ``s0 < s1`` (interpolated ends)."""
    inner = lane.points[(lane.s > s0) & (lane.s < s1)]
    ends = np.stack([np.interp([s0, s1], lane.s, lane.points[:, c]) for c in range(2)], axis=1)  # [2, 2]
    return np.concatenate([ends[:1], inner, ends[1:]])


def _infer_successors(
    lanes: list[Lane],
    seg_a: np.ndarray,
    seg_b: np.ndarray,
    seg_lane: np.ndarray,
    seg_s: np.ndarray,
    connect_m: float,
    connect_rad: float,
) -> list[tuple[int, ...]]:
    """Successors by endpoint continuity or overlap (see the module docstring), ``[L]`` tuples."""
    n = len(lanes)
    if n == 0:
        return []
    starts = np.stack([ln.points[0] for ln in lanes])  # [L, 2]
    ends = np.stack([ln.points[-1] for ln in lanes])
    h_start = np.array([float(ln.heading_at(0.0)) for ln in lanes])  # [L]
    h_end = np.array([float(ln.heading_at(ln.length)) for ln in lanes])
    length = np.array([ln.length for ln in lanes])
    aligned = np.abs(wrap_angle(h_end[:, None] - h_start[None, :])) <= connect_rad  # [L(i), L(j)]
    gap = np.linalg.norm(ends[:, None] - starts[None], axis=-1) <= connect_m  # i ends where j starts
    seg_len = np.linalg.norm(seg_b - seg_a, axis=1)

    def on_lanes(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``([P, L] distance of each point to each lane, [P, L] its arc length there)``."""
        dist, t, _ = _project(points, seg_a, seg_b)  # [P, S]
        d_lane = np.full((len(points), n), np.inf)
        s_lane = np.zeros((len(points), n))
        for k in range(n):  # per-lane minimum over that lane's segments
            cols = np.flatnonzero(seg_lane == k)
            best = cols[np.argmin(dist[:, cols], axis=1)]
            rows = np.arange(len(points))
            d_lane[:, k] = dist[rows, best]
            s_lane[:, k] = seg_s[best] + t[rows, best] * seg_len[best]
        return d_lane, s_lane

    d_start, s_start = on_lanes(starts)  # [L(j), L(i)]: start of j on lane i
    d_end, s_end = on_lanes(ends)  # [L(i), L(j)]: end of i on lane j
    j_starts_on_i = (d_start.T <= 0.5) & (s_start.T >= 0.5 * length[:, None]) & (s_start.T > 0.0)
    i_ends_on_j = (d_end <= 0.5) & (s_end <= 0.5 * length[None, :])
    succ = aligned & (gap | j_starts_on_i | i_ends_on_j)
    np.fill_diagonal(succ, False)
    return [tuple(int(j) for j in np.flatnonzero(row)) for row in succ]


def _neighbours(
    lanes: list[Lane],
    seg_a: np.ndarray,
    seg_b: np.ndarray,
    seg_lane: np.ndarray,
    parallel_rad: float,
    min_width_m: float,
    max_width_m: float,
) -> tuple[np.ndarray, np.ndarray]:
    """``([L] left neighbour, [L] right neighbour)`` indices, ``-1`` for none."""
    n = len(lanes)
    left, right = np.full(n, -1), np.full(n, -1)
    if n == 0:
        return left, right
    mids = np.stack([np.interp(ln.length / 2, ln.s, ln.points[:, 0]) for ln in lanes])
    mids = np.stack([mids, [np.interp(ln.length / 2, ln.s, ln.points[:, 1]) for ln in lanes]], axis=1)  # [L, 2]
    h_mid = np.array([float(ln.heading_at(ln.length / 2)) for ln in lanes])
    _, t, _ = _project(mids, seg_a, seg_b)  # [L, S]
    seg_dir = seg_b - seg_a
    seg_yaw = np.arctan2(seg_dir[:, 1], seg_dir[:, 0])
    parallel = np.abs(wrap_angle(h_mid[:, None] - seg_yaw[None])) <= parallel_rad  # [L, S]
    # the lateral offset of the other lane seen from this lane's mid point, in this lane's frame
    normal = np.stack([-np.sin(h_mid), np.cos(h_mid)], axis=1)  # [L, 2]
    foot = seg_a[None] + t[..., None] * seg_dir[None]  # [L, S, 2]
    lateral = ((foot - mids[:, None]) * normal[:, None]).sum(-1)  # [L, S], > 0 to the left
    along = np.abs(((foot - mids[:, None]) * np.stack([np.cos(h_mid), np.sin(h_mid)], 1)[:, None]).sum(-1))
    # the foot of the perpendicular must lie beside the mid point (``along``), i.e. on a parallel stretch
    ok = parallel & (np.abs(lateral) >= min_width_m) & (np.abs(lateral) <= max_width_m) & (along < 0.5)
    ok &= seg_lane[None] != np.arange(n)[:, None]
    for i in range(n):
        for side, out in ((1.0, left), (-1.0, right)):
            cand = np.flatnonzero(ok[i] & (side * lateral[i] > 0))
            if len(cand):
                out[i] = int(seg_lane[cand[np.argmin(np.abs(lateral[i, cand]))]])
    return left, right
