"""Waymo Open Motion ``Scenario`` TFRecord loader against the public one-scenario sample."""

from __future__ import annotations

import collections
import json
from pathlib import Path

import numpy as np
import pytest

from simsplat_core.data import CorruptLogError, load_waymo_scenario
from simsplat_core.data.common import MAP_FEATURE_ATTRIBUTES_KEY, lane_successors
from simsplat_core.data.tfrecord import encode_tfrecord, iter_tfrecords
from simsplat_core.data.waymo_scenario import SCENARIO_SOURCE
from simsplat_core.data.waymo_scenario_proto import MAP_TYPE_ENUMS, parse_scenario
from simsplat_core.scenario.lane_graph import LaneGraph
from simsplat_core.types import SceneLog

pytestmark = pytest.mark.shared_data

SAMPLE = Path("waymo") / "motion_data_one_scenario.tfrecord"
SCENARIO_ID = "637f20cafde22ff8"
NUM_STEPS = 91
NUM_TRACKS_WITH_SDC = 83
SDC_TRACK_ID = "2406"
#: MapFeature kinds of the sample: 199 lanes (one bike lane skipped), 59 road lines, 28 road edges,
#: 4 crosswalks; plus 8 stop signs and 3 speed bumps kept in metadata (301 features in the file).
MAP_COUNTS = {"lane": 198, "lane_marking": 59, "road_edge": 28, "crosswalk": 4}


@pytest.fixture(scope="module")
def sample_path(shared_data: Path) -> Path:
    return shared_data / SAMPLE


@pytest.fixture(scope="module")
def log(sample_path: Path) -> SceneLog:
    return load_waymo_scenario(sample_path)


def test_steps_and_ego(log: SceneLog) -> None:
    assert log.seq_id == SCENARIO_ID and log.source == SCENARIO_SOURCE
    assert log.num_frames == NUM_STEPS and not log.images
    np.testing.assert_allclose(np.diff(log.timestamps_us), 100_000, atol=100)  # Waymo steps are ~0.1 s
    assert log.timestamps_us[0] == 0
    np.testing.assert_array_equal(log.ego_poses[0], np.eye(4))
    # Rigid poses: orthonormal rotations.
    rot = log.ego_poses[:, :3, :3]
    np.testing.assert_allclose(rot @ rot.transpose(0, 2, 1), np.broadcast_to(np.eye(3), rot.shape), atol=1e-9)
    assert log.metadata["current_time_index"] == "10"
    assert log.metadata["sdc_track_id"] == SDC_TRACK_ID
    assert all(v > 0 for v in json.loads(log.metadata["ego_size"]))


def test_tracks_exclude_the_ego(log: SceneLog) -> None:
    assert len(log.tracks) == NUM_TRACKS_WITH_SDC - 1
    ids = {tr.object_id for tr in log.tracks}
    assert SDC_TRACK_ID not in ids
    assert collections.Counter(o.category for o in log.objects) == {"vehicle": 69, "pedestrian": 10, "cyclist": 3}
    assert sorted(o.instance_id for o in log.objects) == list(range(1, len(log.objects) + 1))
    for tr in log.tracks:
        assert np.all(tr.size > 0), tr.object_id
        assert np.all(tr.visible)
        assert np.all(np.isfinite(tr.speed)) and np.all(tr.speed >= 0)


def test_known_tracks(log: SceneLog) -> None:
    assert json.loads(log.metadata["tracks_to_predict"]) == [2320, 1676, 1675]
    car = log.track("1676")
    assert log.object("1676").category == "vehicle"
    assert log.object("1676").attributes["tracks_to_predict_difficulty"] == "1"
    # Invalid states are absent frames: this car is valid at 79 of the 91 steps.
    assert len(car) == 79 and np.all(np.diff(car.frame_idx) > 0)
    assert 4.0 < car.size[0, 0] < 7.0 and 1.5 < car.size[0, 1] < 3.0 and car.size[0, 2] > 1.0
    pedestrian = log.track("2320")
    assert log.object("2320").category == "pedestrian" and len(pedestrian) == NUM_STEPS
    assert np.all(pedestrian.size[:, :2] < 1.5)


def test_map_features(log: SceneLog) -> None:
    counts = collections.Counter(f.kind for f in log.map_features)
    assert counts == MAP_COUNTS
    assert len({f.feature_id for f in log.map_features}) == len(log.map_features)
    assert all(len(f.points) >= 3 for f in log.map_features if f.kind == "crosswalk")
    assert len(json.loads(log.metadata["stop_signs"])) == 8
    assert len(json.loads(log.metadata["speed_bumps"])) == 3
    assert json.loads(log.metadata["skipped_map_features"]) == {"non-vehicle lane": 1}


def test_map_feature_attributes_keep_types_entries_neighbours_and_speed_limits(
    log: SceneLog, sample_path: Path
) -> None:
    attributes = json.loads(log.metadata[MAP_FEATURE_ATTRIBUTES_KEY])
    by_kind = {f.feature_id: f.kind for f in log.map_features}
    # Every lane, road line and road edge has an entry, crosswalks none.
    assert set(attributes) == {i for i, kind in by_kind.items() if kind != "crosswalk"}
    scenario = parse_scenario(next(iter_tfrecords(sample_path)).data)
    decoded = {f"{f.kind}_{f.feature_id}": f for f in scenario.map_features}
    for feature_id, entry in attributes.items():
        source = decoded[feature_id]
        assert entry["type"] == MAP_TYPE_ENUMS[source.kind].values[source.type_id]
        if by_kind[feature_id] != "lane":
            assert set(entry) == {"type"}
            continue
        assert entry["entry_lanes"] == [f"lane_{i}" for i in source.entry_lanes]
        assert entry["left_neighbors"] == [f"lane_{i}" for i in source.left_neighbors]
        assert entry["right_neighbors"] == [f"lane_{i}" for i in source.right_neighbors]
        assert entry.get("speed_limit_mph") == source.speed_limit_mph
    lanes = [entry for entry in attributes.values() if "entry_lanes" in entry]
    assert any(entry["left_neighbors"] for entry in lanes) and any(entry["right_neighbors"] for entry in lanes)
    assert {entry["type"] for entry in lanes} <= {"TYPE_UNDEFINED", "TYPE_FREEWAY", "TYPE_SURFACE_STREET"}
    assert json.loads(log.metadata["driveways"]) == []


def test_traffic_signals_per_step(log: SceneLog) -> None:
    steps = json.loads(log.metadata["traffic_signals"])
    assert len(steps) == NUM_STEPS
    lanes = {f.feature_id for f in log.map_features if f.kind == "lane"}
    for row in steps:
        for lane, state, *stop in row:
            assert lane in lanes and state.startswith("LANE_STATE_") and len(stop) == 3


def test_lane_graph_builds_and_vehicles_sit_on_lanes(log: SceneLog) -> None:
    inferred = LaneGraph.from_features(log.map_features)
    explicit = LaneGraph.from_features(log.map_features, successors=lane_successors(log))
    for graph in (inferred, explicit):
        assert len(graph.lanes) >= MAP_COUNTS["lane"] - 1  # a one-point lane has no direction
        assert sum(1 for nxt in graph.successors if nxt) > 0.8 * len(graph.lanes)
    # Map and tracks share the world frame: moving vehicles are close to a lane centre line.
    current = int(log.metadata["current_time_index"])
    xy, heading = [], []
    for tr in log.tracks:
        row = tr.index_of(current)
        if log.object(tr.object_id).category == "vehicle" and row is not None and tr.speed[row] > 2.0:
            xy.append(tr.center[row, :2])
            heading.append(tr.heading[row])
    assert len(xy) >= 5
    match = explicit.nearest(np.array(xy), np.array(heading))
    assert np.median(match.distance) < 1.0


def test_corrupt_crc_names_file_and_record(sample_path: Path, tmp_path: Path) -> None:
    data = bytearray(sample_path.read_bytes())
    data[len(data) // 2] ^= 0xFF
    path = tmp_path / "bad_crc.tfrecord"
    path.write_bytes(bytes(data))
    with pytest.raises(CorruptLogError, match=r"record 0 \(byte offset 0\).*data CRC32C mismatch") as info:
        load_waymo_scenario(path)
    assert str(path) in str(info.value) and info.value.record_index == 0


def test_truncated_file(sample_path: Path, tmp_path: Path) -> None:
    data = sample_path.read_bytes()
    path = tmp_path / "truncated.tfrecord"
    path.write_bytes(data[: len(data) - 100])
    with pytest.raises(CorruptLogError, match=r"record 0 .*truncated record") as info:
        load_waymo_scenario(path)
    assert str(path) in str(info.value)


def test_malformed_proto_with_valid_crc_names_the_field(sample_path: Path, tmp_path: Path) -> None:
    data = next(iter_tfrecords(sample_path)).data
    path = tmp_path / "cut_proto.tfrecord"
    path.write_bytes(encode_tfrecord(data[: len(data) // 2]))
    with pytest.raises(CorruptLogError, match=r"record 0 .*field 'Scenario\.") as info:
        load_waymo_scenario(path)
    assert info.value.record_index == 0 and str(path) in str(info.value)


def test_empty_file_and_missing_record(sample_path: Path, tmp_path: Path) -> None:
    empty = tmp_path / "empty.tfrecord"
    empty.write_bytes(b"")
    with pytest.raises(CorruptLogError, match="no records"):
        load_waymo_scenario(empty)
    with pytest.raises(IndexError, match="record 1 requested"):
        load_waymo_scenario(sample_path, record_index=1)
