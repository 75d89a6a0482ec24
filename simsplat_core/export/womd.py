"""``ExportScenario`` -> Waymo Open Motion ``Scenario`` protos and TFRecord shards (the input of SMART, MTR and the
WOMD converters of GPUDrive and ScenarioNet).

What goes where:

* ``scenario_id``, ``timestamps_seconds``, ``current_time_index``, ``sdc_track_index``, ``objects_of_interest``;
  ``tracks_to_predict`` as ``RequiredPrediction(track_index)`` (no difficulty);
* one ``Track`` per row (``id``, ``object_type`` ``TYPE_<AGENT TYPE>``), one ``ObjectState`` per step: all fields
  at valid steps (centre as double, box, heading and velocity as float32), only ``valid = false`` at invalid ones
  (WOMD's own invalid states carry no box: a reader sees zeros);
* map features with their ids, types (unset where the record has none), lane speed limits (unset when 0), entry
  and exit lanes, stop signs' controlled lanes and position, polygons of crosswalks, speed bumps and driveways.
  Lane neighbours carry the neighbour's id and, as the record keeps no adjacency segments, the whole of both
  lanes as the segments (``self_*_index`` over this lane, ``neighbor_*_index`` over the neighbour where the
  neighbour is in the map). Lane boundaries and ``interpolating`` are not written;
* one ``DynamicMapState`` per step (empty when the record has no signals), holding that step's signal states;
* ``ExportScenario.metadata``, track sources and source object ids have no ``Scenario`` field: the dataset's
  manifest keeps them.

The protobuf runtime (``womd_messages``) builds and serializes every message. For speed (a 91-step, 100-agent
scenario holds 9,100 ``ObjectState`` s; a real WOMD map some 20,000 ``MapPoint`` s and a thousand signal states) the
repeated small messages are not set field by field from Python: ``ObjectState`` s and map points are laid out with
numpy (``schema_messages.fixed_width_records``), each distinct signal lane state is serialized once by the runtime,
and these bytes are merged into their parents with one ``MergeFromString`` each, which parses and checks them.
Bad input raises ``ValueError`` naming the scenario and the ``Scenario`` field.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator
from typing import Any

import numpy as np

from simsplat_core.data.tfrecord import encode_tfrecord
from simsplat_core.data.waymo_scenario_proto import (
    MAP_FEATURE,
    MAP_TYPE_ENUMS,
    OBJECT_TYPE,
    POLYGON_KINDS,
    SIGNAL_STATE,
    TRACK,
)
from simsplat_core.export import womd_messages
from simsplat_core.export.record import (
    HEIGHT,
    LENGTH,
    STATE_COLUMNS,
    ExportMapFeature,
    ExportScenario,
    SignalState,
)
from simsplat_core.export.schema_messages import field_named, fixed_width_records

#: Version of what this writer puts into a ``Scenario`` (the dataset manifest's ``schema_versions["womd"]``): the
#: messages are the public protos'; the number changes when the mapping from ``ExportScenario`` does.
FORMAT_VERSION = "1"

_INT32_MAX = 2**31 - 1
_STATES_FIELD = field_named(TRACK, "states")
#: Map kind -> the repeated ``MapPoint`` field of its message (stop signs have one ``position`` instead).
_POINTS_FIELD = {
    f.name: field_named(f.message, "polygon" if f.name in POLYGON_KINDS else "polyline")
    for f in MAP_FEATURE.fields
    if f.oneof and f.message is not None and f.name != "stop_sign"
}
_MIN_POLYGON_POINTS = 3


def encode_scenario(scenario: ExportScenario) -> bytes:
    """One serialized ``Scenario`` (module docstring).

    Raises:
        ValueError: a value the format cannot hold (an id outside int32, non-finite or non-positive box values at
            a valid step, a polygon of fewer than 3 points, a stop sign with several points); the message names
            the scenario and the field.
    """
    return bytes(scenario_message(scenario).SerializeToString())


def iter_shard_records(scenarios: Iterable[ExportScenario]) -> Iterator[bytes]:
    """The TFRecord records of a shard, one framed ``Scenario`` per scenario, in order (for streaming to a file)."""
    for scenario in scenarios:
        yield encode_tfrecord(encode_scenario(scenario))


def encode_shard(scenarios: Iterable[ExportScenario]) -> bytes:
    """A TFRecord shard: one record per scenario, in order (read it with ``tfrecord.iter_tfrecords``)."""
    return b"".join(iter_shard_records(scenarios))


def scenario_message(scenario: ExportScenario) -> Any:
    """The ``womd_messages.Scenario`` of ``scenario`` (see ``encode_scenario``)."""
    where = f"scenario {scenario.scenario_id!r}"
    _check_tracks(scenario, where)
    msg = womd_messages.Scenario(
        scenario_id=scenario.scenario_id,
        timestamps_seconds=np.asarray(scenario.timestamps_s, np.float64).tolist(),
        current_time_index=scenario.current_time_index,
        sdc_track_index=scenario.sdc_index,
        objects_of_interest=[int(i) for i in scenario.objects_of_interest],
    )
    for row in scenario.tracks_to_predict:
        msg.tracks_to_predict.add(track_index=int(row))
    _add_tracks(msg, scenario)
    polyline_sizes = {f.feature_id: len(f.points) for f in scenario.map_features}
    points_wire = _map_points_wire(scenario.map_features, where)
    for index, (feature, wire) in enumerate(zip(scenario.map_features, points_wire)):
        _add_map_feature(msg, feature, wire, polyline_sizes, f"{where}: Scenario.map_features[{index}]")
    _add_signals(msg, scenario, where)
    return msg


def _check_tracks(scenario: ExportScenario, where: str) -> None:
    ids = np.asarray(scenario.track_ids)
    bad = np.flatnonzero((ids < 0) | (ids > _INT32_MAX))
    if bad.size:
        raise ValueError(f"{where}: Scenario.tracks[{bad[0]}].id {ids[bad[0]]} is outside int32's [0, {_INT32_MAX}]")
    valid = np.asarray(scenario.valid, bool)
    states = np.asarray(scenario.states, np.float64)
    rows, steps = np.nonzero(valid & ~np.all(np.isfinite(states), axis=2))
    if rows.size:
        raise ValueError(f"{where}: Scenario.tracks[{rows[0]}].states[{steps[0]}] has non-finite values")
    rows, steps, cols = np.nonzero(valid[..., None] & ~(states[..., LENGTH : HEIGHT + 1] > 0))
    if rows.size:
        name = STATE_COLUMNS[LENGTH + cols[0]]
        raise ValueError(f"{where}: Scenario.tracks[{rows[0]}].states[{steps[0]}].{name} must be > 0 at a valid step")


def _track_states_wire(states: np.ndarray, valid: np.ndarray) -> list[bytes]:
    """Per track row, the serialized ``repeated ObjectState states``.

    Args:
        states: ``[A, T, 9]`` box states (``record.STATE_COLUMNS``).
        valid: ``[A, T]`` bool.
    """
    a, t = valid.shape
    values = np.concatenate([states.reshape(a * t, -1), np.ones((a * t, 1))], axis=1)
    full = fixed_width_records(_STATES_FIELD, (*STATE_COLUMNS, "valid"), values).reshape(a, t, -1)  # [A, T, R]
    empty = fixed_width_records(_STATES_FIELD, ("valid",), np.zeros((1, 1)))[0]  # valid = false only
    full[~valid, : empty.size] = empty
    sizes = np.where(valid, full.shape[2], empty.size)  # [A, T] bytes kept of each record
    keep = np.arange(full.shape[2]) < sizes[..., None]
    data = full[keep].tobytes()
    ends = np.cumsum(sizes.sum(axis=1)).tolist()
    return [data[start:end] for start, end in zip([0, *ends[:-1]], ends)]


def _add_tracks(msg: Any, scenario: ExportScenario) -> None:
    valid = np.asarray(scenario.valid, bool)
    wires = _track_states_wire(np.asarray(scenario.states, np.float64), valid)
    for row, wire in enumerate(wires):
        object_type = OBJECT_TYPE.number(f"TYPE_{scenario.agent_types[row].upper()}")
        track = msg.tracks.add(id=int(scenario.track_ids[row]), object_type=object_type)
        track.MergeFromString(wire)


def _map_points_wire(features: tuple[ExportMapFeature, ...], where: str) -> list[bytes]:
    """Per feature, its serialized ``MapPoint`` field (polyline or polygon; ``b""`` for stop signs): the points of
    all features sharing a field laid out in one ``fixed_width_records`` call."""
    groups: dict[int, list[int]] = {}  # points field number -> feature indices (all of them MapPoint fields)
    for index, feature in enumerate(features):
        points = np.asarray(feature.points)
        if not np.all(np.isfinite(points)):
            raise ValueError(f"{where}: Scenario.map_features[{index}]: feature {feature.feature_id} "
                             f"({feature.kind}) has non-finite points")
        if feature.kind != "stop_sign":
            groups.setdefault(_POINTS_FIELD[feature.kind].number, []).append(index)
    out = [b""] * len(features)
    for indices in groups.values():
        field = _POINTS_FIELD[features[indices[0]].kind]
        points = np.concatenate([features[i].points for i in indices]).astype(np.float64)  # [sum P, 3]
        records = fixed_width_records(field, ("x", "y", "z"), points)
        data = records.tobytes()
        ends = (np.cumsum([len(features[i].points) for i in indices]) * records.shape[1]).tolist()
        for i, start, end in zip(indices, [0, *ends[:-1]], ends):
            out[i] = data[start:end]
    return out


def _add_map_feature(
    msg: Any, feature: ExportMapFeature, points_wire: bytes, polyline_sizes: dict[int, int], where: str
) -> None:
    out = msg.map_features.add(id=int(feature.feature_id))
    data = getattr(out, feature.kind)
    points = feature.points
    if feature.kind == "stop_sign":
        if len(points) != 1:
            raise ValueError(f"{where}: stop sign {feature.feature_id} needs one position, got {len(points)} points")
        data.lane.extend(int(i) for i in feature.controlled_lanes)
        data.position.x, data.position.y, data.position.z = np.asarray(points[0], np.float64).tolist()
        return
    if feature.kind in POLYGON_KINDS and len(points) < _MIN_POLYGON_POINTS:
        raise ValueError(f"{where}: {feature.kind} {feature.feature_id} polygon has {len(points)} points, needs 3")
    data.MergeFromString(points_wire)
    if feature.type:
        data.type = MAP_TYPE_ENUMS[feature.kind].number(feature.type)
    if feature.kind == "lane":
        _fill_lane(data, feature, polyline_sizes)


def _fill_lane(lane: Any, feature: ExportMapFeature, polyline_sizes: dict[int, int]) -> None:
    if feature.speed_limit_mph:
        lane.speed_limit_mph = float(feature.speed_limit_mph)
    lane.entry_lanes.extend(int(i) for i in feature.entry_lanes)
    lane.exit_lanes.extend(int(i) for i in feature.exit_lanes)
    last = len(feature.points) - 1
    sides = ((lane.left_neighbors, feature.left_neighbors), (lane.right_neighbors, feature.right_neighbors))
    for neighbors, ids in sides:
        for lane_id in ids:
            neighbor = neighbors.add(feature_id=int(lane_id), self_start_index=0, self_end_index=last)
            if lane_id in polyline_sizes:
                neighbor.neighbor_start_index = 0
                neighbor.neighbor_end_index = polyline_sizes[lane_id] - 1


def _lane_state_wire(signal: SignalState, stop: tuple[float, ...] | None, where: str) -> bytes:
    """One serialized ``DynamicMapState.lane_states`` entry (tag, length, ``TrafficSignalLaneState``)."""
    state = womd_messages.TrafficSignalLaneState(lane=int(signal.lane_id), state=SIGNAL_STATE.number(signal.state))
    if stop is not None:
        if len(stop) != 3 or not all(map(math.isfinite, stop)):
            raise ValueError(f"{where} lane {signal.lane_id}: stop_point must be 3 finite numbers, got {list(stop)}")
        state.stop_point.x, state.stop_point.y, state.stop_point.z = stop
    return bytes(womd_messages.DynamicMapState(lane_states=[state]).SerializeToString())


def _add_signals(msg: Any, scenario: ExportScenario, where: str) -> None:
    """One ``DynamicMapState`` per step; each distinct lane state (lane, state, stop point) is serialized once and
    merged into every step that has it (signals hold their state for many steps)."""
    serialized: dict[tuple[int, str, tuple[float, ...] | None], bytes] = {}
    for step in range(scenario.num_steps):
        parts = []
        for signal in scenario.signals[step] if scenario.signals else ():
            stop = None if signal.stop_point is None else tuple(np.asarray(signal.stop_point, float).ravel().tolist())
            key = (int(signal.lane_id), signal.state, stop)
            wire = serialized.get(key)
            if wire is None:
                wire = serialized[key] = _lane_state_wire(signal, stop, f"{where}: Scenario.dynamic_map_states[{step}]")
            parts.append(wire)
        msg.dynamic_map_states.add().MergeFromString(b"".join(parts))
