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

The protobuf runtime (``womd_messages``) builds and serializes every message; the ``ObjectState`` s and map points
are laid out with numpy (``schema_messages.fixed_width_records``) and merged into their parents in one call each.
Bad input raises ``ValueError`` naming the scenario and the ``Scenario`` field.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
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
from simsplat_core.export.record import HEIGHT, LENGTH, STATE_COLUMNS, ExportMapFeature, ExportScenario
from simsplat_core.export.schema_messages import field_named, fixed_width_records

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


def encode_shard(scenarios: Iterable[ExportScenario]) -> bytes:
    """A TFRecord shard: one record per scenario, in order (read it with ``tfrecord.iter_tfrecords``)."""
    return b"".join(encode_tfrecord(encode_scenario(s)) for s in scenarios)


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
    for index, feature in enumerate(scenario.map_features):
        _add_map_feature(msg, feature, polyline_sizes, f"{where}: Scenario.map_features[{index}]")
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


def _add_map_feature(msg: Any, feature: ExportMapFeature, polyline_sizes: dict[int, int], where: str) -> None:
    points = np.asarray(feature.points, np.float64)
    if not np.all(np.isfinite(points)):
        raise ValueError(f"{where}: feature {feature.feature_id} ({feature.kind}) has non-finite points")
    out = msg.map_features.add(id=int(feature.feature_id))
    data = getattr(out, feature.kind)
    if feature.kind == "stop_sign":
        if len(points) != 1:
            raise ValueError(f"{where}: stop sign {feature.feature_id} needs one position, got {len(points)} points")
        data.lane.extend(int(i) for i in feature.controlled_lanes)
        data.position.x, data.position.y, data.position.z = points[0].tolist()
        return
    if feature.kind in POLYGON_KINDS and len(points) < _MIN_POLYGON_POINTS:
        raise ValueError(f"{where}: {feature.kind} {feature.feature_id} polygon has {len(points)} points, needs 3")
    data.MergeFromString(fixed_width_records(_POINTS_FIELD[feature.kind], ("x", "y", "z"), points).tobytes())
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


def _add_signals(msg: Any, scenario: ExportScenario, where: str) -> None:
    for step in range(scenario.num_steps):
        dynamic = msg.dynamic_map_states.add()
        for signal in scenario.signals[step] if scenario.signals else ():
            state = dynamic.lane_states.add(lane=int(signal.lane_id), state=SIGNAL_STATE.number(signal.state))
            if signal.stop_point is None:
                continue
            stop = np.asarray(signal.stop_point, np.float64).ravel().tolist()
            if len(stop) != 3 or not all(map(math.isfinite, stop)):
                raise ValueError(f"{where}: Scenario.dynamic_map_states[{step}] lane {signal.lane_id}: stop_point "
                                 f"must be 3 finite numbers, got {stop}")
            state.stop_point.x, state.stop_point.y, state.stop_point.z = stop
