"""Waymo Open Motion's ``Scenario`` messages (``scenario.proto`` / ``map.proto``): their schemas and the decoder.

The schemas below are the project's one definition of these messages: field numbers, types, enum values, packing
and ``oneof`` groups follow the public protos (proto2, waymo-open-dataset ``waymo_open_dataset/protos``). They
decode with ``protowire`` (no TensorFlow, no generated ``*_pb2`` modules) and, through
``simsplat_core.export.womd_messages``, define the protobuf runtime classes the WOMD exporter writes with.
Not defined: ``Scenario.compressed_frame_laser_data`` and ``frame_camera_tokens`` (skipped as unknown fields).
Decoded into ``WaymoScenario``: everything but lane boundaries (``LaneCenter.left/right_boundaries``), the
adjacency segments of lane neighbours (only their lane ids are kept) and ``LaneCenter.interpolating``.

Units and frames: metres in an arbitrary global frame (the loader moves everything to the SDC's
first pose); headings are radians counter-clockwise from global +x; time in seconds.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from simsplat_core.data.protowire import EnumSchema, Field, MessageSchema, ProtoDecodeError, decode_message

OBJECT_TYPE = EnumSchema("ObjectType", ("TYPE_UNSET", "TYPE_VEHICLE", "TYPE_PEDESTRIAN", "TYPE_CYCLIST", "TYPE_OTHER"))
SIGNAL_STATE = EnumSchema(
    "State",
    (
        "LANE_STATE_UNKNOWN",
        "LANE_STATE_ARROW_STOP",
        "LANE_STATE_ARROW_CAUTION",
        "LANE_STATE_ARROW_GO",
        "LANE_STATE_STOP",
        "LANE_STATE_CAUTION",
        "LANE_STATE_GO",
        "LANE_STATE_FLASHING_STOP",
        "LANE_STATE_FLASHING_CAUTION",
    ),
)
LANE_TYPE = EnumSchema("LaneType", ("TYPE_UNDEFINED", "TYPE_FREEWAY", "TYPE_SURFACE_STREET", "TYPE_BIKE_LANE"))
ROAD_LINE_TYPE = EnumSchema(
    "RoadLineType",
    (
        "TYPE_UNKNOWN",
        "TYPE_BROKEN_SINGLE_WHITE",
        "TYPE_SOLID_SINGLE_WHITE",
        "TYPE_SOLID_DOUBLE_WHITE",
        "TYPE_BROKEN_SINGLE_YELLOW",
        "TYPE_BROKEN_DOUBLE_YELLOW",
        "TYPE_SOLID_SINGLE_YELLOW",
        "TYPE_SOLID_DOUBLE_YELLOW",
        "TYPE_PASSING_DOUBLE_YELLOW",
    ),
)
ROAD_EDGE_TYPE = EnumSchema("RoadEdgeType", ("TYPE_UNKNOWN", "TYPE_ROAD_EDGE_BOUNDARY", "TYPE_ROAD_EDGE_MEDIAN"))
DIFFICULTY_LEVEL = EnumSchema("DifficultyLevel", ("NONE", "LEVEL_1", "LEVEL_2"))

#: ``Track.ObjectType`` enum -> Waymo's type name.
OBJECT_TYPES: dict[int, str] = dict(enumerate(OBJECT_TYPE.values))
#: ``TrafficSignalLaneState.State`` enum -> Waymo's state name.
SIGNAL_STATES: dict[int, str] = dict(enumerate(SIGNAL_STATE.values))
#: The ``MapFeature.feature_data`` member whose enum is the feature's type.
MAP_TYPE_ENUMS: dict[str, EnumSchema] = {"lane": LANE_TYPE, "road_line": ROAD_LINE_TYPE, "road_edge": ROAD_EDGE_TYPE}

OBJECT_STATE = MessageSchema(
    "ObjectState",
    (
        Field(2, "center_x", "double"),
        Field(3, "center_y", "double"),
        Field(4, "center_z", "double"),
        Field(5, "length", "float"),
        Field(6, "width", "float"),
        Field(7, "height", "float"),
        Field(8, "heading", "float"),
        Field(9, "velocity_x", "float"),
        Field(10, "velocity_y", "float"),
        Field(11, "valid", "bool"),
    ),
)
TRACK = MessageSchema(
    "Track",
    (
        Field(1, "id", "int32"),
        Field(2, "object_type", "enum", enum=OBJECT_TYPE),
        Field(3, "states", "message", repeated=True, message=OBJECT_STATE),
    ),
    enums=(OBJECT_TYPE,),
)
MAP_POINT = MessageSchema("MapPoint", (Field(1, "x", "double"), Field(2, "y", "double"), Field(3, "z", "double")))
SIGNAL_LANE_STATE = MessageSchema(
    "TrafficSignalLaneState",
    (
        Field(1, "lane", "int64"),
        Field(2, "state", "enum", enum=SIGNAL_STATE),
        Field(3, "stop_point", "message", message=MAP_POINT),
    ),
    enums=(SIGNAL_STATE,),
)
DYNAMIC_MAP_STATE = MessageSchema(
    "DynamicMapState", (Field(1, "lane_states", "message", repeated=True, message=SIGNAL_LANE_STATE),)
)
BOUNDARY_SEGMENT = MessageSchema(
    "BoundarySegment",
    (
        Field(1, "lane_start_index", "int32"),
        Field(2, "lane_end_index", "int32"),
        Field(3, "boundary_feature_id", "int64"),
        Field(4, "boundary_type", "enum", enum=ROAD_LINE_TYPE),
    ),
)
LANE_NEIGHBOR = MessageSchema(
    "LaneNeighbor",
    (
        Field(1, "feature_id", "int64"),
        Field(2, "self_start_index", "int32"),
        Field(3, "self_end_index", "int32"),
        Field(4, "neighbor_start_index", "int32"),
        Field(5, "neighbor_end_index", "int32"),
        Field(6, "boundaries", "message", repeated=True, message=BOUNDARY_SEGMENT),
    ),
)
LANE_CENTER = MessageSchema(
    "LaneCenter",
    (
        Field(1, "speed_limit_mph", "double"),
        Field(2, "type", "enum", enum=LANE_TYPE),
        Field(3, "interpolating", "bool"),
        Field(8, "polyline", "message", repeated=True, message=MAP_POINT),
        Field(9, "entry_lanes", "int64", repeated=True, packed=True),
        Field(10, "exit_lanes", "int64", repeated=True, packed=True),
        Field(11, "left_neighbors", "message", repeated=True, message=LANE_NEIGHBOR),
        Field(12, "right_neighbors", "message", repeated=True, message=LANE_NEIGHBOR),
        Field(13, "left_boundaries", "message", repeated=True, message=BOUNDARY_SEGMENT),
        Field(14, "right_boundaries", "message", repeated=True, message=BOUNDARY_SEGMENT),
    ),
    enums=(LANE_TYPE,),
)
ROAD_LINE = MessageSchema(
    "RoadLine",
    (
        Field(1, "type", "enum", enum=ROAD_LINE_TYPE),
        Field(2, "polyline", "message", repeated=True, message=MAP_POINT),
    ),
    enums=(ROAD_LINE_TYPE,),
)
ROAD_EDGE = MessageSchema(
    "RoadEdge",
    (
        Field(1, "type", "enum", enum=ROAD_EDGE_TYPE),
        Field(2, "polyline", "message", repeated=True, message=MAP_POINT),
    ),
    enums=(ROAD_EDGE_TYPE,),
)
STOP_SIGN = MessageSchema(
    "StopSign", (Field(1, "lane", "int64", repeated=True), Field(2, "position", "message", message=MAP_POINT))
)
CROSSWALK = MessageSchema("Crosswalk", (Field(1, "polygon", "message", repeated=True, message=MAP_POINT),))
SPEED_BUMP = MessageSchema("SpeedBump", (Field(1, "polygon", "message", repeated=True, message=MAP_POINT),))
DRIVEWAY = MessageSchema("Driveway", (Field(1, "polygon", "message", repeated=True, message=MAP_POINT),))
_FEATURE_DATA = "feature_data"
MAP_FEATURE = MessageSchema(
    "MapFeature",
    (
        Field(1, "id", "int64"),
        Field(3, "lane", "message", message=LANE_CENTER, oneof=_FEATURE_DATA),
        Field(4, "road_line", "message", message=ROAD_LINE, oneof=_FEATURE_DATA),
        Field(5, "road_edge", "message", message=ROAD_EDGE, oneof=_FEATURE_DATA),
        Field(7, "stop_sign", "message", message=STOP_SIGN, oneof=_FEATURE_DATA),
        Field(8, "crosswalk", "message", message=CROSSWALK, oneof=_FEATURE_DATA),
        Field(9, "speed_bump", "message", message=SPEED_BUMP, oneof=_FEATURE_DATA),
        Field(10, "driveway", "message", message=DRIVEWAY, oneof=_FEATURE_DATA),
    ),
)
#: ``MapFeature`` oneof member -> its field number.
MAP_FEATURE_KINDS: dict[str, int] = {f.name: f.number for f in MAP_FEATURE.fields if f.oneof == _FEATURE_DATA}
#: Map kinds whose points are a polygon (closed implicitly).
POLYGON_KINDS: frozenset[str] = frozenset({"crosswalk", "speed_bump", "driveway"})
REQUIRED_PREDICTION = MessageSchema(
    "RequiredPrediction",
    (Field(1, "track_index", "int32"), Field(2, "difficulty", "enum", enum=DIFFICULTY_LEVEL)),
    enums=(DIFFICULTY_LEVEL,),
)
SCENARIO = MessageSchema(
    "Scenario",
    (
        Field(1, "timestamps_seconds", "double", repeated=True),
        Field(2, "tracks", "message", repeated=True, message=TRACK),
        Field(4, "objects_of_interest", "int32", repeated=True),
        Field(5, "scenario_id", "string"),
        Field(6, "sdc_track_index", "int32"),
        Field(7, "dynamic_map_states", "message", repeated=True, message=DYNAMIC_MAP_STATE),
        Field(8, "map_features", "message", repeated=True, message=MAP_FEATURE),
        Field(10, "current_time_index", "int32"),
        Field(11, "tracks_to_predict", "message", repeated=True, message=REQUIRED_PREDICTION),
    ),
)

#: The top-level fields that tell a ``Scenario`` from a ``Frame`` by wire type (``tracks`` is a message where
#: ``Frame.timestamp_micros`` is a varint); for source detection with ``common.first_record_has``.
SCENARIO_SIGNATURE = MessageSchema(
    "Scenario",
    (
        Field(2, "tracks", "message", repeated=True, message=MessageSchema("Track", ())),
        Field(5, "scenario_id", "string"),
    ),
)

_STATE_KEYS = ("center_x", "center_y", "center_z", "length", "width", "height", "heading", "velocity_x", "velocity_y")


@dataclass(frozen=True)
class ScenarioTrack:
    """One object's states over all steps of a scenario (global frame).

    Attributes:
        track_id: ``Track.id`` (non-negative, unique in the scenario).
        object_type: ``Track.ObjectType`` enum value.
        states: ``[S, 9]`` float64 per step: ``center_x, center_y, center_z, length, width, height,
            heading, velocity_x, velocity_y`` (zeros where a field is absent).
        valid: ``[S]`` bool, ``ObjectState.valid``.
    """

    track_id: int
    object_type: int
    states: np.ndarray
    valid: np.ndarray


@dataclass(frozen=True)
class ScenarioMapFeature:
    """One map feature in the global frame.

    Attributes:
        feature_id: ``MapFeature.id``.
        kind: the set ``oneof`` member, a key of ``MAP_FEATURE_KINDS``.
        points: ``[P, 3]`` float64 polyline (lane, road_line, road_edge), polygon (``POLYGON_KINDS``) or
            the single position of a stop sign.
        type_id: ``LaneType`` / ``RoadLineType`` / ``RoadEdgeType`` enum (``MAP_TYPE_ENUMS``), 0 for other kinds.
        entry_lanes, exit_lanes: lane ids (lanes only).
        left_neighbors, right_neighbors: lane ids of the ``LaneNeighbor`` s, in file order (lanes only).
        controlled_lanes: lanes a stop sign controls (stop signs only).
        speed_limit_mph: lanes only, ``None`` when absent.
    """

    feature_id: int
    kind: str
    points: np.ndarray
    type_id: int = 0
    entry_lanes: tuple[int, ...] = ()
    exit_lanes: tuple[int, ...] = ()
    left_neighbors: tuple[int, ...] = ()
    right_neighbors: tuple[int, ...] = ()
    controlled_lanes: tuple[int, ...] = ()
    speed_limit_mph: float | None = None


@dataclass(frozen=True)
class SignalState:
    """The state of one traffic signal controlling one lane at one step.

    Attributes:
        lane_id: the controlled lane's ``MapFeature.id``.
        state: ``TrafficSignalLaneState.State`` enum value (see ``SIGNAL_STATES``).
        stop_point: ``[3]`` float64 global stop point, or ``None`` when absent.
    """

    lane_id: int
    state: int
    stop_point: np.ndarray | None


@dataclass(frozen=True)
class WaymoScenario:
    """The decoded subset of one ``Scenario``.

    Attributes:
        scenario_id: ``Scenario.scenario_id``.
        timestamps_s: ``[S]`` float64 ``timestamps_seconds``.
        current_time_index: last step of the observed history.
        sdc_track_index: index into ``tracks`` of the self-driving car.
        tracks: all tracks in file order (the SDC included).
        map_features: all decoded map features in file order.
        signals: per step (``len == S`` or 0), the signal states of that step.
        objects_of_interest: track ids of the interactive group.
        tracks_to_predict: ``(track index, difficulty)`` pairs.
    """

    scenario_id: str
    timestamps_s: np.ndarray
    current_time_index: int
    sdc_track_index: int
    tracks: tuple[ScenarioTrack, ...]
    map_features: tuple[ScenarioMapFeature, ...]
    signals: tuple[tuple[SignalState, ...], ...]
    objects_of_interest: tuple[int, ...]
    tracks_to_predict: tuple[tuple[int, int], ...]


def _require(value: Any, path: str) -> Any:
    if value is None:
        raise ProtoDecodeError(path, -1, "required field is missing")
    return value


def _points(msgs: list[dict[str, Any]], path: str, min_points: int) -> np.ndarray:
    """``[P, 3]`` float64 from repeated ``MapPoint`` s (absent coordinates are 0, as in proto)."""
    if len(msgs) < min_points:
        raise ProtoDecodeError(path, -1, f"expected at least {min_points} points, got {len(msgs)}")
    pts = np.array([[m["x"] or 0.0, m["y"] or 0.0, m["z"] or 0.0] for m in msgs], dtype=np.float64).reshape(-1, 3)
    if not np.all(np.isfinite(pts)):
        raise ProtoDecodeError(path, -1, "non-finite coordinates")
    return pts


def _track(msg: dict[str, Any], path: str, num_steps: int) -> ScenarioTrack:
    states = msg["states"]
    if len(states) != num_steps:
        raise ProtoDecodeError(f"{path}.states", -1, f"{len(states)} states, but {num_steps} timestamps")
    values = np.array([[s[k] or 0.0 for k in _STATE_KEYS] for s in states], dtype=np.float64).reshape(-1, 9)
    valid = np.array([bool(s["valid"]) for s in states], dtype=bool)
    bad = np.flatnonzero(valid & ~np.all(np.isfinite(values), axis=1))
    if bad.size:
        raise ProtoDecodeError(f"{path}.states[{bad[0]}]", -1, "non-finite values in a valid state")
    return ScenarioTrack(
        track_id=int(_require(msg["id"], f"{path}.id")),
        object_type=int(msg["object_type"] or 0),
        states=values,
        valid=valid,
    )


def _neighbor_ids(msgs: list[dict[str, Any]], path: str) -> tuple[int, ...]:
    return tuple(int(_require(m["feature_id"], f"{path}[{i}].feature_id")) for i, m in enumerate(msgs))


def _map_feature(msg: dict[str, Any], path: str) -> ScenarioMapFeature | None:
    """The decoded feature, or ``None`` for a feature of a kind not in ``MAP_FEATURE_KINDS``."""
    feature_id = int(_require(msg["id"], f"{path}.id"))
    kinds = [kind for kind in MAP_FEATURE_KINDS if msg[kind] is not None]
    if len(kinds) > 1:
        raise ProtoDecodeError(path, -1, f"several feature_data members set: {kinds}")
    if not kinds:
        return None
    kind = kinds[0]
    data, where = msg[kind], f"{path}.{kind}"
    if kind == "lane":
        return ScenarioMapFeature(
            feature_id,
            kind,
            _points(data["polyline"], f"{where}.polyline", 1),
            type_id=int(data["type"] or 0),
            entry_lanes=tuple(int(i) for i in data["entry_lanes"]),
            exit_lanes=tuple(int(i) for i in data["exit_lanes"]),
            left_neighbors=_neighbor_ids(data["left_neighbors"], f"{where}.left_neighbors"),
            right_neighbors=_neighbor_ids(data["right_neighbors"], f"{where}.right_neighbors"),
            speed_limit_mph=data["speed_limit_mph"],
        )
    if kind in ("road_line", "road_edge"):
        return ScenarioMapFeature(
            feature_id, kind, _points(data["polyline"], f"{where}.polyline", 1), type_id=int(data["type"] or 0)
        )
    if kind == "stop_sign":
        position = _points([_require(data["position"], f"{where}.position")], f"{where}.position", 1)
        return ScenarioMapFeature(feature_id, kind, position, controlled_lanes=tuple(int(i) for i in data["lane"]))
    return ScenarioMapFeature(feature_id, kind, _points(data["polygon"], f"{where}.polygon", 3))


def _signals(msg: dict[str, Any], path: str) -> tuple[SignalState, ...]:
    out = []
    for i, lane_state in enumerate(msg["lane_states"]):
        where = f"{path}.lane_states[{i}]"
        stop = lane_state["stop_point"]
        out.append(
            SignalState(
                lane_id=int(_require(lane_state["lane"], f"{where}.lane")),
                state=int(lane_state["state"] or 0),
                stop_point=_points([stop], f"{where}.stop_point", 1)[0] if stop is not None else None,
            )
        )
    return tuple(out)


def parse_scenario(data: bytes) -> WaymoScenario:
    """Decode one serialized ``Scenario``.

    Raises:
        ProtoDecodeError: malformed bytes, a required field missing, state / timestamp counts that
            disagree, or an out-of-range track index; ``field_path`` names the field.
    """
    msg = decode_message(data, SCENARIO)
    timestamps = msg["timestamps_seconds"]
    if timestamps.size == 0:
        raise ProtoDecodeError("Scenario.timestamps_seconds", -1, "no timestamps")
    num_steps = int(timestamps.size)
    tracks = tuple(_track(m, f"Scenario.tracks[{i}]", num_steps) for i, m in enumerate(msg["tracks"]))
    sdc = int(_require(msg["sdc_track_index"], "Scenario.sdc_track_index"))
    if not 0 <= sdc < len(tracks):
        raise ProtoDecodeError("Scenario.sdc_track_index", -1, f"index {sdc} outside [0, {len(tracks)})")
    current = int(msg["current_time_index"] or 0)
    if not 0 <= current < num_steps:
        raise ProtoDecodeError("Scenario.current_time_index", -1, f"index {current} outside [0, {num_steps})")
    dynamic = msg["dynamic_map_states"]
    if dynamic and len(dynamic) != num_steps:
        raise ProtoDecodeError(
            "Scenario.dynamic_map_states", -1, f"{len(dynamic)} states, but {num_steps} timestamps"
        )
    features = (_map_feature(m, f"Scenario.map_features[{i}]") for i, m in enumerate(msg["map_features"]))
    to_predict = []
    for i, req in enumerate(msg["tracks_to_predict"]):
        index = int(_require(req["track_index"], f"Scenario.tracks_to_predict[{i}].track_index"))
        if not 0 <= index < len(tracks):
            raise ProtoDecodeError(
                f"Scenario.tracks_to_predict[{i}].track_index", -1, f"index {index} outside [0, {len(tracks)})"
            )
        to_predict.append((index, int(req["difficulty"] or 0)))
    return WaymoScenario(
        scenario_id=str(_require(msg["scenario_id"], "Scenario.scenario_id")),
        timestamps_s=np.asarray(timestamps, dtype=np.float64),
        current_time_index=current,
        sdc_track_index=sdc,
        tracks=tracks,
        map_features=tuple(f for f in features if f is not None),
        signals=tuple(_signals(m, f"Scenario.dynamic_map_states[{i}]") for i, m in enumerate(dynamic)),
        objects_of_interest=tuple(int(i) for i in msg["objects_of_interest"]),
        tracks_to_predict=tuple(to_predict),
    )
