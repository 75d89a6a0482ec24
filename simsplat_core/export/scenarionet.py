"""ScenarioNet scenario descriptions of ``ExportScenario`` records: one pickle per scenario plus the dataset's summary
and mapping, as MetaDrive's ``ScenarioEnv``, ScenarioNet's tools, UniTraj and ScenarioMax read them.

Everything is plain Python (dicts with string keys, lists, tuples, ``str`` / ``int`` / ``float`` / ``bool`` /
``None``) and numpy arrays, so a pickle loads without this package. Which published reader each part follows:

* top level ``id``, ``version``, ``length``, ``tracks``, ``dynamic_map_states``, ``map_features``, ``metadata``:
  MetaDrive's ``ScenarioDescription`` (its ``FIRST_LEVEL_KEYS`` and ``sanity_check``: string dict keys, only the
  allowed value types, every state array ``length`` long, invalid steps zero, types from ``MetaDriveType``).
  ``version`` is ``SCENARIO_VERSION``, the data version string MetaDrive writes into its own scenario exports;
  no reader checks more than its presence.
* ``tracks``: keyed by the track id as a string; the state arrays and per-track metadata as ScenarioNet's Waymo
  converter writes them (float32 ``position [T, 3]``, ``length`` / ``width`` / ``height`` / ``heading [T]``,
  ``velocity [T, 2]``, bool ``valid [T]``); UniTraj stacks all seven, so all seven are always there. Types:
  ``AGENT_TYPE_NAMES`` (``"unset"`` becomes ``OTHER``: ``sanity_check`` rejects ``UNSET``).
* ``dynamic_map_states``: as the Waymo converter, one ``TRAFFIC_LIGHT`` per controlled lane, keyed by the lane id:
  ``state.object_state`` a list of ``T`` WOMD state names (``None`` at steps without a state), ``lane`` the lane
  id, ``stop_point`` float32 ``[3]`` (the last one given; zeros when none), and ``metadata`` whose ``object_id`` is
  the key (``sanity_check``). UniTraj reads ``lane``, ``stop_point.tolist()`` and ``object_state``.
* ``map_features``: keyed by the feature id as a string; the per-kind fields of the Waymo converter. Lanes:
  ``polyline``, ``speed_limit_mph`` / ``speed_limit_kmh`` (0 when unknown), ``interpolating`` (False),
  ``entry_lanes`` / ``exit_lanes`` (ids as strings, so that they index ``map_features``), ``left_neighbor`` /
  ``right_neighbor`` (the converter's neighbour dicts, which UniTraj reads: ``feature_id`` and index ranges as
  strings, here each lane's whole length), ``left_boundaries`` / ``right_boundaries`` (empty: the record has no
  boundary links). Road lines and edges: ``polyline``. Stop signs: ``lane`` (controlled lane ids) and
  ``position [3]``. Crosswalks, speed bumps, driveways: ``polygon``. Points are float32 ``[P, 3]``. Types:
  ``MAP_TYPE_NAMES``, one table from (kind, WOMD type) to the ``MetaDriveType`` string.
* ``metadata``: ``sanity_check``'s required keys (``metadrive_processed``, ``coordinate``, float32 ``ts [T]``),
  the Waymo converter's (``id``, ``scenario_id``, ``dataset``, ``source_file``, ``sdc_id``, ``sdc_track_index``,
  ``current_time_index``, ``track_length``, ``objects_of_interest`` as string ids, ``tracks_to_predict`` as
  ``{track id: {track_index, track_id, difficulty, object_type}}``, the form UniTraj reads), the
  ``object_summary`` / ``number_summary`` that ScenarioNet's ``update_summaries`` adds (its filters read them from
  the summary; the type sets are sorted tuples here, so the bytes of a pickle do not depend on string hashing),
  plus ``dataset_version`` and the record's own ``metadata`` strings under ``"simsplat"``.
* dataset files: ``dataset_summary`` (file name -> the scenario's metadata with arrays as lists and sets as
  tuples, what ScenarioNet writes to ``dataset_summary.pkl``) and ``dataset_mapping`` (file name -> directory
  relative to the summary, ``dataset_mapping.pkl``); file names ``sd_<dataset>_<dataset version>_<id>.pkl`` as
  ``ScenarioDescription.get_export_file_name`` makes them (readers accept any ``.pkl`` name starting ``sd_``).
  The description's ``id`` is the file-safe form of the record's ``scenario_id`` (``scenario_file_id``);
  ``metadata["scenario_id"]`` keeps the record's id as it is.

Coordinates stay in the record's world frame (metres, right-handed, z up, headings counter-clockwise from +x):
``coordinate`` is ``"waymo"``, as for WOMD data; MetaDrive's reader re-centres on the SDC's first position itself.
"""

from __future__ import annotations

import hashlib
import pickle
import re
from collections import Counter
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

from simsplat_core.export.record import (
    HEADING,
    HEIGHT,
    LENGTH,
    POLYGON_KINDS,
    VX,
    VY,
    WIDTH,
    ExportMapFeature,
    ExportScenario,
    X,
    Z,
)

#: ``version`` of every description: MetaDrive's data version string (``metadrive.constants.DATA_VERSION``).
SCENARIO_VERSION = "MetaDrive v0.4.3"
#: Default dataset name (``metadata["dataset"]``, ``metadata.tracks[*].dataset`` and the file names).
DATASET_NAME = "simsplat"
#: Default dataset version (file names, ``metadata["dataset_version"]``).
DATASET_VERSION = "v1"
#: ``metadata["coordinate"]``: WOMD's right-handed world frame (MetaDrive's ``COORDINATE_WAYMO``).
COORDINATE = "waymo"
#: Pickle protocol of every file (Python 3.8+ readers load it).
PICKLE_PROTOCOL = 4
#: The dataset's summary and mapping file names (``ScenarioDescription.DATASET``).
SUMMARY_FILE_NAME = "dataset_summary.pkl"
MAPPING_FILE_NAME = "dataset_mapping.pkl"
#: Type of every ``dynamic_map_states`` entry.
TRAFFIC_LIGHT = "TRAFFIC_LIGHT"
#: A track moving further than this (metres, summed over valid steps) counts as moving in ``number_summary``.
MOVING_DISTANCE_M = 1.0
_MPH_TO_KMH = 1.609344

#: ``ExportScenario.agent_types`` value -> ``MetaDriveType`` agent string.
AGENT_TYPE_NAMES: dict[str, str] = {
    "unset": "OTHER",
    "vehicle": "VEHICLE",
    "pedestrian": "PEDESTRIAN",
    "cyclist": "CYCLIST",
    "other": "OTHER",
}

#: Map kind -> WOMD type name (``""``: untyped) -> ``MetaDriveType`` string. Untyped and WOMD's unknown types take
#: a concrete default: lanes ``LANE_SURFACE_STREET``, road edges ``ROAD_EDGE_BOUNDARY``, road lines MetaDrive's
#: ``LINE_UNKNOWN`` (``"UNKNOWN_LINE"``; ScenarioNet's Waymo converter writes ``"UNKNOWN"``, which MetaDrive
#: counts as a road edge).
MAP_TYPE_NAMES: dict[str, dict[str, str]] = {
    "lane": {
        "": "LANE_SURFACE_STREET",
        "TYPE_UNDEFINED": "LANE_SURFACE_STREET",
        "TYPE_FREEWAY": "LANE_FREEWAY",
        "TYPE_SURFACE_STREET": "LANE_SURFACE_STREET",
        "TYPE_BIKE_LANE": "LANE_BIKE_LANE",
    },
    "road_line": {
        "": "UNKNOWN_LINE",
        "TYPE_UNKNOWN": "UNKNOWN_LINE",
        "TYPE_BROKEN_SINGLE_WHITE": "ROAD_LINE_BROKEN_SINGLE_WHITE",
        "TYPE_SOLID_SINGLE_WHITE": "ROAD_LINE_SOLID_SINGLE_WHITE",
        "TYPE_SOLID_DOUBLE_WHITE": "ROAD_LINE_SOLID_DOUBLE_WHITE",
        "TYPE_BROKEN_SINGLE_YELLOW": "ROAD_LINE_BROKEN_SINGLE_YELLOW",
        "TYPE_BROKEN_DOUBLE_YELLOW": "ROAD_LINE_BROKEN_DOUBLE_YELLOW",
        "TYPE_SOLID_SINGLE_YELLOW": "ROAD_LINE_SOLID_SINGLE_YELLOW",
        "TYPE_SOLID_DOUBLE_YELLOW": "ROAD_LINE_SOLID_DOUBLE_YELLOW",
        "TYPE_PASSING_DOUBLE_YELLOW": "ROAD_LINE_PASSING_DOUBLE_YELLOW",
    },
    "road_edge": {
        "": "ROAD_EDGE_BOUNDARY",
        "TYPE_UNKNOWN": "ROAD_EDGE_BOUNDARY",
        "TYPE_ROAD_EDGE_BOUNDARY": "ROAD_EDGE_BOUNDARY",
        "TYPE_ROAD_EDGE_MEDIAN": "ROAD_EDGE_MEDIAN",
    },
    "stop_sign": {"": "STOP_SIGN"},
    "crosswalk": {"": "CROSSWALK"},
    "speed_bump": {"": "SPEED_BUMP"},
    "driveway": {"": "DRIVEWAY"},
}

#: ``MetaDriveType`` road-line strings (``map_height_diff`` measures these).
_ROAD_LINE_NAMES = frozenset(MAP_TYPE_NAMES["road_line"].values())
_UNSAFE_FILE_CHARS = re.compile(r"[^A-Za-z0-9._-]+")


def map_type_name(kind: str, womd_type: str) -> str:
    """The ``MetaDriveType`` string of a map feature of ``kind`` with WOMD type ``womd_type`` (``""``: untyped).

    Raises:
        ValueError: a kind or type outside ``MAP_TYPE_NAMES`` (named).
    """
    names = MAP_TYPE_NAMES.get(kind)
    if names is None:
        raise ValueError(f"map kind {kind!r} has no ScenarioNet type; known kinds: {sorted(MAP_TYPE_NAMES)}")
    if womd_type not in names:
        raise ValueError(f"{kind} type {womd_type!r} has no ScenarioNet type; known: {sorted(names)}")
    return names[womd_type]


def scenario_file_id(scenario_id: str) -> str:
    """``scenario_id`` as a file-name part: itself when it only has letters, digits, ``.``, ``_`` and ``-``; else
    the runs of other characters replaced by ``-`` plus ``-`` and 8 hex digits of its SHA-1 (distinct ids stay
    distinct)."""
    if not scenario_id:
        raise ValueError("scenario_id must not be empty")
    if not _UNSAFE_FILE_CHARS.search(scenario_id):
        return scenario_id
    digest = hashlib.sha1(scenario_id.encode("utf-8")).hexdigest()[:8]
    return f"{_UNSAFE_FILE_CHARS.sub('-', scenario_id).strip('-')}-{digest}"


def scenario_file_name(scenario_id: str, dataset: str = DATASET_NAME, dataset_version: str = DATASET_VERSION) -> str:
    """``sd_<dataset>_<dataset_version>_<file id>.pkl``, the scenario's file name (``scenario_file_id``)."""
    for name, value in (("dataset", dataset), ("dataset_version", dataset_version)):
        if not value or _UNSAFE_FILE_CHARS.search(value):
            raise ValueError(f"{name} {value!r} must be non-empty letters, digits, '.', '_' or '-'")
    return f"sd_{dataset}_{dataset_version}_{scenario_file_id(scenario_id)}.pkl"


def scenario_description(
    record: ExportScenario, dataset: str = DATASET_NAME, dataset_version: str = DATASET_VERSION
) -> dict[str, Any]:
    """The ScenarioNet scenario description of ``record`` (module docstring): a plain dict, ``T`` steps long."""
    record.validate()
    lane_points = {f.feature_id: len(f.points) for f in record.map_features if f.kind == "lane"}
    description: dict[str, Any] = {
        "id": scenario_file_id(record.scenario_id),
        "version": SCENARIO_VERSION,
        "length": record.num_steps,
        "tracks": _tracks(record, dataset),
        "dynamic_map_states": _dynamic_map_states(record, dataset),
        "map_features": {str(f.feature_id): _map_feature(f, lane_points) for f in record.map_features},
    }
    description["metadata"] = _metadata(record, description, dataset, dataset_version)
    return description


def to_pickle(value: object) -> bytes:
    """Pickle bytes (``PICKLE_PROTOCOL``) of a description, a summary or a mapping."""
    return pickle.dumps(value, protocol=PICKLE_PROTOCOL)


def dataset_summary(descriptions: Mapping[str, Mapping[str, Any]]) -> dict[str, dict[str, Any]]:
    """``{file name: the description's metadata}`` with numpy arrays as lists and sets as tuples (recursively),
    as ScenarioNet writes ``dataset_summary.pkl``. ``descriptions`` maps each file name to its description."""
    return {name: _plain(dict(description["metadata"])) for name, description in descriptions.items()}


def dataset_mapping(file_names: Iterable[str], directory: str = "") -> dict[str, str]:
    """``{file name: directory}``: where each scenario file lies relative to the summary (``""``: beside it), as
    ScenarioNet writes ``dataset_mapping.pkl``."""
    return {name: directory for name in file_names}


def _f32(values: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(values, dtype=np.float32)


def _tracks(record: ExportScenario, dataset: str) -> dict[str, dict[str, Any]]:
    """``tracks``: one entry per track row; states zeroed at invalid steps."""
    t = record.num_steps
    valid = np.asarray(record.valid, dtype=bool)
    states = np.where(valid[..., None], np.asarray(record.states, dtype=np.float64), 0.0)  # [A, T, 9]
    out: dict[str, dict[str, Any]] = {}
    for row, track_id in enumerate(record.track_ids.tolist()):
        key = str(track_id)
        type_name = AGENT_TYPE_NAMES[record.agent_types[row]]
        s = states[row]
        metadata: dict[str, Any] = {"track_length": t, "type": type_name, "object_id": key, "dataset": dataset}
        if record.track_sources:
            metadata["source"] = record.track_sources[row]
        if record.source_object_ids:
            metadata["original_id"] = record.source_object_ids[row]
        out[key] = {
            "type": type_name,
            "state": {
                "position": _f32(s[:, X : Z + 1]),
                "length": _f32(s[:, LENGTH]),
                "width": _f32(s[:, WIDTH]),
                "height": _f32(s[:, HEIGHT]),
                "heading": _f32(s[:, HEADING]),
                "velocity": _f32(s[:, [VX, VY]]),
                "valid": valid[row].copy(),
            },
            "metadata": metadata,
        }
    return out


def _dynamic_map_states(record: ExportScenario, dataset: str) -> dict[str, dict[str, Any]]:
    """``dynamic_map_states``: one traffic light per lane that has a signal state at some step."""
    t = record.num_steps
    states: dict[int, list[str | None]] = {}
    stop_points: dict[int, np.ndarray] = {}
    for step, step_signals in enumerate(record.signals):
        for signal in step_signals:
            states.setdefault(signal.lane_id, [None] * t)[step] = signal.state
            if signal.stop_point is not None:
                stop_points[signal.lane_id] = np.asarray(signal.stop_point, dtype=np.float64).reshape(3)
    out: dict[str, dict[str, Any]] = {}
    for lane_id in sorted(states):
        key = str(lane_id)
        out[key] = {
            "type": TRAFFIC_LIGHT,
            "state": {"object_state": states[lane_id]},
            "lane": key,
            "stop_point": _f32(stop_points.get(lane_id, np.zeros(3))),
            "metadata": {"track_length": t, "type": TRAFFIC_LIGHT, "object_id": key, "dataset": dataset},
        }
    return out


def _neighbours(feature_ids: tuple[int, ...], num_points: int, by_id: Mapping[int, int]) -> list[dict[str, Any]]:
    """The Waymo converter's neighbour dicts: whole-length index ranges (the record has no finer ones)."""
    return [
        {
            "feature_id": str(fid),
            "self_start_index": "0",
            "self_end_index": str(num_points - 1),
            "neighbor_start_index": "0",
            "neighbor_end_index": str(max(by_id.get(fid, 1) - 1, 0)),
            "boundaries": [],
        }
        for fid in feature_ids
    ]


def _map_feature(feature: ExportMapFeature, lane_points: Mapping[int, int]) -> dict[str, Any]:
    """One ``map_features`` entry (``lane_points``: point count per lane id, for neighbour index ranges)."""
    points = _f32(feature.points)
    out: dict[str, Any] = {"type": map_type_name(feature.kind, feature.type)}
    if feature.kind == "lane":
        out.update(
            polyline=points,
            speed_limit_mph=float(feature.speed_limit_mph),
            speed_limit_kmh=float(feature.speed_limit_mph) * _MPH_TO_KMH,
            interpolating=False,
            entry_lanes=[str(i) for i in feature.entry_lanes],
            exit_lanes=[str(i) for i in feature.exit_lanes],
            left_boundaries=[],
            right_boundaries=[],
            left_neighbor=_neighbours(feature.left_neighbors, len(points), lane_points),
            right_neighbor=_neighbours(feature.right_neighbors, len(points), lane_points),
        )
    elif feature.kind == "stop_sign":
        out.update(lane=[str(i) for i in feature.controlled_lanes], position=points[0].copy())
    elif feature.kind in POLYGON_KINDS:
        out["polygon"] = points
    else:
        out["polyline"] = points
    return out


def _object_summary(key: str, track: Mapping[str, Any]) -> dict[str, Any]:
    """ScenarioNet's per-object summary: moving distance over valid steps (2D), valid and first-run lengths."""
    valid = track["state"]["valid"]
    xy = track["state"]["position"][valid, :2].astype(np.float64)
    runs = np.flatnonzero(np.diff(np.r_[0, valid.astype(np.int8), 0]))  # starts and ends of valid runs
    return {
        "type": track["type"],
        "object_id": key,
        "track_length": len(valid),
        "moving_distance": float(np.linalg.norm(np.diff(xy, axis=0), axis=1).sum()),
        "valid_length": int(valid.sum()),
        "continuous_valid_length": int(runs[1] - runs[0]) if runs.size else 0,
    }


def _map_height_diff(map_features: Mapping[str, Mapping[str, Any]]) -> float:
    """Height range (metres) of the road-line points; 0 without road lines."""
    heights = [f["polyline"][:, 2] for f in map_features.values() if f["type"] in _ROAD_LINE_NAMES]
    if not heights:
        return 0.0
    z = np.concatenate(heights)
    return float(z.max() - z.min())


def _number_summary(description: Mapping[str, Any], object_summary: Mapping[str, Mapping[str, Any]]) -> dict[str, Any]:
    """ScenarioNet's per-scenario counts (object types, moving objects, signal states, map features)."""
    types = Counter(track["type"] for track in description["tracks"].values())
    moving = Counter(s["type"] for s in object_summary.values() if s["moving_distance"] > MOVING_DISTANCE_M)
    light_states = Counter(
        state
        for light in description["dynamic_map_states"].values()
        for state in light["state"]["object_state"]
        if state is not None
    )
    return {
        "num_objects": len(description["tracks"]),
        "object_types": tuple(sorted(types)),
        "num_objects_each_type": dict(sorted(types.items())),
        "num_moving_objects": sum(moving.values()),
        "num_moving_objects_each_type": dict(sorted(moving.items())),
        "num_traffic_lights": len(description["dynamic_map_states"]),
        "num_traffic_light_types": tuple(sorted(light_states)),
        "num_traffic_light_each_step": dict(sorted(light_states.items())),
        "num_map_features": len(description["map_features"]),
        "map_height_diff": _map_height_diff(description["map_features"]),
    }


def _metadata(
    record: ExportScenario, description: Mapping[str, Any], dataset: str, dataset_version: str
) -> dict[str, Any]:
    """``metadata``: the required keys, the Waymo converter's keys, the summaries and the record's own strings."""
    tracks = description["tracks"]
    track_keys = [str(i) for i in record.track_ids.tolist()]
    object_summary = {key: _object_summary(key, track) for key, track in tracks.items()}
    return {
        "id": description["id"],
        "scenario_id": record.scenario_id,
        "dataset": dataset,
        "dataset_version": dataset_version,
        "source_file": record.metadata.get("source_file", record.scenario_id),
        "coordinate": COORDINATE,
        "metadrive_processed": False,
        "ts": _f32(record.timestamps_s),
        "track_length": record.num_steps,
        "current_time_index": int(record.current_time_index),
        "sdc_id": track_keys[record.sdc_index],
        "sdc_track_index": int(record.sdc_index),
        "objects_of_interest": [str(i) for i in record.objects_of_interest],
        "tracks_to_predict": {
            track_keys[row]: {
                "track_index": int(row),
                "track_id": track_keys[row],
                "difficulty": 0,
                "object_type": tracks[track_keys[row]]["type"],
            }
            for row in record.tracks_to_predict
        },
        "object_summary": object_summary,
        "number_summary": _number_summary(description, object_summary),
        "simsplat": {str(k): str(v) for k, v in record.metadata.items()},
    }


def _plain(value: Any) -> Any:
    """``value`` with numpy arrays as lists and sets as sorted tuples, through dicts, lists and tuples."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, set | frozenset):
        return tuple(sorted(value))
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return type(value)(_plain(v) for v in value)
    return value
