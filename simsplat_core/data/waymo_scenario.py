"""Waymo Open Motion ``Scenario`` TFRecords -> ``SceneLog`` (tracks, ego, map; no camera images).

One ``Scenario`` record (by default the first of the file; ``record_index`` picks another) becomes
one ``SceneLog`` whose frames are the scenario's steps (91 at 10 Hz in the motion dataset; steps
``0..current_time_index`` are the observed history). Conventions of the result:

* ``timestamps_us = round(timestamps_seconds * 1e6)`` (Waymo's steps are ~0.1 s, not exactly);
* ego = the SDC track (``sdc_track_index``), kept apart from ``tracks`` like the other loaders keep
  the ego vehicle: ``ego_poses[f]`` is the planar pose (yaw only) of the SDC box centre lowered to
  the bottom of its box (ego frame: x forward, y left, z up, origin on the ground under the box
  centre). The SDC must be valid at every step. Its box size goes to ``metadata["ego_size"]``;
* world frame = the SDC pose at step 0 (``ego_poses[0]`` is the identity); the global -> world
  transform is in ``metadata["global_SE3_world"]`` (JSON 4x4, world -> global);
* tracks: every other track, at the steps where ``ObjectState.valid`` (invalid states are absent
  frames; a track with no valid state is dropped with a warning); heading is the world yaw of the
  box; ``speed`` is ``|velocity_x, velocity_y|``; ``visible`` is ``True`` at every valid step (the
  scenario has no cameras: "observed by the SDC's perception");
* categories by ``SCENARIO_CATEGORIES`` (UNSET / OTHER -> ``"other"``), Waymo's type name in
  ``attributes["waymo_type"]``, ``attributes["tracks_to_predict_difficulty"]`` and
  ``attributes["object_of_interest"]`` where they apply; ``instance_id`` 1..N by first appearance
  (step, then track id); ``object_id`` is the Waymo track id as a string;
* map: lane centre lines of vehicle lane types (``VEHICLE_LANE_TYPES``; bike lanes skipped) ->
  ``"lane"`` (``lane_<id>``), road edges -> ``"road_edge"``, road lines -> ``"lane_marking"``,
  crosswalk polygons -> ``"crosswalk"``. Lane connectivity (``exit_lanes``) goes to
  ``metadata[LANE_SUCCESSORS_KEY]`` (read it with ``common.lane_successors``). The scenario has no
  drivable-area polygons and none is derived (off-road tests use the road edges). Stop signs
  (position + controlled lanes), speed-bump and driveway polygons have no ``MAP_KINDS``; they go to
  ``metadata["stop_signs"]`` / ``metadata["speed_bumps"]`` / ``metadata["driveways"]`` (JSON, world frame);
* what a ``MapFeature`` has no room for goes to ``metadata[common.MAP_FEATURE_ATTRIBUTES_KEY]``
  (``"map_feature_attributes"``, read it with ``common.map_feature_attributes``): a JSON object from
  the ``MapFeature.feature_id`` (``"lane_123"``, ``"road_line_7"``, ``"road_edge_5"``) to that
  feature's attributes, only the keys that apply:
  ``"type"`` (Waymo's type name, e.g. ``"TYPE_SURFACE_STREET"``, ``"TYPE_SOLID_SINGLE_WHITE"``,
  ``"TYPE_ROAD_EDGE_BOUNDARY"``; lanes, road lines and road edges), ``"entry_lanes"``,
  ``"left_neighbors"``, ``"right_neighbors"`` (lists of lane feature ids; lanes, possibly empty) and
  ``"speed_limit_mph"`` (a number; lanes whose record has one). Exit lanes are the lane successors
  above. Features with none of these (crosswalks) have no entry. Example:
  ``{"lane_100": {"type": "TYPE_SURFACE_STREET", "entry_lanes": ["lane_99"], "left_neighbors":
  ["lane_101"], "right_neighbors": [], "speed_limit_mph": 25.0}, "road_edge_200": {"type":
  "TYPE_ROAD_EDGE_BOUNDARY"}}``;
* traffic-signal states per step go to ``metadata["traffic_signals"]`` (JSON list over steps of
  ``[lane feature id, state name, stop point x, y, z]``, world frame).
"""

from __future__ import annotations

import collections
import json
import logging
import time
from pathlib import Path

import numpy as np

from simsplat_core.data.common import (
    LANE_SUCCESSORS_KEY,
    MAP_FEATURE_ATTRIBUTES_KEY,
    BoxObservation,
    build_track,
    first_record_has,
    loaded,
    parse_tfrecords,
    safe_seq_id,
)
from simsplat_core.data.errors import CorruptLogError
from simsplat_core.data.waymo_scenario_proto import (
    MAP_TYPE_ENUMS,
    OBJECT_TYPES,
    SCENARIO_SIGNATURE,
    SIGNAL_STATES,
    ScenarioMapFeature,
    ScenarioTrack,
    WaymoScenario,
    parse_scenario,
)
from simsplat_core.geometry import invert_transform, pose_from_yaw, transform_points, wrap_angle
from simsplat_core.types import MapFeature, ObjectInfo, SceneLog, Track, node_type_for_category

logger = logging.getLogger(__name__)

#: ``SceneLog.source`` of logs from this loader.
SCENARIO_SOURCE = "waymo-scenario"
#: ``Track.ObjectType`` enum -> shared category.
SCENARIO_CATEGORIES: dict[int, str] = {0: "other", 1: "vehicle", 2: "pedestrian", 3: "cyclist", 4: "other"}
#: ``LaneCenter.LaneType`` values kept as ``"lane"`` features (undefined, freeway, surface street).
VEHICLE_LANE_TYPES: frozenset[int] = frozenset({0, 1, 2})
#: Scenario map kind -> ``MapFeature.kind`` (stop signs and speed bumps go to metadata).
SCENARIO_MAP_KINDS: dict[str, str] = {
    "lane": "lane",
    "road_edge": "road_edge",
    "road_line": "lane_marking",
    "crosswalk": "crosswalk",
}
#: Decimals kept for world coordinates written to metadata JSON (millimetres).
_JSON_DECIMALS = 3
# Columns of ``ScenarioTrack.states``.
_X, _Y, _Z, _LENGTH, _WIDTH, _HEIGHT, _HEADING, _VX, _VY = range(9)


def is_waymo_scenario_file(path: Path) -> bool:
    """Whether ``path`` is a TFRecord file whose first record is a Waymo Open Motion ``Scenario`` (log-source
    detection)."""
    return path.is_file() and first_record_has(path, SCENARIO_SIGNATURE, "scenario_id")


def _where(record_index: int, field: str) -> str:
    return f"record {record_index}, field {field!r}"


def _ego_poses_global(path: Path, record_index: int, scenario: WaymoScenario) -> np.ndarray:
    """``[S, 4, 4]`` global poses of the SDC (planar, origin at the bottom of its box)."""
    sdc = scenario.tracks[scenario.sdc_track_index]
    invalid = np.flatnonzero(~sdc.valid)
    if invalid.size:
        field = f"Scenario.tracks[{scenario.sdc_track_index}].states[{invalid[0]}].valid"
        raise CorruptLogError(
            path,
            _where(record_index, field),
            f"the SDC track is invalid at {invalid.size} steps; the ego pose needs every step",
            record_index=record_index,
        )
    s = sdc.states
    return np.stack(
        [pose_from_yaw(row[_X], row[_Y], row[_Z] - 0.5 * row[_HEIGHT], row[_HEADING]) for row in s]
    )


def _check_sizes(path: Path, record_index: int, index: int, track: ScenarioTrack) -> None:
    sizes = track.states[track.valid][:, _LENGTH : _HEIGHT + 1]
    bad_row, bad_col = np.nonzero(~(sizes > 0))
    if bad_row.size:
        step = int(np.flatnonzero(track.valid)[bad_row[0]])
        name = ("length", "width", "height")[int(bad_col[0])]
        raise CorruptLogError(
            path,
            _where(record_index, f"Scenario.tracks[{index}].states[{step}].{name}"),
            f"non-positive box size {sizes[bad_row[0], bad_col[0]]} in a valid state",
            record_index=record_index,
        )


def _tracks_and_objects(
    path: Path, record_index: int, scenario: WaymoScenario, world_from_global: np.ndarray, timestamps_us: np.ndarray
) -> tuple[tuple[Track, ...], tuple[ObjectInfo, ...]]:
    """Tracks and objects of every non-SDC track (``world_from_global`` is ``[4, 4]``, ``timestamps_us`` ``[S]``)."""
    yaw_offset = float(np.arctan2(world_from_global[1, 0], world_from_global[0, 0]))  # global -> world yaw
    difficulty = {scenario.tracks[i].track_id: level for i, level in scenario.tracks_to_predict}
    interesting = set(scenario.objects_of_interest)
    candidates = []
    for index, track in enumerate(scenario.tracks):
        if index == scenario.sdc_track_index:
            continue
        if not track.valid.any():
            logger.warning("%s: track %d (id %d) has no valid state; dropped", path, index, track.track_id)
            continue
        _check_sizes(path, record_index, index, track)
        candidates.append((int(np.flatnonzero(track.valid)[0]), track.track_id, index, track))
    ids = collections.Counter(track_id for _, track_id, _, _ in candidates)
    duplicate = [track_id for track_id, n in ids.items() if n > 1]
    if duplicate:
        raise CorruptLogError(
            path, _where(record_index, "Scenario.tracks.id"), f"track id {duplicate[0]} appears twice"
        )
    tracks, objects = [], []
    for instance_id, (_, track_id, index, track) in enumerate(sorted(candidates), start=1):
        steps = np.flatnonzero(track.valid)
        states = track.states[steps]
        centers = transform_points(world_from_global, states[:, _X : _Z + 1])
        headings = wrap_angle(states[:, _HEADING] + yaw_offset)
        speeds = np.hypot(states[:, _VX], states[:, _VY])
        sizes = states[:, _LENGTH : _HEIGHT + 1]
        observations = [
            BoxObservation(int(f), centers[k], sizes[k], float(headings[k]), float(speeds[k]), True)
            for k, f in enumerate(steps)
        ]
        object_id = str(track_id)
        tracks.append(build_track(object_id, observations, timestamps_us))
        category = SCENARIO_CATEGORIES.get(track.object_type, "other")
        attributes = {
            "waymo_type": OBJECT_TYPES.get(track.object_type, str(track.object_type)),
            "waymo_track_index": str(index),
        }
        if track_id in difficulty:
            attributes["tracks_to_predict_difficulty"] = str(difficulty[track_id])
        if track_id in interesting:
            attributes["object_of_interest"] = "true"
        objects.append(
            ObjectInfo(
                object_id=object_id,
                category=category,
                node_type=node_type_for_category(category),
                instance_id=instance_id,
                attributes=attributes,
            )
        )
    return tuple(tracks), tuple(objects)


def _rounded(points: np.ndarray) -> list[list[float]]:
    return [[round(float(v), _JSON_DECIMALS) for v in p] for p in np.asarray(points).reshape(-1, 3)]


def _lane_ids(ids: tuple[int, ...]) -> list[str]:
    return [f"lane_{i}" for i in ids]


def _feature_attributes(feat: ScenarioMapFeature) -> dict[str, object]:
    """The ``MAP_FEATURE_ATTRIBUTES_KEY`` entry of one feature (empty for kinds without attributes)."""
    enum = MAP_TYPE_ENUMS.get(feat.kind)
    if enum is None:
        return {}
    out: dict[str, object] = {"type": enum.name_of(feat.type_id)}
    if feat.kind == "lane":
        out.update(
            entry_lanes=_lane_ids(feat.entry_lanes),
            left_neighbors=_lane_ids(feat.left_neighbors),
            right_neighbors=_lane_ids(feat.right_neighbors),
        )
        if feat.speed_limit_mph is not None:
            out["speed_limit_mph"] = float(feat.speed_limit_mph)
    return out


def _map(
    features: tuple[ScenarioMapFeature, ...], world_from_global: np.ndarray
) -> tuple[list[MapFeature], dict[str, str]]:
    """Map features in the world frame, plus the metadata entries for what has no ``MapFeature`` kind or field."""
    out: list[MapFeature] = []
    successors: dict[str, list[str]] = {}
    attributes: dict[str, dict[str, object]] = {}
    polygons: dict[str, list[dict[str, object]]] = {"speed_bump": [], "driveway": []}
    stop_signs = []
    skipped = collections.Counter[str]()
    for feat in features:
        points = transform_points(world_from_global, feat.points)
        if feat.kind == "lane" and feat.type_id not in VEHICLE_LANE_TYPES:
            skipped["non-vehicle lane"] += 1
            continue
        if feat.kind == "stop_sign":
            lanes = _lane_ids(feat.controlled_lanes)
            stop_signs.append({"id": feat.feature_id, "position": _rounded(points)[0], "lanes": lanes})
            continue
        if feat.kind in polygons:
            polygons[feat.kind].append({"id": feat.feature_id, "polygon": _rounded(points)})
            continue
        kind = SCENARIO_MAP_KINDS[feat.kind]
        feature_id = f"{feat.kind}_{feat.feature_id}"
        out.append(MapFeature(feature_id, kind, points))
        if feat.kind == "lane":
            successors[feature_id] = _lane_ids(feat.exit_lanes)
        feature_attributes = _feature_attributes(feat)
        if feature_attributes:
            attributes[feature_id] = feature_attributes
    metadata = {
        LANE_SUCCESSORS_KEY: json.dumps(successors, sort_keys=True),
        MAP_FEATURE_ATTRIBUTES_KEY: json.dumps(attributes, sort_keys=True),
        "stop_signs": json.dumps(stop_signs),
        "speed_bumps": json.dumps(polygons["speed_bump"]),
        "driveways": json.dumps(polygons["driveway"]),
        "skipped_map_features": json.dumps(dict(skipped), sort_keys=True),
    }
    return out, metadata


def _signals_json(scenario: WaymoScenario, world_from_global: np.ndarray) -> str:
    steps = []
    for states in scenario.signals:
        row = []
        for st in states:
            stop: list[float | None] = [None] * 3
            if st.stop_point is not None:
                stop = list(_rounded(transform_points(world_from_global, st.stop_point))[0])
            row.append([f"lane_{st.lane_id}", SIGNAL_STATES.get(st.state, str(st.state)), *stop])
        steps.append(row)
    return json.dumps(steps)


def load_waymo_scenario(path: str | Path, record_index: int = 0, seq_id: str | None = None) -> SceneLog:
    """Load one Waymo Open Motion ``Scenario`` of a TFRecord file as a ``SceneLog`` (see module docstring).

    Args:
        path: TFRecord file of ``Scenario`` records.
        record_index: which record (scenario) to load; every record is CRC-checked and decoded.
        seq_id: sequence id; default: the ``scenario_id`` made directory-safe.

    Returns:
        A validated ``SceneLog`` (``source=SCENARIO_SOURCE``) with no images, one frame per step.

    Raises:
        CorruptLogError: truncated file, CRC mismatch, malformed proto, a missing required field, an
            SDC that is invalid at some step, a non-positive box size, duplicate track ids or non-
            increasing timestamps; the message names the file, the record and the field.
        IndexError: ``record_index`` is not a record of the file.
    """
    path = Path(path)
    t0 = time.perf_counter()
    records = parse_tfrecords(path, parse_scenario)
    if not 0 <= record_index < len(records):
        raise IndexError(f"{path}: record {record_index} requested, the file has {len(records)} scenarios")
    _, scenario = records[record_index]
    timestamps_us = np.round(scenario.timestamps_s * 1e6).astype(np.int64)
    bad = np.flatnonzero(np.diff(timestamps_us) <= 0)
    if bad.size:
        raise CorruptLogError(
            path,
            _where(record_index, f"Scenario.timestamps_seconds[{bad[0] + 1}]"),
            f"timestamp {scenario.timestamps_s[bad[0] + 1]} does not increase",
            record_index=record_index,
        )
    global_poses = _ego_poses_global(path, record_index, scenario)
    world_from_global = invert_transform(global_poses[0])
    ego_poses = world_from_global @ global_poses
    ego_poses[0] = np.eye(4)
    tracks, objects = _tracks_and_objects(path, record_index, scenario, world_from_global, timestamps_us)
    map_features, map_metadata = _map(scenario.map_features, world_from_global)
    sdc = scenario.tracks[scenario.sdc_track_index]
    metadata = {
        "source_file": str(path),
        "record_index": str(record_index),
        "scenario_id": scenario.scenario_id,
        "current_time_index": str(scenario.current_time_index),
        "sdc_track_id": str(sdc.track_id),
        "ego_size": json.dumps([round(float(v), _JSON_DECIMALS) for v in sdc.states[0, _LENGTH : _HEIGHT + 1]]),
        "ego_pose": "SDC box centre at the bottom of its box, yaw only",
        "global_SE3_world": json.dumps(global_poses[0].round(9).tolist()),
        "tracks_to_predict": json.dumps([scenario.tracks[i].track_id for i, _ in scenario.tracks_to_predict]),
        "objects_of_interest": json.dumps(list(scenario.objects_of_interest)),
        "traffic_signals": _signals_json(scenario, world_from_global),
        "traffic_signal_columns": "lane feature id, state, stop point x, y, z (world frame)",
        **map_metadata,
    }
    log = SceneLog(
        seq_id=seq_id if seq_id is not None else safe_seq_id(scenario.scenario_id),
        source=SCENARIO_SOURCE,
        timestamps_us=timestamps_us,
        ego_poses=ego_poses,
        tracks=tracks,
        objects=objects,
        map_features=tuple(map_features),
        metadata=metadata,
    )
    return loaded(log, path, t0, scenario.scenario_id)
