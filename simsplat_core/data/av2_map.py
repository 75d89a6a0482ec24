"""Argoverse 2 vector map (``log_map_archive*.json``, sensor logs and motion-forecasting scenarios) -> ``MapFeature`` s.

What becomes what (all points moved from the city frame to the log's world frame):

* ``lane_segments`` of type VEHICLE or BUS -> ``"lane"``: the centre line, from resampling the left
  and right boundaries to the same number of points (``max`` of their counts) by arc length and
  averaging; direction of travel kept. BIKE lanes are skipped. (Motion-forecasting archives also
  carry a 2D ``centerline`` with z = 0; it is not used, so that lanes keep the map's elevation.)
* ``pedestrian_crossings`` -> ``"crosswalk"`` polygon ``edge1 + edge2`` (edge2 reversed when needed
  so the outline does not self-intersect).
* ``drivable_areas`` -> ``"drivable_area"`` polygon (``area_boundary``, implicitly closed).
* ``"road_edge"`` polylines: the parts of drivable-area outlines that are neither shared with
  another drivable area nor lying across the end of a lane that continues beyond the map crop (or
  dead-ends) (AV2 has no explicit curbs). A crop line across a shoulder or parking strip with no
  lane may remain as a short road edge.

Lane connectivity (``successors`` of the drivable lanes) comes from ``archive_lane_successors``; the other lane
attributes a Waymo Open Motion export needs (``archive_lane_attributes``: WOMD lane type, entry lanes = AV2
``predecessors``, same-direction left / right neighbours) are read from the same archive. AV2 archives carry no
speed limits; lane markings are not turned into features, so no road-line types are given.
Malformed content raises ``CorruptLogError`` naming the file and the JSON field.
"""

from __future__ import annotations

import json
import logging
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from simsplat_core.data.errors import CorruptLogError
from simsplat_core.geometry import transform_points
from simsplat_core.types import MapFeature

logger = logging.getLogger(__name__)

#: Lane types kept as drivable ``"lane"`` features.
DRIVABLE_LANE_TYPES = frozenset({"VEHICLE", "BUS"})
#: AV2 ``lane_type`` -> Waymo Open Motion lane type (``LaneCenter.type``). BIKE lanes are not kept as features.
WOMD_LANE_TYPES: dict[str, str] = {
    "VEHICLE": "TYPE_SURFACE_STREET",
    "BUS": "TYPE_SURFACE_STREET",
    "BIKE": "TYPE_BIKE_LANE",
}
#: Two drivable-area edges closer than this (metres, at sampled points) count as shared.
SHARED_EDGE_TOL_M = 0.1
#: Drivable-area edges within this distance (metres) of a dangling lane's end cross-section are map crops.
CUT_TOL_M = 0.3


def resample_polyline(points: np.ndarray, count: int) -> np.ndarray:
    """Resample ``[P, D]`` points to ``[count, D]`` evenly spaced by arc length (ends kept)."""
    seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
    arc = np.concatenate([[0.0], np.cumsum(seg)])
    if arc[-1] <= 0.0:
        return np.repeat(points[:1], count, axis=0)
    targets = np.linspace(0.0, arc[-1], count)
    return np.stack([np.interp(targets, arc, points[:, d]) for d in range(points.shape[1])], axis=1)


def lane_centerline(left: np.ndarray, right: np.ndarray) -> np.ndarray:
    """Centre line ``[N, 3]`` of a lane from its ``[L, 3]`` left and ``[R, 3]`` right boundaries, ``N = max(L, R)``."""
    count = max(left.shape[0], right.shape[0], 2)
    return 0.5 * (resample_polyline(left, count) + resample_polyline(right, count))


def crosswalk_polygon(edge1: np.ndarray, edge2: np.ndarray) -> np.ndarray:
    """Outline ``[P1 + P2, 3]`` of a crossing from its two long edges, oriented head-to-tail."""
    if np.linalg.norm(edge1[-1] - edge2[0]) < np.linalg.norm(edge1[-1] - edge2[-1]):
        return np.concatenate([edge1, edge2])
    return np.concatenate([edge1, edge2[::-1]])


def _point_segment_distance(points: np.ndarray, seg_a: np.ndarray, seg_b: np.ndarray) -> np.ndarray:
    """``[N, S]`` 2D distances from ``[N, 2]`` points to ``[S, 2]`` segments ``a -> b``."""
    ab = seg_b - seg_a
    rel = points[:, None, :] - seg_a[None]
    t = np.clip((rel * ab[None]).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-12)[None], 0.0, 1.0)
    return np.linalg.norm(rel - t[..., None] * ab[None], axis=-1)


def _covered(starts: np.ndarray, ends: np.ndarray, seg_a: np.ndarray, seg_b: np.ndarray, tol: float) -> np.ndarray:
    """``[E]`` bool: edges ``starts -> ends`` (``[E, 2]``) whose quarter, mid and three-quarter points
    all lie within ``tol`` of some segment ``seg_a -> seg_b`` (``[S, 2]``)."""
    covered = np.ones(starts.shape[0], dtype=bool)
    if seg_a.shape[0] == 0:
        return ~covered
    for frac in (0.25, 0.5, 0.75):
        probe = starts + frac * (ends - starts)
        covered &= _point_segment_distance(probe, seg_a, seg_b).min(axis=1) < tol
    return covered


def road_edges_from_areas(
    polygons: list[np.ndarray],
    cut_lines: np.ndarray | None = None,
    tol: float = SHARED_EDGE_TOL_M,
    cut_tol: float = CUT_TOL_M,
) -> list[np.ndarray]:
    """Polylines ``[P, 3]`` along drivable-area outlines that are plausibly curbs.

    Dropped outline edges: those shared with another polygon (all probe points within ``tol`` of
    its outline, tested in 2D) and those lying along ``cut_lines`` (``[C, 2, 2+]`` segments, e.g. the
    end cross-sections of lanes that continue beyond the map crop; within ``cut_tol``). Consecutive
    kept edges of one outline are joined into one polyline.
    """
    if not polygons:
        return []
    starts = np.concatenate(polygons)
    ends = np.concatenate([np.roll(p, -1, axis=0) for p in polygons])
    bounds = [(p[:, :2].min(axis=0) - tol, p[:, :2].max(axis=0) + tol) for p in polygons]
    first_row = np.cumsum([0] + [len(p) for p in polygons])
    shared = np.zeros(len(starts), dtype=bool)
    for i in range(len(polygons)):
        rows = slice(first_row[i], first_row[i + 1])
        for j in range(len(polygons)):
            if i == j or np.any(bounds[i][0] > bounds[j][1]) or np.any(bounds[j][0] > bounds[i][1]):
                continue
            other = slice(first_row[j], first_row[j + 1])
            shared[rows] |= _covered(starts[rows, :2], ends[rows, :2], starts[other, :2], ends[other, :2], tol)
    if cut_lines is not None and len(cut_lines):
        cut = np.asarray(cut_lines, dtype=np.float64)
        shared |= _covered(starts[:, :2], ends[:, :2], cut[:, 0, :2], cut[:, 1, :2], cut_tol)
    edges: list[np.ndarray] = []
    offset = 0
    for poly in polygons:
        keep = ~shared[offset : offset + len(poly)]
        offset += len(poly)
        if not keep.any():
            continue
        if keep.all():
            edges.append(np.concatenate([poly, poly[:1]]))
            continue
        # Rotate so that the loop starts right after a shared edge, then cut into runs.
        first = int(np.flatnonzero(~keep)[0]) + 1
        order = (np.arange(len(poly)) + first) % len(poly)
        run: list[np.ndarray] = []
        for idx in order:
            if keep[idx]:
                if not run:
                    run.append(poly[idx])
                run.append(poly[(idx + 1) % len(poly)])
            elif run:
                edges.append(np.array(run))
                run = []
        if run:
            edges.append(np.array(run))
    return edges


def _points(value: Any, path: Path, field: str, min_points: int) -> np.ndarray:
    """``[P, 3]`` float64 from a JSON list of ``{"x", "y", "z"}``."""
    if not isinstance(value, list) or len(value) < min_points:
        raise CorruptLogError(path, f"field {field!r}", f"expected a list of at least {min_points} points")
    try:
        pts = np.array([[p["x"], p["y"], p["z"]] for p in value], dtype=np.float64)
    except (KeyError, TypeError, ValueError) as exc:
        raise CorruptLogError(
            path, f"field {field!r}", f"points must be objects with numeric x, y, z ({exc!r})"
        ) from exc
    if not np.all(np.isfinite(pts)):
        raise CorruptLogError(path, f"field {field!r}", "non-finite coordinates")
    return pts


def _section(doc: Mapping[str, Any], key: str, path: Path) -> Mapping[str, Any]:
    section = doc.get(key)
    if not isinstance(section, Mapping):
        raise CorruptLogError(path, f"field {key!r}", "missing or not an object")
    return section


def _entry_field(entry: Any, key: str, path: Path, where: str) -> Any:
    if not isinstance(entry, Mapping) or key not in entry:
        raise CorruptLogError(path, f"field {where + '.' + key!r}", "missing")
    return entry[key]


def find_map_archive(folder: str | Path) -> Path:
    """The one ``log_map_archive*.json`` of ``folder``.

    Raises:
        CorruptLogError: none, or several (named), in ``folder``.
    """
    folder = Path(folder)
    candidates = sorted(folder.glob("log_map_archive*.json"))
    if not candidates:
        raise CorruptLogError(folder, "file", "no log_map_archive*.json")
    if len(candidates) > 1:
        raise CorruptLogError(folder, "file", f"several map archives: {[c.name for c in candidates]}")
    return candidates[0]


def read_map_archive(path: str | Path) -> Mapping[str, Any]:
    """The parsed JSON object of an AV2 ``log_map_archive*.json``.

    Raises:
        CorruptLogError: unreadable file, invalid JSON, or a top level that is not an object.
    """
    path = Path(path)
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise CorruptLogError(path, f"line {exc.lineno} column {exc.colno}", f"invalid JSON: {exc.msg}") from exc
    except (OSError, UnicodeDecodeError) as exc:
        raise CorruptLogError(path, "file", f"cannot read: {exc}") from exc
    if not isinstance(doc, Mapping):
        raise CorruptLogError(path, "top level", "expected a JSON object")
    return doc


def archive_lane_successors(doc: Mapping[str, Any], path: str | Path) -> dict[str, list[str]]:
    """``{lane feature id: [successor lane feature ids]}`` of the drivable lanes of a parsed map archive.

    Ids follow ``load_av2_map`` (``lane_<id>``); successors that are not drivable lanes of the archive (bike
    lanes, lanes beyond the map crop) are left out.

    Raises:
        CorruptLogError: ``lane_segments`` missing, or a lane without a ``lane_type`` or with ``successors``
            that is not a list (named by the JSON field).
    """
    path = Path(path)
    lanes = _section(doc, "lane_segments", path)
    drivable = {str(key) for key, lane in lanes.items()
                if _entry_field(lane, "lane_type", path, f"lane_segments[{key}]") in DRIVABLE_LANE_TYPES}
    out: dict[str, list[str]] = {}
    for key in sorted(drivable):
        successors = lanes[key].get("successors") or []
        if not isinstance(successors, list):
            raise CorruptLogError(path, f"field {f'lane_segments[{key}].successors'!r}", "expected a list of lane ids")
        out[f"lane_{key}"] = [f"lane_{s}" for s in successors if str(s) in drivable]
    return out


def _heading_vector(lane: Mapping[str, Any], path: Path, where: str) -> np.ndarray:
    """``[2]`` start-to-end direction of a lane (mean of its two boundaries' chords), not normalised."""
    chords = []
    for side in ("left_lane_boundary", "right_lane_boundary"):
        points = _points(_entry_field(lane, side, path, where), path, f"{where}.{side}", 2)
        chords.append(points[-1, :2] - points[0, :2])
    return 0.5 * (chords[0] + chords[1])


def _same_direction_neighbour(
    lanes: Mapping[str, Any], key: str, side: str, drivable: set[str], path: Path
) -> str | None:
    """Feature id of the drivable lane AV2 names as ``key``'s ``side`` (``"left"`` / ``"right"``) neighbour when it
    runs the same way (AV2 also names the opposite-direction lane across a centre line); ``None`` otherwise."""
    where = f"lane_segments[{key}]"
    neighbour = lanes[key].get(f"{side}_neighbor_id")
    if neighbour is None or str(neighbour) not in drivable:
        return None
    own = _heading_vector(lanes[key], path, where)
    other = _heading_vector(lanes[str(neighbour)], path, f"lane_segments[{neighbour}]")
    return f"lane_{neighbour}" if float(own @ other) > 0.0 else None


def archive_lane_attributes(doc: Mapping[str, Any], path: str | Path) -> dict[str, dict[str, Any]]:
    """``{lane feature id: attributes}`` of the drivable lanes of a parsed map archive, in the shape of
    ``common.MAP_FEATURE_ATTRIBUTES_KEY``: ``type`` (``WOMD_LANE_TYPES``), ``entry_lanes`` (the AV2
    ``predecessors``), ``left_neighbors`` / ``right_neighbors`` (the AV2 neighbour when it is a drivable lane running
    the same way). Ids follow ``load_av2_map``; lanes that are not drivable lanes of the archive are left out, and so
    is a list key with nothing in it.

    Raises:
        CorruptLogError: ``lane_segments`` missing, a lane without a ``lane_type``, ``predecessors`` that is not a
            list, or malformed lane boundaries (named by the JSON field).
    """
    path = Path(path)
    lanes = {str(key): lane for key, lane in _section(doc, "lane_segments", path).items()}
    drivable = {key for key, lane in lanes.items()
                if _entry_field(lane, "lane_type", path, f"lane_segments[{key}]") in DRIVABLE_LANE_TYPES}
    out: dict[str, dict[str, Any]] = {}
    for key in sorted(drivable):
        predecessors = lanes[key].get("predecessors") or []
        if not isinstance(predecessors, list):
            field = f"lane_segments[{key}].predecessors"
            raise CorruptLogError(path, f"field {field!r}", "expected a list of lane ids")
        attributes: dict[str, Any] = {"type": WOMD_LANE_TYPES[lanes[key]["lane_type"]]}
        entry = [f"lane_{p}" for p in predecessors if str(p) in drivable]
        if entry:
            attributes["entry_lanes"] = entry
        for side in ("left", "right"):
            neighbour = _same_direction_neighbour(lanes, key, side, drivable, path)
            if neighbour is not None:
                attributes[f"{side}_neighbors"] = [neighbour]
        out[f"lane_{key}"] = attributes
    return out


def load_av2_map(path: str | Path, world_from_city: np.ndarray) -> list[MapFeature]:
    """Parse an AV2 ``log_map_archive*.json`` into map features in the world frame.

    Args:
        path: the JSON file.
        world_from_city: ``[4, 4]`` transform from the AV2 city frame to the log's world frame.

    Raises:
        CorruptLogError: unreadable / invalid JSON, or a missing or malformed section or field.
    """
    path = Path(path)
    doc = read_map_archive(path)

    def to_world(points: np.ndarray) -> np.ndarray:
        return transform_points(world_from_city, points)

    features: list[MapFeature] = []
    skipped = 0
    lanes = _section(doc, "lane_segments", path)
    lane_ids = {str(key) for key in lanes}
    cut_lines: list[np.ndarray] = []  # [2, 3] end cross-sections of lanes continuing off the map
    for key, lane in sorted(lanes.items()):
        where = f"lane_segments[{key}]"
        lane_type = _entry_field(lane, "lane_type", path, where)
        left = _points(_entry_field(lane, "left_lane_boundary", path, where), path, f"{where}.left_lane_boundary", 2)
        right = _points(_entry_field(lane, "right_lane_boundary", path, where), path, f"{where}.right_lane_boundary", 2)
        for side, end_index in (("successors", -1), ("predecessors", 0)):
            neighbours = lane.get(side) or []
            if not isinstance(neighbours, list):
                raise CorruptLogError(path, f"field {where + '.' + side!r}", "expected a list of lane ids")
            if not neighbours or any(str(n) not in lane_ids for n in neighbours):
                cut_lines.append(to_world(np.stack([left[end_index], right[end_index]])))
        if lane_type not in DRIVABLE_LANE_TYPES:
            skipped += 1
            continue
        features.append(MapFeature(f"lane_{key}", "lane", to_world(lane_centerline(left, right))))
    for key, crossing in sorted(_section(doc, "pedestrian_crossings", path).items()):
        where = f"pedestrian_crossings[{key}]"
        edge1 = _points(_entry_field(crossing, "edge1", path, where), path, f"{where}.edge1", 2)
        edge2 = _points(_entry_field(crossing, "edge2", path, where), path, f"{where}.edge2", 2)
        features.append(MapFeature(f"crosswalk_{key}", "crosswalk", to_world(crosswalk_polygon(edge1, edge2))))
    areas = []
    for key, area in sorted(_section(doc, "drivable_areas", path).items()):
        where = f"drivable_areas[{key}]"
        outline = _points(_entry_field(area, "area_boundary", path, where), path, f"{where}.area_boundary", 3)
        if np.allclose(outline[0], outline[-1]):
            outline = outline[:-1]
        areas.append(to_world(outline))
        features.append(MapFeature(f"drivable_area_{key}", "drivable_area", areas[-1]))
    for i, edge in enumerate(road_edges_from_areas(areas, np.array(cut_lines).reshape(-1, 2, 3))):
        features.append(MapFeature(f"road_edge_{i}", "road_edge", edge))
    logger.debug("%s: %d map features, %d non-vehicle lanes skipped", path, len(features), skipped)
    return features
