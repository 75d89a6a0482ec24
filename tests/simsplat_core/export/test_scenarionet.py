"""ScenarioNet scenario descriptions, checked against the published description (MetaDrive's ``ScenarioDescription``
and its ``sanity_check``, ``MetaDriveType``'s strings, the fields ScenarioNet's Waymo converter writes and UniTraj
reads) by a checker written here from those sources, not from the exporter."""

from __future__ import annotations

import dataclasses
import pickle
from typing import Any

import numpy as np
import pytest

from simsplat_core.export.record import ExportMapFeature, ExportScenario
from simsplat_core.export.scenarionet import (
    dataset_mapping,
    dataset_summary,
    scenario_description,
    scenario_file_name,
    to_pickle,
)
from tests.simsplat_core.export.conftest import make_scenario

# --- the published description -------------------------------------------------------------------------------

FIRST_LEVEL_KEYS = {"id", "version", "length", "tracks", "dynamic_map_states", "map_features", "metadata"}
REQUIRED_METADATA = {"metadrive_processed", "coordinate", "ts", "sdc_id"}
ALLOWED_VALUE_TYPES = (int, float, str, np.ndarray, dict, list, tuple, type(None), set)
AGENT_TYPES = {"VEHICLE", "PEDESTRIAN", "CYCLIST", "OTHER"}
LANE_TYPES = {"LANE_SURFACE_STREET", "LANE_SURFACE_UNSTRUCTURE", "LANE_UNKNOWN", "LANE_FREEWAY", "LANE_BIKE_LANE"}
LINE_TYPES = {
    "UNKNOWN_LINE", "ROAD_LINE_BROKEN_SINGLE_WHITE", "ROAD_LINE_SOLID_SINGLE_WHITE", "ROAD_LINE_SOLID_DOUBLE_WHITE",
    "ROAD_LINE_BROKEN_SINGLE_YELLOW", "ROAD_LINE_BROKEN_DOUBLE_YELLOW", "ROAD_LINE_SOLID_SINGLE_YELLOW",
    "ROAD_LINE_SOLID_DOUBLE_YELLOW", "ROAD_LINE_PASSING_DOUBLE_YELLOW",
}
EDGE_TYPES = {"ROAD_EDGE_BOUNDARY", "ROAD_EDGE_MEDIAN"}
POLYGON_TYPES = {"CROSSWALK", "SPEED_BUMP", "DRIVEWAY"}
SIGNAL_STATES = {
    "LANE_STATE_UNKNOWN", "LANE_STATE_ARROW_STOP", "LANE_STATE_ARROW_CAUTION", "LANE_STATE_ARROW_GO",
    "LANE_STATE_STOP", "LANE_STATE_CAUTION", "LANE_STATE_GO", "LANE_STATE_FLASHING_STOP",
    "LANE_STATE_FLASHING_CAUTION",
}
#: Track state key -> (dtype kind, trailing shape); UniTraj stacks all of them.
TRACK_STATE = {
    "position": ("f", (3,)), "length": ("f", ()), "width": ("f", ()), "height": ("f", ()),
    "heading": ("f", ()), "velocity": ("f", (2,)), "valid": ("b", ()),
}


def _check_plain(value: Any, path: str = "scenario") -> None:
    """String dict keys and only the allowed value types, all the way down (``sanity_check``)."""
    assert isinstance(value, ALLOWED_VALUE_TYPES), f"{path}: {type(value).__name__} is not allowed"
    if isinstance(value, dict):
        for key, item in value.items():
            assert isinstance(key, str), f"{path}: key {key!r} is not a string"
            _check_plain(item, f"{path}.{key}")
    elif isinstance(value, list | tuple):
        for i, item in enumerate(value):
            _check_plain(item, f"{path}[{i}]")


def _check_summary_values(value: Any, path: str = "summary") -> None:
    """Plain values only, no arrays or sets (ScenarioNet turns them into lists and tuples in the summary)."""
    _check_plain(value, path)
    assert not isinstance(value, np.ndarray | set), f"{path}: {type(value).__name__} in the summary"
    if isinstance(value, dict):
        for key, item in value.items():
            _check_summary_values(item, f"{path}.{key}")
    elif isinstance(value, list | tuple):
        for i, item in enumerate(value):
            _check_summary_values(item, f"{path}[{i}]")


def _check_object(key: str, obj: dict[str, Any], length: int, allowed_types: set[str]) -> None:
    """A track or dynamic map state: type, state arrays ``length`` long, metadata naming itself."""
    assert {"type", "state", "metadata"} <= set(obj), key
    assert obj["type"] in allowed_types, (key, obj["type"])
    for name, array in obj["state"].items():
        assert len(array) == length, (key, name)
    assert obj["metadata"]["object_id"] == key and obj["metadata"]["type"] == obj["type"]
    assert obj["metadata"]["track_length"] == length


def _check_track(key: str, track: dict[str, Any], length: int) -> None:
    _check_object(key, track, length, AGENT_TYPES)
    state = track["state"]
    assert set(state) == set(TRACK_STATE), key
    for name, (kind, tail) in TRACK_STATE.items():
        assert state[name].dtype.kind == kind and state[name].shape == (length, *tail), (key, name)
    invalid = ~state["valid"]
    for name in TRACK_STATE:
        if name != "valid":
            assert not np.any(state[name][invalid]), f"{key}.{name} is non-zero at an invalid step"
    assert state["valid"].any(), key


def _check_map_feature(key: str, feature: dict[str, Any], lane_ids: set[str]) -> None:
    kind = feature["type"]
    if kind in LANE_TYPES | LINE_TYPES | EDGE_TYPES:
        line = feature["polyline"]
        assert line.ndim == 2 and line.shape[1] == 3 and line.dtype.kind == "f", key
    if kind in LANE_TYPES:
        for name in ("entry_lanes", "exit_lanes"):
            assert all(isinstance(i, str) and i in lane_ids for i in feature[name]), (key, name)
        for name in ("left_neighbor", "right_neighbor"):
            for neighbour in feature[name]:
                assert neighbour["feature_id"] in lane_ids
                assert int(neighbour["self_start_index"]) <= int(neighbour["self_end_index"]) < len(feature["polyline"])
        assert isinstance(feature["speed_limit_mph"], float)
    elif kind in POLYGON_TYPES:
        assert feature["polygon"].ndim == 2 and feature["polygon"].shape[1] == 3, key
    elif kind == "STOP_SIGN":
        assert feature["position"].shape == (3,) and set(feature["lane"]) <= lane_ids, key
    else:
        assert kind in LINE_TYPES | EDGE_TYPES, (key, kind)


def check_description(sd: dict[str, Any]) -> None:
    """Assert that ``sd`` is a scenario description as the published readers expect."""
    assert FIRST_LEVEL_KEYS <= set(sd)
    _check_plain(sd)
    length = sd["length"]
    assert isinstance(length, int) and isinstance(sd["id"], str) and isinstance(sd["version"], str)
    for key, track in sd["tracks"].items():
        _check_track(key, track, length)
    lane_ids = {k for k, f in sd["map_features"].items() if f["type"] in LANE_TYPES}
    for key, light in sd["dynamic_map_states"].items():
        _check_object(key, light, length, {"TRAFFIC_LIGHT"})
        assert set(light["state"]["object_state"]) <= SIGNAL_STATES | {None}
        assert light["lane"] in lane_ids and light["stop_point"].shape == (3,)
    for key, feature in sd["map_features"].items():
        _check_map_feature(key, feature, lane_ids)
    meta = sd["metadata"]
    assert REQUIRED_METADATA <= set(meta)
    assert meta["ts"].shape == (length,) and np.all(np.diff(meta["ts"]) > 0)
    assert meta["sdc_id"] in sd["tracks"] and meta["coordinate"] in {"waymo", "metadrive"}
    assert 0 <= meta["current_time_index"] < length
    assert set(meta["objects_of_interest"]) <= set(sd["tracks"])
    for key, entry in meta["tracks_to_predict"].items():
        assert key in sd["tracks"] and entry["track_id"] == key
        assert sd["tracks"][key]["state"]["valid"][meta["current_time_index"]]
    assert set(meta["object_summary"]) == set(sd["tracks"])


# --- tests ---------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(("num_agents", "num_steps"), [(3, 91), (1, 11), (5, 20)])
def test_descriptions_pass_the_published_checks(num_agents: int, num_steps: int) -> None:
    record = make_scenario(num_agents, num_steps)
    sd = scenario_description(record)
    check_description(sd)
    assert sd["length"] == num_steps and len(sd["tracks"]) == num_agents
    assert list(sd["tracks"]) == [str(i) for i in record.track_ids.tolist()]
    assert sd["metadata"]["sdc_id"] == str(record.track_ids[record.sdc_index])


def test_types_map_to_scenarionet_strings(scenario: ExportScenario) -> None:
    sd = scenario_description(scenario)
    assert [t["type"] for t in sd["tracks"].values()] == ["VEHICLE", "VEHICLE", "PEDESTRIAN"]
    types = {key: f["type"] for key, f in sd["map_features"].items()}
    assert types == {"100": "LANE_SURFACE_STREET", "101": "LANE_SURFACE_STREET", "200": "ROAD_EDGE_BOUNDARY",
                     "300": "ROAD_LINE_BROKEN_SINGLE_WHITE", "400": "CROSSWALK", "500": "STOP_SIGN",
                     "600": "SPEED_BUMP"}
    lane = sd["map_features"]["100"]
    assert [n["feature_id"] for n in lane["left_neighbor"]] == ["101"] and lane["speed_limit_mph"] == 25.0
    assert sd["map_features"]["500"]["lane"] == ["100"]


def test_untyped_features_and_unset_agents_get_defaults(scenario: ExportScenario) -> None:
    points = np.array([[0.0, 0.0, 0.0], [10.0, 0.0, 0.5]])
    untyped = (
        ExportMapFeature(1, "lane", points),
        ExportMapFeature(2, "road_edge", points + [0, 2, 0]),
        ExportMapFeature(3, "road_line", points + [0, 1, 0]),
        ExportMapFeature(4, "lane", points + [0, 4, 0], type="TYPE_UNDEFINED"),
    )
    record = dataclasses.replace(scenario, map_features=untyped, signals=(),
                                 agent_types=("vehicle", "unset", "pedestrian"))
    sd = scenario_description(record)
    check_description(sd)
    assert [f["type"] for f in sd["map_features"].values()] == [
        "LANE_SURFACE_STREET", "ROAD_EDGE_BOUNDARY", "UNKNOWN_LINE", "LANE_SURFACE_STREET"]
    assert sd["tracks"]["8"]["type"] == "OTHER" and sd["dynamic_map_states"] == {}
    assert sd["metadata"]["number_summary"]["map_height_diff"] == pytest.approx(0.5)  # the road line's z range


def test_invalid_steps_are_zero_and_flagged(scenario: ExportScenario) -> None:
    states = scenario.states.copy()
    states[-1, :5] = 7.0  # junk under the invalid steps of the last agent
    sd = scenario_description(dataclasses.replace(scenario, states=states))
    check_description(sd)
    last = sd["tracks"][str(scenario.track_ids[-1])]["state"]
    assert last["valid"].tolist() == [False] * 5 + [True] * (scenario.num_steps - 5)
    assert not last["position"][:5].any() and last["position"][5:].any()
    summary = sd["metadata"]["object_summary"][str(scenario.track_ids[-1])]
    assert summary["valid_length"] == scenario.num_steps - 5 == summary["continuous_valid_length"]


def test_signals_become_traffic_lights_per_lane(scenario: ExportScenario) -> None:
    signals = tuple(step if t % 2 == 0 else () for t, step in enumerate(scenario.signals))
    sd = scenario_description(dataclasses.replace(scenario, signals=signals))
    light = sd["dynamic_map_states"]["101"]
    assert light["lane"] == "101" and light["stop_point"].tolist() == [100.0, 3.5, 0.0]
    assert light["state"]["object_state"][:3] == ["LANE_STATE_GO", None, "LANE_STATE_GO"]
    assert sd["metadata"]["number_summary"]["num_traffic_light_each_step"] == {"LANE_STATE_GO": 46}


def test_pickle_round_trip(scenario: ExportScenario) -> None:
    sd = scenario_description(scenario)
    loaded = pickle.loads(to_pickle(sd))
    check_description(loaded)
    for key, track in sd["tracks"].items():
        for name, array in track["state"].items():
            np.testing.assert_array_equal(loaded["tracks"][key]["state"][name], array)
    np.testing.assert_array_equal(loaded["map_features"]["400"]["polygon"], sd["map_features"]["400"]["polygon"])
    assert loaded["metadata"]["tracks_to_predict"] == sd["metadata"]["tracks_to_predict"]
    assert to_pickle(scenario_description(scenario)) == to_pickle(sd)  # deterministic bytes


def test_tracks_and_map_follow_the_record(scenario: ExportScenario) -> None:
    sd = scenario_description(scenario)
    ped = sd["tracks"]["9"]["state"]
    np.testing.assert_allclose(ped["position"][10], scenario.states[2, 10, :3], rtol=1e-6)
    np.testing.assert_allclose(ped["velocity"][10], scenario.states[2, 10, 7:9], rtol=1e-6)
    np.testing.assert_allclose(sd["metadata"]["ts"], scenario.timestamps_s, atol=1e-6)
    assert sd["metadata"]["tracks_to_predict"] == {
        "8": {"track_index": 1, "track_id": "8", "difficulty": 0, "object_type": "VEHICLE"}}
    assert sd["metadata"]["objects_of_interest"] == ["8"] and sd["metadata"]["scenario_id"] == scenario.scenario_id
    assert sd["tracks"]["8"]["metadata"]["source"] == "edited" and sd["tracks"]["7"]["metadata"]["original_id"] == "ego"


def test_file_names_are_safe_and_distinct() -> None:
    ids = ["seq-a/edit-1/1/w0", "seq-a-edit-1-1-w0", "seq-a/edit-1/1/w1", "plain_id.2"]
    names = [scenario_file_name(i) for i in ids]
    assert len(set(names)) == len(ids)
    for name in names:
        assert name.startswith("sd_simsplat_v1_") and name.endswith(".pkl") and "/" not in name
    assert names[-1] == "sd_simsplat_v1_plain_id.2.pkl"
    with pytest.raises(ValueError, match="dataset"):
        scenario_file_name("x", dataset="a/b")


def test_summary_and_mapping_agree_with_the_files() -> None:
    records = [make_scenario(3, 30, scenario_id=f"seq-{i}/edit/1/w0", seed=i) for i in range(3)]
    files = {scenario_file_name(r.scenario_id): scenario_description(r) for r in records}
    summary = dataset_summary(files)
    mapping = dataset_mapping(files, "shard-0")
    assert set(summary) == set(mapping) == set(files) and set(mapping.values()) == {"shard-0"}
    for name, sd in files.items():
        meta = summary[name]
        assert meta["id"] == sd["id"] and name.endswith(f"_{sd['id']}.pkl")
        assert meta["ts"] == sd["metadata"]["ts"].tolist() and meta["sdc_id"] == sd["metadata"]["sdc_id"]
        assert meta["number_summary"]["num_objects"] == len(sd["tracks"])
        _check_summary_values(meta)
    assert pickle.loads(to_pickle(summary)) == summary and pickle.loads(to_pickle(mapping)) == mapping


def _corrupt_sdc(sd: dict[str, Any]) -> None:
    sd["metadata"]["sdc_id"] = "missing"


def _corrupt_invalid_step(sd: dict[str, Any]) -> None:
    sd["tracks"]["9"]["state"]["position"][0] = 1.0  # the last agent is invalid at step 0


def _corrupt_scalar(sd: dict[str, Any]) -> None:
    sd["metadata"]["current_time_index"] = np.int64(10)  # not a native int


def _corrupt_key(sd: dict[str, Any]) -> None:
    sd["map_features"][100] = sd["map_features"].pop("100")


def _corrupt_length(sd: dict[str, Any]) -> None:
    sd["tracks"]["7"]["state"]["heading"] = sd["tracks"]["7"]["state"]["heading"][:-1]


def _corrupt_type(sd: dict[str, Any]) -> None:
    sd["tracks"]["8"]["type"] = sd["tracks"]["8"]["metadata"]["type"] = "UNSET"


@pytest.mark.parametrize("corrupt", [_corrupt_sdc, _corrupt_invalid_step, _corrupt_scalar, _corrupt_key,
                                     _corrupt_length, _corrupt_type])
def test_the_checker_rejects_what_readers_reject(scenario: ExportScenario, corrupt: Any) -> None:
    sd = scenario_description(scenario)
    corrupt(sd)
    with pytest.raises(AssertionError):
        check_description(sd)
