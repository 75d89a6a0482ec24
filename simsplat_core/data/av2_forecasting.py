"""Argoverse 2 motion-forecasting scenario -> ``SceneLog`` (tracks, ego, map; no camera images).

Input: a scenario directory holding ``scenario_<id>.parquet`` (one row per track and timestep) and
``log_map_archive_<id>.json`` (its vector map), or the Parquet file itself (the map is looked up beside it).
Decoded with ``pyarrow`` alone. Conventions of the result:

* frames = the scenario's ``num_timestamps`` steps at 10 Hz: ``timestamps_us[t] = round(start_timestamp / 1000)
  + t * STEP_US`` (``start_timestamp`` / ``end_timestamp`` are nanoseconds; the end must match the step count);
* ego = the track ``"AV"`` (``EGO_TRACK_ID``), kept apart from ``tracks``; it must be present at every step.
  ``ego_poses[f]`` is its planar pose (yaw = ``heading``) on the ground; its nominal size goes to
  ``metadata["ego_size"]``;
* world frame = the ego pose at step 0 (``ego_poses[0]`` is the identity); the city -> world transform is in
  ``metadata["city_SE3_world"]`` (JSON 4x4, world -> city), as for AV2 sensor logs;
* heights: the scenario is 2D. The ground height under a position is the height of the nearest map vertex
  (lane centre lines, crosswalks, drivable areas; 0 without a map vertex); a box centre sits half its height
  above it;
* boxes: the scenario has none; every object gets the nominal size of its type (``NOMINAL_SIZES``,
  ``attributes["box_size"] = "nominal"``); heading = ``heading`` turned into the world frame; ``speed`` =
  ``|velocity_x, velocity_y|``; ``visible`` is ``True`` at every step where the track has a row (no cameras);
* categories by ``OBJECT_CATEGORIES`` (an ``object_type`` outside it is an error); the AV2 type in
  ``attributes["av2_object_type"]``, the track category (``object_category`` 0-3) by name in
  ``attributes["av2_track_category"]`` (``fragment``, ``unscored``, ``scored``, ``focal``); the focal and scored
  track ids also in ``metadata["focal_track_id"]`` / ``metadata["scored_track_ids"]`` (JSON);
  ``instance_id`` 1..N by first appearance (step, then track id); ``object_id`` is the ``track_id``;
* ``metadata["current_time_index"]`` = the last step with ``observed`` rows (49 for the 5 s history of the
  public scenarios);
* map: see ``av2_map`` (the same archive format as the sensor logs); lane successors from the archive go to
  ``metadata[LANE_SUCCESSORS_KEY]``, the other lane attributes to ``metadata[MAP_FEATURE_ATTRIBUTES_KEY]``
  (``"map_feature_attributes"``, read with ``common.map_feature_attributes``): JSON ``{lane feature id ("lane_123"):
  {"type": "TYPE_SURFACE_STREET", "entry_lanes": [feature ids], "left_neighbors": [feature ids],
  "right_neighbors": [feature ids]}}``. The type is the WOMD lane type of the AV2 ``lane_type`` (VEHICLE and BUS:
  ``TYPE_SURFACE_STREET``; BIKE lanes are not map features); entry lanes are the AV2 ``predecessors``; a
  neighbour is the AV2 ``left_neighbor_id`` / ``right_neighbor_id`` when that lane is a map feature running the same
  way (AV2 also names the opposite-direction lane across a centre line; WOMD neighbours are lanes one can change
  into). Keys with nothing to say are left out; AV2 has no speed limits, so ``speed_limit_mph`` never appears. The
  Waymo scenario loader writes the same entry in the same shape.

Bad input raises ``CorruptLogError`` naming the file and the column (or JSON field) and the offending value.
"""

from __future__ import annotations

import json
import logging
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from simsplat_core.data.arrow_columns import read_columns
from simsplat_core.data.av2_map import (
    archive_lane_attributes,
    archive_lane_successors,
    find_map_archive,
    load_av2_map,
    read_map_archive,
)
from simsplat_core.data.common import (
    LANE_SUCCESSORS_KEY,
    MAP_FEATURE_ATTRIBUTES_KEY,
    BoxObservation,
    build_track,
    loaded,
    safe_seq_id,
)
from simsplat_core.data.errors import CorruptLogError
from simsplat_core.geometry import invert_transform, pose_from_yaw, transform_points, wrap_angle
from simsplat_core.types import MapFeature, ObjectInfo, SceneLog, Track, node_type_for_category

logger = logging.getLogger(__name__)

#: ``SceneLog.source`` of logs from this loader.
FORECASTING_SOURCE = "av2-forecasting"
#: Step of the scenarios, microseconds (10 Hz).
STEP_US = 100_000
#: ``track_id`` of the autonomous vehicle (the ego).
EGO_TRACK_ID = "AV"
#: ``object_type`` -> shared category.
OBJECT_CATEGORIES: dict[str, str] = {
    "vehicle": "vehicle",
    "bus": "vehicle",
    "pedestrian": "pedestrian",
    "cyclist": "cyclist",
    "motorcyclist": "cyclist",
    "riderless_bicycle": "cyclist",
    "static": "static",
    "construction": "static",
    "background": "other",
    "unknown": "other",
}
#: ``object_type`` -> nominal box ``(length, width, height)`` in metres (the scenarios have no boxes).
NOMINAL_SIZES: dict[str, tuple[float, float, float]] = {
    "vehicle": (4.5, 2.0, 1.6),
    "bus": (12.0, 2.6, 3.2),
    "pedestrian": (0.6, 0.6, 1.7),
    "cyclist": (1.8, 0.7, 1.7),
    "motorcyclist": (2.0, 0.8, 1.6),
    "riderless_bicycle": (1.8, 0.6, 1.1),
    "static": (1.0, 1.0, 1.0),
    "construction": (0.5, 0.5, 1.0),
    "background": (1.0, 1.0, 1.0),
    "unknown": (1.0, 1.0, 1.0),
}
#: ``object_category`` value -> track category name.
TRACK_CATEGORIES: tuple[str, ...] = ("fragment", "unscored", "scored", "focal")
#: Largest accepted mismatch between ``end_timestamp`` and the step count, nanoseconds.
END_TOLERANCE_NS = 1_000_000
#: Map kinds whose vertices give the ground height.
_GROUND_KINDS = frozenset({"lane", "crosswalk", "drivable_area"})
#: Scenario-level columns (one value per file) by type.
_SCENARIO_STR = ("scenario_id", "focal_track_id", "city", "slice_id")
_SCENARIO_FLOAT = ("start_timestamp", "end_timestamp")
_SCENARIO_INT = ("num_timestamps", "map_id")


@dataclass(frozen=True)
class ScenarioHeader:
    """The scenario-level columns of a scenario Parquet (the same value in every row).

    Attributes:
        scenario_id, focal_track_id, city, slice_id: as in the file.
        start_ns, end_ns: ``start_timestamp`` / ``end_timestamp``, nanoseconds.
        num_timestamps: steps of the scenario.
        map_id: the map's id.
    """

    scenario_id: str
    focal_track_id: str
    city: str
    slice_id: str
    start_ns: float
    end_ns: float
    num_timestamps: int
    map_id: int


def scenario_parquet(path: Path) -> Path | None:
    """The scenario Parquet ``path`` names: the file itself, or the one ``scenario_*.parquet`` of a directory."""
    if path.is_file():
        return path if path.name.startswith("scenario_") and path.suffix == ".parquet" else None
    if path.is_dir():
        found = sorted(path.glob("scenario_*.parquet"))
        return found[0] if len(found) == 1 else None
    return None


def is_av2_forecasting_scenario(path: Path) -> bool:
    """Whether ``path`` is an AV2 motion-forecasting scenario (its directory or its ``scenario_*.parquet``, with
    the scenario columns ``track_id``, ``timestep`` and ``focal_track_id``; log-source detection)."""
    parquet = scenario_parquet(path)
    if parquet is None:
        return False
    import pyarrow as pa  # noqa: PLC0415  # only when a candidate file is there
    import pyarrow.parquet as pq  # noqa: PLC0415

    try:
        names = set(pq.read_schema(parquet).names)
    except (pa.ArrowException, OSError):
        return False
    return {"track_id", "timestep", "focal_track_id"} <= names


def _single_value(path: Path, name: str, values: np.ndarray) -> object:
    distinct = list(dict.fromkeys(values.tolist()))
    if len(distinct) != 1:
        raise CorruptLogError(path, f"column {name!r}", f"expected one value per scenario, found {distinct[:3]}")
    return distinct[0]


def _read_scenario(path: Path) -> tuple[dict[str, np.ndarray], ScenarioHeader]:
    """Per-row columns (``[N]`` each) and the scenario-level values of a scenario Parquet."""
    cols = read_columns(
        path,
        float_columns=("position_x", "position_y", "heading", "velocity_x", "velocity_y", *_SCENARIO_FLOAT),
        int_columns=("timestep", "object_category", *_SCENARIO_INT),
        str_columns=("track_id", "object_type", *_SCENARIO_STR),
        bool_columns=("observed",),
        file_format="parquet",
    )
    if cols["track_id"].size == 0:
        raise CorruptLogError(path, "column 'track_id'", "no rows")
    one = {name: _single_value(path, name, cols[name]) for name in (*_SCENARIO_STR, *_SCENARIO_FLOAT, *_SCENARIO_INT)}
    header = ScenarioHeader(
        **{name: str(one[name]) for name in _SCENARIO_STR},
        start_ns=float(cols["start_timestamp"][0]),
        end_ns=float(cols["end_timestamp"][0]),
        num_timestamps=int(cols["num_timestamps"][0]),
        map_id=int(cols["map_id"][0]),
    )
    return cols, header


def _timestamps_us(path: Path, cols: dict[str, np.ndarray], scenario: ScenarioHeader) -> np.ndarray:
    """``[S]`` int64 step timestamps; checks ``num_timestamps``, ``end_timestamp`` and every ``timestep``."""
    steps = scenario.num_timestamps
    if steps < 2:
        raise CorruptLogError(path, "column 'num_timestamps'", f"{steps} steps; a scenario needs at least 2")
    start_ns, end_ns = scenario.start_ns, scenario.end_ns
    expected_end = start_ns + (steps - 1) * STEP_US * 1000.0
    if abs(end_ns - expected_end) > END_TOLERANCE_NS:
        raise CorruptLogError(
            path,
            "column 'end_timestamp'",
            f"{end_ns:.0f} ns is not {steps - 1} steps of {STEP_US / 1000:g} ms after start_timestamp {start_ns:.0f}",
        )
    bad = np.flatnonzero((cols["timestep"] < 0) | (cols["timestep"] >= steps))
    if bad.size:
        raise CorruptLogError(
            path,
            "column 'timestep'",
            f"value {cols['timestep'][bad[0]]} in row {bad[0]} is outside 0..{steps - 1} (num_timestamps {steps})",
        )
    return int(round(start_ns / 1000.0)) + np.arange(steps, dtype=np.int64) * STEP_US


def _rows_by_track(path: Path, cols: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Row indices ``[n]`` of every track, sorted by timestep; checks per-track constants and duplicate steps."""
    _, track_index = np.unique(cols["track_id"].astype(str), return_inverse=True)
    order = np.lexsort((cols["timestep"], track_index))
    ids = track_index[order]
    starts = np.flatnonzero(np.r_[True, ids[1:] != ids[:-1]])
    out: dict[str, np.ndarray] = {}
    for rows in np.split(order, starts[1:]):
        track_id = str(cols["track_id"][rows[0]])
        steps = cols["timestep"][rows]
        dup = np.flatnonzero(np.diff(steps) == 0)
        if dup.size:
            raise CorruptLogError(
                path, "column 'timestep'", f"track {track_id!r} has two rows at timestep {steps[dup[0]]}"
            )
        for name in ("object_type", "object_category"):
            values = set(cols[name][rows].tolist())
            if len(values) > 1:
                raise CorruptLogError(
                    path, f"column {name!r}", f"track {track_id!r} has several values {sorted(values)}"
                )
        object_type = str(cols["object_type"][rows[0]])
        if object_type not in OBJECT_CATEGORIES:
            raise CorruptLogError(
                path,
                "column 'object_type'",
                f"unknown object type {object_type!r} (track {track_id!r}); "
                f"expected one of {sorted(OBJECT_CATEGORIES)}",
            )
        category = int(cols["object_category"][rows[0]])
        if not 0 <= category < len(TRACK_CATEGORIES):
            raise CorruptLogError(
                path, "column 'object_category'", f"value {category} (track {track_id!r}) is outside 0..3"
            )
        out[track_id] = rows
    return out


def ground_heights(xy: np.ndarray, vertices: np.ndarray, chunk: int = 4096) -> np.ndarray:
    """``[N]`` ground height under ``[N, 2]`` positions: the z of the nearest (in 2D) of ``[V, 3]`` map vertices
    (all 0 when ``V == 0``)."""
    if vertices.shape[0] == 0:
        return np.zeros(xy.shape[0])
    out = np.empty(xy.shape[0])
    for lo in range(0, xy.shape[0], chunk):
        d2 = ((xy[lo : lo + chunk, None, :] - vertices[None, :, :2]) ** 2).sum(-1)  # [n, V]
        out[lo : lo + chunk] = vertices[np.argmin(d2, axis=1), 2]
    return out


def _tracks_and_objects(
    cols: dict[str, np.ndarray],
    by_track: dict[str, np.ndarray],
    ground: np.ndarray,
    world_from_city: np.ndarray,
    timestamps_us: np.ndarray,
) -> tuple[tuple[Track, ...], tuple[ObjectInfo, ...]]:
    """Tracks and objects of every track but the ego (``ground`` is ``[N]`` per row, ``world_from_city`` ``[4, 4]``)."""
    yaw_offset = float(np.arctan2(world_from_city[1, 0], world_from_city[0, 0]))
    others = sorted((int(cols["timestep"][rows[0]]), track_id) for track_id, rows in by_track.items()
                    if track_id != EGO_TRACK_ID)
    tracks, objects = [], []
    for instance_id, (_, track_id) in enumerate(others, start=1):
        rows = by_track[track_id]
        object_type = str(cols["object_type"][rows[0]])
        size = np.array(NOMINAL_SIZES[object_type])
        city = np.column_stack([cols["position_x"][rows], cols["position_y"][rows], ground[rows] + 0.5 * size[2]])
        centers = transform_points(world_from_city, city)
        headings = wrap_angle(cols["heading"][rows] + yaw_offset)
        speeds = np.hypot(cols["velocity_x"][rows], cols["velocity_y"][rows])
        observations = [
            BoxObservation(int(cols["timestep"][r]), centers[k], size, float(headings[k]), float(speeds[k]), True)
            for k, r in enumerate(rows)
        ]
        tracks.append(build_track(track_id, observations, timestamps_us))
        category = OBJECT_CATEGORIES[object_type]
        objects.append(
            ObjectInfo(
                object_id=track_id,
                category=category,
                node_type=node_type_for_category(category),
                instance_id=instance_id,
                attributes={
                    "av2_object_type": object_type,
                    "av2_track_category": TRACK_CATEGORIES[int(cols["object_category"][rows[0]])],
                    "box_size": "nominal",
                },
            )
        )
    return tuple(tracks), tuple(objects)


def load_av2_forecasting(path: str | Path, seq_id: str | None = None) -> SceneLog:
    """Load one Argoverse 2 motion-forecasting scenario as a ``SceneLog`` (see module docstring).

    Args:
        path: the scenario directory (``scenario_<id>.parquet`` + ``log_map_archive_<id>.json``) or its Parquet.
        seq_id: sequence id; default: the ``scenario_id`` made directory-safe.

    Returns:
        A validated ``SceneLog`` (``source=FORECASTING_SOURCE``) with no images, one frame per step.

    Raises:
        FileNotFoundError: ``path`` does not exist.
        CorruptLogError: no (or several) scenario Parquet or map archive, a missing or mistyped column, nulls,
            non-finite values, several scenario ids (or other per-scenario values) in one file, a timestep
            outside the scenario, an unknown object type or track category, two rows of one track at one
            step, an ego track missing at some step, a focal track that is not in the file, or a malformed map;
            the message names the file, the column or JSON field, and the value.
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"AV2 forecasting scenario not found: {path}")
    t0 = time.perf_counter()
    parquet = scenario_parquet(path)
    if parquet is None:
        found = sorted(p.name for p in path.glob("scenario_*.parquet")) if path.is_dir() else []
        raise CorruptLogError(path, "file", f"expected one scenario_*.parquet, found {found or 'none'}")
    cols, scenario = _read_scenario(parquet)
    timestamps_us = _timestamps_us(parquet, cols, scenario)
    by_track = _rows_by_track(parquet, cols)
    ego_rows = by_track.get(EGO_TRACK_ID)
    if ego_rows is None or ego_rows.size != timestamps_us.size:
        have = 0 if ego_rows is None else ego_rows.size
        raise CorruptLogError(
            parquet, "column 'track_id'", f"the ego track {EGO_TRACK_ID!r} has {have} of {timestamps_us.size} steps"
        )
    focal = scenario.focal_track_id
    if focal not in by_track:
        raise CorruptLogError(parquet, "column 'focal_track_id'", f"focal track {focal!r} has no rows")

    map_path = find_map_archive(parquet.parent)
    city_map = load_av2_map(map_path, np.eye(4))
    vertices = np.concatenate([f.points for f in city_map if f.kind in _GROUND_KINDS] or [np.zeros((0, 3))])
    ground = ground_heights(np.column_stack([cols["position_x"], cols["position_y"]]), vertices)  # [N]
    city_from_ego = np.stack(
        [pose_from_yaw(cols["position_x"][r], cols["position_y"][r], ground[r], cols["heading"][r]) for r in ego_rows]
    )
    world_from_city = invert_transform(city_from_ego[0])
    ego_poses = world_from_city @ city_from_ego
    ego_poses[0] = np.eye(4)
    tracks, objects = _tracks_and_objects(cols, by_track, ground, world_from_city, timestamps_us)
    map_features = [MapFeature(f.feature_id, f.kind, transform_points(world_from_city, f.points)) for f in city_map]
    archive = read_map_archive(map_path)
    successors = archive_lane_successors(archive, map_path)
    lane_attributes = archive_lane_attributes(archive, map_path)

    observed_steps = cols["timestep"][cols["observed"]]
    scored = sorted(t for t, rows in by_track.items() if int(cols["object_category"][rows[0]]) >= 2)
    metadata = {
        "source_file": str(parquet),
        "map_file": map_path.name,
        "scenario_id": scenario.scenario_id,
        "city_name": scenario.city,
        "map_id": str(scenario.map_id),
        "slice_id": scenario.slice_id,
        "focal_track_id": focal,
        "scored_track_ids": json.dumps(scored),
        "current_time_index": str(int(observed_steps.max())) if observed_steps.size else "-1",
        "ego_track_id": EGO_TRACK_ID,
        "ego_size": json.dumps(list(NOMINAL_SIZES["vehicle"])),
        "ego_pose": "AV position on the ground (nearest map vertex height), yaw = heading",
        "box_size": "nominal per object type; the scenario has positions and headings only",
        "city_SE3_world": json.dumps(city_from_ego[0].round(9).tolist()),
        LANE_SUCCESSORS_KEY: json.dumps(successors, sort_keys=True),
        MAP_FEATURE_ATTRIBUTES_KEY: json.dumps(lane_attributes, sort_keys=True),
    }
    log = SceneLog(
        seq_id=seq_id if seq_id is not None else safe_seq_id(scenario.scenario_id),
        source=FORECASTING_SOURCE,
        timestamps_us=timestamps_us,
        ego_poses=ego_poses,
        tracks=tracks,
        objects=objects,
        map_features=tuple(map_features),
        metadata=metadata,
    )
    return loaded(log, parquet, t0, scenario.scenario_id)
