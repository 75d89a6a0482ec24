"""A stored log's map as exported map features: kinds, integer ids, lane connectivity, types, traffic signals.

``SceneLog.map_features`` kinds map to WOMD's: ``lane`` -> lane, ``road_edge`` -> road edge, ``lane_marking`` ->
road line, ``crosswalk`` -> crosswalk. What the loaders keep in metadata comes back too: stop signs, speed bumps
and driveways (``metadata["stop_signs"]`` / ``["speed_bumps"]`` / ``["driveways"]``), lane successors
(``metadata["lane_successors"]``, whose inverse gives the entry lanes where the source did not list them) and
per-feature attributes (``data.common.map_feature_attributes``: ``type``, ``entry_lanes``, ``left_neighbors``,
``right_neighbors``, ``speed_limit_mph``).

Road edges follow WOMD's convention, the road on their left (``scenario.geometry.ROAD_EDGE_ROAD_SIDE``): where the
log has drivable areas, an edge whose left side is not the drivable area is reversed (the synthetic world's and
Argoverse's edges run either way). A log without road edges gets its drivable-area outlines as road-edge
boundaries (closed, counter-clockwise), so off-road checks downstream see the road's border; drivable areas and
sidewalks have no WOMD kind and are left out. Every such decision is returned as a note for the manifest.
"""

from __future__ import annotations

import json
from collections import Counter, defaultdict
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from simsplat_core.data.common import lane_successors, map_feature_attributes
from simsplat_core.export.ids import feature_ids
from simsplat_core.export.record import MAP_TYPES, ExportMapFeature, SignalState
from simsplat_core.scenario.geometry import points_in_polygon
from simsplat_core.types import SceneLog

#: ``MapFeature.kind`` -> exported kind (kinds absent here are derived or left out, see the module docstring).
KIND_OF_LOG_KIND: dict[str, str] = {
    "lane": "lane", "road_edge": "road_edge", "lane_marking": "road_line", "crosswalk": "crosswalk",
}


@dataclass(frozen=True)
class ExportMap:
    """A log's exported map.

    Attributes:
        features: the exported features.
        ids: the log's feature id (``"lane_123"``, ``"stop_sign_7"``) -> exported integer id.
        notes: what was derived or left out, for the manifest (``"sidewalk: 3 left out (no WOMD kind)"``).
    """

    features: tuple[ExportMapFeature, ...]
    ids: Mapping[str, int]
    notes: tuple[str, ...]


def _json(log: SceneLog, key: str, default: Any) -> Any:
    raw = log.metadata.get(key)
    if not raw:
        return default
    try:
        return json.loads(raw)
    except json.JSONDecodeError as exc:
        raise ValueError(f"log {log.seq_id!r}: metadata {key!r} is not valid JSON ({exc})") from exc


def _counter_clockwise_ring(polygon: np.ndarray) -> np.ndarray:
    """``[P + 1, 3]``: the closed outline of ``polygon`` ``[P, 3]``, counter-clockwise, so that the area lies to
    the left of its direction as WOMD's road edges have the road (``scenario.geometry.ROAD_EDGE_ROAD_SIDE``)."""
    x, y = polygon[:, 0], polygon[:, 1]
    signed_area = 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))
    ring = polygon if signed_area >= 0 else polygon[::-1]
    return np.concatenate([ring, ring[:1]])


#: How far beside a road edge (metres) its two sides are probed for the drivable area.
_SIDE_PROBE_M = 0.5


def _road_on_left(points: np.ndarray, areas: list[np.ndarray]) -> bool | None:
    """Whether the drivable ``areas`` (polygons ``[P, 3]``) lie to the left of the polyline ``points`` ``[N, 3]``:
    a vote over its segments' midpoints probed :data:`_SIDE_PROBE_M` to each side; ``None`` when no probe is in
    an area (the edge's side cannot be told)."""
    a, b = points[:-1, :2], points[1:, :2]
    direction = b - a
    length = np.linalg.norm(direction, axis=1)
    keep = length > 1e-6
    if not keep.any():
        return None
    left = np.stack([-direction[keep, 1], direction[keep, 0]], 1) / length[keep, None]
    mid = 0.5 * (a[keep] + b[keep])
    inside_left = np.zeros(len(mid), bool)
    inside_right = np.zeros(len(mid), bool)
    for area in areas:
        inside_left |= points_in_polygon(mid + _SIDE_PROBE_M * left, area[:, :2])
        inside_right |= points_in_polygon(mid - _SIDE_PROBE_M * left, area[:, :2])
    votes_left, votes_right = int((inside_left & ~inside_right).sum()), int((inside_right & ~inside_left).sum())
    if votes_left == votes_right == 0:
        return None
    return votes_left >= votes_right


def _collect(log: SceneLog) -> tuple[list[tuple[str, str, np.ndarray]], dict[str, list[str]], list[str]]:
    """(source id, kind, points) of every exported feature, stop sign controlled lanes, notes."""
    out: list[tuple[str, str, np.ndarray]] = []
    notes: list[str] = []
    has_edges = any(f.kind == "road_edge" for f in log.map_features)
    areas = [np.asarray(f.points, np.float64) for f in log.map_features if f.kind == "drivable_area"]
    dropped = Counter[str]()
    reversed_edges = 0
    for feat in log.map_features:
        kind = KIND_OF_LOG_KIND.get(feat.kind)
        points = np.asarray(feat.points, np.float64)
        if kind is None and feat.kind == "drivable_area" and not has_edges:
            kind, points = "road_edge", _counter_clockwise_ring(points)
        if kind is None:
            dropped[feat.kind] += 1
            continue
        if kind == "road_edge" and feat.kind == "road_edge" and areas and _road_on_left(points, areas) is False:
            points = points[::-1]
            reversed_edges += 1
        out.append((feat.feature_id, kind, points))
    derived = sum(1 for f in log.map_features if f.kind == "drivable_area") if not has_edges else 0
    if derived:
        notes.append(f"drivable_area: {derived} outlines exported as road edges (the log has no road edges)")
    if reversed_edges:
        notes.append(f"road_edge: {reversed_edges} reversed so that the road lies on their left (WOMD's convention)")
    notes += [f"{kind}: {n} left out (no WOMD map kind)" for kind, n in sorted(dropped.items())]
    controlled: dict[str, list[str]] = {}
    for sign in _json(log, "stop_signs", []):
        sid = f"stop_sign_{sign['id']}"
        out.append((sid, "stop_sign", np.asarray(sign["position"], np.float64).reshape(1, 3)))
        controlled[sid] = [str(lane) for lane in sign.get("lanes", [])]
    for kind, key in (("speed_bump", "speed_bumps"), ("driveway", "driveways")):
        for polygon in _json(log, key, []):
            out.append((f"{kind}_{polygon['id']}", kind, np.asarray(polygon["polygon"], np.float64).reshape(-1, 3)))
    return out, controlled, notes


def export_map(log: SceneLog) -> ExportMap:
    """The exported map of ``log`` (module docstring)."""
    collected, controlled, notes = _collect(log)
    ids = feature_ids([sid for sid, _, _ in collected])
    attributes = map_feature_attributes(log) or {}
    successors = lane_successors(log) or {}
    predecessors: dict[str, list[str]] = defaultdict(list)
    for lane, nexts in successors.items():
        for nxt in nexts:
            predecessors[nxt].append(lane)

    def linked(names: list[str]) -> tuple[int, ...]:
        return tuple(ids[n] for n in names if n in ids)

    features = []
    for sid, kind, points in collected:
        attrs = attributes.get(sid, {})
        kind_type = str(attrs.get("type", ""))
        neighbours = {side: [str(n) for n in attrs.get(side, [])]  # type: ignore[attr-defined]
                      for side in ("left_neighbors", "right_neighbors", "entry_lanes")}
        features.append(ExportMapFeature(
            feature_id=ids[sid], kind=kind, points=points, source_id=sid,
            type=kind_type if kind_type in MAP_TYPES.get(kind, ()) else "",
            entry_lanes=linked(neighbours["entry_lanes"] or predecessors.get(sid, [])) if kind == "lane" else (),
            exit_lanes=linked(successors.get(sid, [])) if kind == "lane" else (),
            left_neighbors=linked(neighbours["left_neighbors"]),
            right_neighbors=linked(neighbours["right_neighbors"]),
            controlled_lanes=linked(controlled.get(sid, [])),
            speed_limit_mph=float(attrs.get("speed_limit_mph", 0.0)),  # type: ignore[arg-type]
        ))
    return ExportMap(tuple(features), ids, tuple(notes))


def log_signals(log: SceneLog, ids: Mapping[str, int]) -> tuple[tuple[SignalState, ...], ...]:
    """Traffic-signal states at each log frame (``metadata["traffic_signals"]``: per frame, rows of ``[lane id,
    state, stop x, y, z]``); ``()`` when the log has none. Signals of lanes not in the map are left out."""
    steps = _json(log, "traffic_signals", [])
    if not steps:
        return ()
    out = []
    for row in steps:
        states = []
        for lane, state, *stop in row:
            if lane not in ids:
                continue
            point = None if any(v is None for v in stop) or len(stop) != 3 else np.asarray(stop, np.float64)
            states.append(SignalState(ids[lane], str(state), point))
        out.append(tuple(states))
    if len(out) != len(log.timestamps_us):
        raise ValueError(f"log {log.seq_id!r}: metadata 'traffic_signals' has {len(out)} steps, the log "
                         f"{len(log.timestamps_us)} frames")
    return tuple(out)
