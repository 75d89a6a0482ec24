"""WOMD ``Scenario`` export: what ``encode_scenario`` writes reads back through the project's decoder and loader."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from google.protobuf import unknown_fields

from simsplat_core.data import load_waymo_scenario
from simsplat_core.data.common import LANE_SUCCESSORS_KEY, MAP_FEATURE_ATTRIBUTES_KEY
from simsplat_core.data.tfrecord import iter_tfrecords
from simsplat_core.data.waymo_scenario_proto import (
    LANE_TYPE,
    MAP_TYPE_ENUMS,
    OBJECT_TYPES,
    ROAD_EDGE_TYPE,
    ROAD_LINE_TYPE,
    SIGNAL_STATE,
    WaymoScenario,
    parse_scenario,
)
from simsplat_core.export import womd_messages
from simsplat_core.export.record import (
    AGENT_TYPES,
    HEADING,
    LANE_TYPES,
    LENGTH,
    ROAD_EDGE_TYPES,
    ROAD_LINE_TYPES,
    SIGNAL_STATES,
    ExportMapFeature,
    ExportScenario,
    SignalState,
    X,
    Z,
)
from simsplat_core.export.womd import encode_scenario, encode_shard
from tests.simsplat_core.export.conftest import make_scenario

SAMPLE = Path("waymo") / "motion_data_one_scenario.tfrecord"


def rich_scenario(num_agents: int = 6, **changes: object) -> ExportScenario:
    """``make_scenario`` with every agent type, a lane fork with entry / exit lanes, a driveway and signals that
    change over time (a red phase, a step without signals, a state without a stop point)."""
    base = make_scenario(num_agents)
    xs = np.linspace(0.0, 30.0, 4)
    fork = ExportMapFeature(
        102, "lane", np.stack([200 + xs, np.zeros(4), np.zeros(4)], 1), type="TYPE_FREEWAY", entry_lanes=(100, 101),
        exit_lanes=(103, 104), left_neighbors=(101, 999), speed_limit_mph=65.0,
    )
    driveway = ExportMapFeature(700, "driveway", np.array([[5, -6, 0], [9, -6, 0], [9, -3, 0.2], [5, -3, 0.1]]))
    median = ExportMapFeature(201, "road_edge", base.map_features[2].points + [0, 9, 0], type="TYPE_ROAD_EDGE_MEDIAN")
    signals = []
    for step in range(base.num_steps):
        if step == 3:
            signals.append(())
            continue
        state = "LANE_STATE_STOP" if step >= 50 else "LANE_STATE_GO"
        signals.append((SignalState(101, state, np.array([100.0, 3.5, 0.25])), SignalState(100, "LANE_STATE_ARROW_GO")))
    fields: dict[str, object] = {
        "agent_types": ("vehicle", "cyclist", "pedestrian", "other", "unset", "vehicle")[:num_agents],
        "map_features": base.map_features + (fork, driveway, median),
        "signals": tuple(signals),
        "objects_of_interest": (8, 10),
        "tracks_to_predict": (1, 3),
    }
    fields.update(changes)
    return dataclasses.replace(base, **fields)


def test_record_enums_are_the_format_enums() -> None:
    assert LANE_TYPES == LANE_TYPE.values and ROAD_LINE_TYPES == ROAD_LINE_TYPE.values
    assert ROAD_EDGE_TYPES == ROAD_EDGE_TYPE.values and SIGNAL_STATES == SIGNAL_STATE.values
    assert [f"TYPE_{t.upper()}" for t in AGENT_TYPES] == [OBJECT_TYPES[i] for i in range(len(AGENT_TYPES))]


def test_tracks_round_trip_through_the_decoder() -> None:
    scenario = rich_scenario()
    decoded = parse_scenario(encode_scenario(scenario))
    assert decoded.scenario_id == scenario.scenario_id
    np.testing.assert_array_equal(decoded.timestamps_s, scenario.timestamps_s)
    assert decoded.current_time_index == scenario.current_time_index
    assert decoded.sdc_track_index == scenario.sdc_index
    assert decoded.objects_of_interest == (8, 10)
    assert decoded.tracks_to_predict == ((1, 0), (3, 0))
    assert [t.track_id for t in decoded.tracks] == scenario.track_ids.tolist()
    assert [OBJECT_TYPES[t.object_type] for t in decoded.tracks] == [f"TYPE_{t.upper()}" for t in scenario.agent_types]
    states = np.stack([t.states for t in decoded.tracks])  # [A, T, 9]
    valid = np.stack([t.valid for t in decoded.tracks])
    np.testing.assert_array_equal(valid, scenario.valid)
    assert not valid.all()
    # Centres are doubles, box, heading and velocity float32; invalid steps carry no values.
    expected = scenario.states.copy()
    expected[..., Z + 1 :] = expected[..., Z + 1 :].astype(np.float32)
    expected[~scenario.valid] = 0.0
    np.testing.assert_array_equal(states, expected)
    assert np.any(states[..., X : Z + 1] != states[..., X : Z + 1].astype(np.float32))  # the centre kept doubles


def test_invalid_steps_are_bare_valid_false_states() -> None:
    scenario = rich_scenario()
    row = scenario.num_tracks - 1
    states = dataclasses.replace(scenario, states=scenario.states + 1.0).states  # invalid rows are not zero now
    message = womd_messages.Scenario.FromString(encode_scenario(dataclasses.replace(scenario, states=states)))
    invalid = message.tracks[row].states[0]
    assert invalid.ListFields() == [(invalid.DESCRIPTOR.fields_by_name["valid"], False)]
    assert message.tracks[row].states[10].length == pytest.approx(states[row, 10, LENGTH])


def test_every_map_kind_round_trips_with_ids_types_and_connectivity() -> None:
    scenario = rich_scenario()
    decoded = {f.feature_id: f for f in parse_scenario(encode_scenario(scenario)).map_features}
    assert list(decoded) == [f.feature_id for f in scenario.map_features]
    for feature in scenario.map_features:
        got = decoded[feature.feature_id]
        assert got.kind == feature.kind
        np.testing.assert_array_equal(got.points, feature.points)
        enum = MAP_TYPE_ENUMS.get(feature.kind)
        assert got.type_id == (enum.number(feature.type) if enum is not None and feature.type else 0)
        assert (got.entry_lanes, got.exit_lanes) == (feature.entry_lanes, feature.exit_lanes)
        assert (got.left_neighbors, got.right_neighbors) == (feature.left_neighbors, feature.right_neighbors)
        assert got.controlled_lanes == feature.controlled_lanes
        assert got.speed_limit_mph == (feature.speed_limit_mph or None)
    assert {f.kind for f in decoded.values()} == {"lane", "road_line", "road_edge", "stop_sign", "crosswalk",
                                                  "speed_bump", "driveway"}
    assert decoded[102].type_id == LANE_TYPE.number("TYPE_FREEWAY") and decoded[102].left_neighbors == (101, 999)


def test_lane_neighbours_span_both_lanes() -> None:
    message = womd_messages.Scenario.FromString(encode_scenario(rich_scenario()))
    fork = next(f.lane for f in message.map_features if f.id == 102)
    known, unknown = fork.left_neighbors
    assert (known.feature_id, known.self_start_index, known.self_end_index) == (101, 0, 3)
    assert (known.neighbor_start_index, known.neighbor_end_index) == (0, 11)  # lane 101 has 12 points
    assert unknown.feature_id == 999 and not unknown.HasField("neighbor_end_index")


def test_signals_per_step() -> None:
    scenario = rich_scenario()
    decoded = parse_scenario(encode_scenario(scenario))
    assert len(decoded.signals) == scenario.num_steps
    for step, (got, want) in enumerate(zip(decoded.signals, scenario.signals)):
        assert [(s.lane_id, SIGNAL_STATE.values[s.state]) for s in got] == [(s.lane_id, s.state) for s in want], step
        for g, w in zip(got, want):
            if w.stop_point is None:
                assert g.stop_point is None
            else:
                np.testing.assert_array_equal(g.stop_point, w.stop_point)
    no_signals = parse_scenario(encode_scenario(dataclasses.replace(scenario, signals=())))
    assert no_signals.signals == ((),) * scenario.num_steps  # one empty DynamicMapState per step, as in WOMD


def test_shard_reads_back_record_by_record(tmp_path: Path) -> None:
    scenarios = [make_scenario(3 + i, scenario_id=f"seq-a/edit-{i}/1/w0") for i in range(3)]
    path = tmp_path / "train.tfrecord-00000-of-00001"
    path.write_bytes(encode_shard(scenarios))
    records = list(iter_tfrecords(path))
    assert [parse_scenario(r.data).scenario_id for r in records] == [s.scenario_id for s in scenarios]
    assert [len(parse_scenario(r.data).tracks) for r in records] == [3, 4, 5]
    third = load_waymo_scenario(path, record_index=2)
    assert third.metadata["scenario_id"] == "seq-a/edit-2/1/w0" and len(third.tracks) == 4


def test_the_loader_reads_a_written_scenario(tmp_path: Path) -> None:
    scenario = rich_scenario()
    path = tmp_path / "one.tfrecord"
    path.write_bytes(encode_shard([scenario]))
    log = load_waymo_scenario(path)
    assert log.num_frames == scenario.num_steps
    assert sorted(int(t.object_id) for t in log.tracks) == scenario.track_ids[1:].tolist()  # the SDC is the ego
    # The SDC drives along +x from the origin: the world frame is its first pose.
    np.testing.assert_allclose(log.ego_poses[-1, :2, 3], scenario.states[0, -1, :2] - scenario.states[0, 0, :2],
                               atol=1e-6)
    attributes = json.loads(log.metadata[MAP_FEATURE_ATTRIBUTES_KEY])
    assert attributes["lane_102"] == {"type": "TYPE_FREEWAY", "entry_lanes": ["lane_100", "lane_101"],
                                      "left_neighbors": ["lane_101", "lane_999"], "right_neighbors": [],
                                      "speed_limit_mph": 65.0}
    assert "speed_limit_mph" not in attributes["lane_101"]
    assert attributes["road_edge_201"] == {"type": "TYPE_ROAD_EDGE_MEDIAN"}
    assert attributes["road_line_300"] == {"type": "TYPE_BROKEN_SINGLE_WHITE"}
    assert [d["id"] for d in json.loads(log.metadata["driveways"])] == [700]
    assert [s["lanes"] for s in json.loads(log.metadata["stop_signs"])] == [["lane_100"]]
    assert json.loads(log.metadata[LANE_SUCCESSORS_KEY])["lane_102"] == ["lane_103", "lane_104"]
    assert json.loads(log.metadata["traffic_signals"])[60][0][:2] == ["lane_101", "LANE_STATE_STOP"]


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda s: {"track_ids": s.track_ids + 2**31, "objects_of_interest": ()},
         r"Scenario\.tracks\[0\]\.id 2147483655 is outside int32"),
        (lambda s: {"states": _with(s.states, (1, 20, HEADING), np.nan)}, r"tracks\[1\]\.states\[20\].*non-finite"),
        (lambda s: {"states": _with(s.states, (2, 30, LENGTH + 1), 0.0)}, r"tracks\[2\]\.states\[30\]\.width must"),
        (lambda s: {"map_features": (ExportMapFeature(9, "crosswalk", np.zeros((2, 3))),)}, r"crosswalk 9 polygon"),
        (lambda s: {"map_features": (ExportMapFeature(9, "stop_sign", np.zeros((2, 3))),)}, r"stop sign 9 needs one"),
        (lambda s: {"map_features": (ExportMapFeature(9, "lane", np.full((2, 3), np.inf)),)}, r"feature 9.*non-finite"),
        (lambda s: {"signals": ((SignalState(1, "LANE_STATE_GO", np.array([1.0, 2.0])),),) * s.num_steps},
         r"dynamic_map_states\[0\] lane 1: stop_point"),
    ],
)
def test_bad_input_names_the_scenario_and_field(change: object, message: str) -> None:
    scenario = make_scenario(4)
    bad = dataclasses.replace(scenario, **change(scenario))
    with pytest.raises(ValueError, match=message) as err:
        encode_scenario(bad)
    assert "seq-a/edit-1/1/w0" in str(err.value)


def _with(array: np.ndarray, index: tuple[int, ...], value: float) -> np.ndarray:
    out = array.copy()
    out[index] = value
    return out


def export_from_decoded(decoded: WaymoScenario) -> ExportScenario:
    """The ``ExportScenario`` of a decoded WOMD record (invalid states zeroed: the record's convention)."""
    valid = np.stack([t.valid for t in decoded.tracks])
    states = np.stack([t.states for t in decoded.tracks])
    states[~valid] = 0.0
    features = tuple(
        ExportMapFeature(
            f.feature_id, f.kind, f.points,
            type=MAP_TYPE_ENUMS[f.kind].values[f.type_id] if f.kind in MAP_TYPE_ENUMS else "",
            entry_lanes=f.entry_lanes, exit_lanes=f.exit_lanes, left_neighbors=f.left_neighbors,
            right_neighbors=f.right_neighbors, controlled_lanes=f.controlled_lanes,
            speed_limit_mph=f.speed_limit_mph or 0.0,
        )
        for f in decoded.map_features
    )  # fmt: skip
    signals = tuple(
        tuple(SignalState(s.lane_id, SIGNAL_STATE.values[s.state], s.stop_point) for s in step)
        for step in decoded.signals
    )
    return ExportScenario(
        scenario_id=decoded.scenario_id,
        timestamps_s=decoded.timestamps_s,
        current_time_index=decoded.current_time_index,
        track_ids=np.array([t.track_id for t in decoded.tracks], np.int64),
        agent_types=tuple(OBJECT_TYPES[t.object_type].removeprefix("TYPE_").lower() for t in decoded.tracks),
        states=states,
        valid=valid,
        sdc_index=decoded.sdc_track_index,
        objects_of_interest=decoded.objects_of_interest,
        tracks_to_predict=tuple(index for index, _ in decoded.tracks_to_predict),
        map_features=features,
        signals=signals,
    )


@pytest.mark.shared_data
def test_the_real_sample_round_trips_field_by_field(shared_data: Path) -> None:
    original = parse_scenario(next(iter_tfrecords(shared_data / SAMPLE)).data)
    again = parse_scenario(encode_scenario(export_from_decoded(original)))
    assert (again.scenario_id, again.current_time_index, again.sdc_track_index) == (
        original.scenario_id, original.current_time_index, original.sdc_track_index)
    np.testing.assert_array_equal(again.timestamps_s, original.timestamps_s)
    assert again.objects_of_interest == original.objects_of_interest
    assert [i for i, _ in again.tracks_to_predict] == [i for i, _ in original.tracks_to_predict]  # no difficulty
    assert len(again.tracks) == len(original.tracks) == 83
    for got, want in zip(again.tracks, original.tracks):
        assert (got.track_id, got.object_type) == (want.track_id, want.object_type)
        np.testing.assert_array_equal(got.valid, want.valid)
        np.testing.assert_array_equal(got.states[got.valid], want.states[want.valid])
        assert not got.states[~got.valid].any()
    assert len(again.map_features) == len(original.map_features) == 301
    for got_f, want_f in zip(again.map_features, original.map_features):
        assert dataclasses.replace(got_f, points=0, speed_limit_mph=got_f.speed_limit_mph or None) == \
            dataclasses.replace(want_f, points=0, speed_limit_mph=want_f.speed_limit_mph or None)
        np.testing.assert_array_equal(got_f.points, want_f.points)
    assert len(again.signals) == len(original.signals) == 91
    for got_step, want_step in zip(again.signals, original.signals):
        assert [(s.lane_id, s.state) for s in got_step] == [(s.lane_id, s.state) for s in want_step]
        np.testing.assert_array_equal([s.stop_point for s in got_step], [s.stop_point for s in want_step])


@pytest.mark.shared_data
def test_the_real_sample_has_no_field_the_messages_lack(shared_data: Path) -> None:
    data = next(iter_tfrecords(shared_data / SAMPLE)).data
    message = womd_messages.Scenario.FromString(data)
    assert message.SerializeToString() == data
    stack = [message]
    while stack:  # every field of the real record is a known field of the right wire type
        msg = stack.pop()
        assert len(unknown_fields.UnknownFieldSet(msg)) == 0, msg.DESCRIPTOR.name
        for field, value in msg.ListFields():
            if field.message_type is not None:
                stack.extend(value if field.is_repeated else [value])

