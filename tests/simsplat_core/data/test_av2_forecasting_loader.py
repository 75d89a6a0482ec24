"""Argoverse 2 motion-forecasting loader: a hand-made scenario (decode and bad input, no shared data) and the
public av2-api test scenario (skipped when ../shared/data is absent)."""

from __future__ import annotations

import collections
import json
from pathlib import Path

import numpy as np
import pytest

from simsplat_core.data import CorruptLogError, load_av2_forecasting
from simsplat_core.data.av2_forecasting import FORECASTING_SOURCE, NOMINAL_SIZES, STEP_US
from simsplat_core.data.av2_map import resample_polyline
from simsplat_core.data.common import lane_successors, map_feature_attributes
from simsplat_core.types import SceneLog
from tests.simsplat_core.data.forecasting_files import (
    GROUND_Z,
    SCENARIO_ID,
    START_NS,
    STEPS,
    changed,
    map_archive,
    scenario_columns,
    write_scenario,
)

SAMPLE = Path("av2") / "forecasting-0a1e6f0a"
SAMPLE_ID = "0a1e6f0a-1817-4a98-b02e-db8c9327d151"


@pytest.fixture()
def tiny(tmp_path: Path) -> SceneLog:
    return load_av2_forecasting(write_scenario(tmp_path / "scenario"))


def test_tiny_scenario_timestamps_ego_and_tracks(tiny: SceneLog) -> None:
    assert tiny.source == FORECASTING_SOURCE and tiny.seq_id == SCENARIO_ID and not tiny.images
    assert tiny.num_frames == STEPS and tiny.timestamps_us[0] == round(START_NS / 1000)
    assert set(np.diff(tiny.timestamps_us)) == {STEP_US}  # 10 Hz
    np.testing.assert_array_equal(tiny.ego_poses[0], np.eye(4))
    np.testing.assert_allclose(tiny.ego_poses[-1][:3, 3], [19.0, 0.0, 0.0], atol=1e-9)  # 10 m/s along +x, on the map
    objects = {o.object_id: o for o in tiny.objects}
    assert list(objects) == ["7", "8", "9"] and [o.instance_id for o in tiny.objects] == [1, 2, 3]  # AV is the ego
    assert [o.category for o in tiny.objects] == ["vehicle", "pedestrian", "vehicle"]
    assert [o.attributes["av2_track_category"] for o in tiny.objects] == ["focal", "unscored", "scored"]
    assert objects["9"].attributes["av2_object_type"] == "bus" and objects["8"].node_type == "nonrigid"
    tracks = {t.object_id: t for t in tiny.tracks}
    bus = tracks["9"]
    assert bus.frame_idx.tolist() == list(range(5, STEPS)) and bus.visible.all()
    np.testing.assert_allclose(bus.size, np.tile(NOMINAL_SIZES["bus"], (15, 1)))
    np.testing.assert_allclose(bus.center[:, 2], NOMINAL_SIZES["bus"][2] / 2)  # on the map's ground (z 2 = world 0)
    np.testing.assert_allclose(bus.center[0, :2], [50.0 + 2.5, 0.0])
    np.testing.assert_allclose(tracks["7"].speed, 10.0) and np.testing.assert_allclose(tracks["8"].speed, 0.0)
    meta = tiny.metadata
    assert meta["focal_track_id"] == "7" and json.loads(meta["scored_track_ids"]) == ["7", "9"]
    assert meta["current_time_index"] == "9" and meta["city_name"] == "pittsburgh"
    assert json.loads(meta["city_SE3_world"])[2][3] == GROUND_Z


def test_tiny_scenario_map(tiny: SceneLog) -> None:
    kinds = collections.Counter(f.kind for f in tiny.map_features)
    assert kinds["lane"] == 2 and kinds["crosswalk"] == 1 and kinds["drivable_area"] == 1 and kinds["road_edge"] >= 1
    lane = next(f for f in tiny.map_features if f.feature_id == "lane_11")
    np.testing.assert_allclose(lane.points[[0, -1]], [[-10.0, 0.0, 0.0], [40.0, 0.0, 0.0]], atol=1e-9)
    assert lane_successors(tiny) == {"lane_11": ["lane_12"], "lane_12": []}  # the bike lane is no lane feature


def test_parquet_path_and_seq_id(tmp_path: Path) -> None:
    folder = write_scenario(tmp_path / "s")
    log = load_av2_forecasting(folder / f"scenario_{SCENARIO_ID}.parquet", seq_id="renamed")
    assert log.seq_id == "renamed" and log.num_frames == STEPS


def _av_rows(columns: dict) -> list[int]:
    return [i for i, t in enumerate(columns["track_id"]) if t == "AV"]


def _bad_cases() -> list[tuple[str, dict, str]]:
    base = scenario_columns()
    dropped = {k: v for k, v in base.items() if k != "heading"}
    duplicate = {k: [*v, v[-1]] for k, v in base.items()}
    no_av_step = {k: [x for i, x in enumerate(v) if i != _av_rows(base)[3]] for k, v in base.items()}
    return [
        ("missing column", dropped, "column 'heading': required column missing"),
        ("unknown type", changed(base, "object_type", 0, "hovercraft"), "column 'object_type'.*'hovercraft'"),
        ("step outside", changed(base, "timestep", 5, STEPS + 5), "column 'timestep'.*outside 0..19"),
        ("duplicate step", duplicate, "column 'timestep'.*two rows at timestep 19"),
        ("ego step missing", no_av_step, "column 'track_id'.*'AV' has 19 of 20 steps"),
        ("end timestamp", {**base, "end_timestamp": [START_NS + 5e9] * len(base["track_id"])},
         "column 'end_timestamp'"),
        ("focal absent", {**base, "focal_track_id": ["99"] * len(base["track_id"])}, "column 'focal_track_id'.*'99'"),
        ("two scenarios", changed(base, "scenario_id", 3, "other"), "column 'scenario_id': expected one value"),
        ("track category", changed(base, "object_category", 0, 7), "column 'object_category'"),
        ("mixed type", changed(base, "object_type", 1, "bus"), "column 'object_type'.*several values"),
        ("non-finite", changed(base, "position_x", 2, float("nan")), "column 'position_x'.*non-finite"),
        ("nulls", changed(base, "track_id", 2, None), "column 'track_id'.*null"),
    ]


@pytest.mark.parametrize(("name", "columns", "match"), _bad_cases(), ids=[c[0] for c in _bad_cases()])
def test_bad_scenario_table_names_file_and_column(tmp_path: Path, name: str, columns: dict, match: str) -> None:
    folder = write_scenario(tmp_path / "s", columns)
    with pytest.raises(CorruptLogError, match=match) as info:
        load_av2_forecasting(folder)
    assert info.value.path.endswith(f"scenario_{SCENARIO_ID}.parquet")


def test_bad_files_and_map(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError, match="not found"):
        load_av2_forecasting(tmp_path / "nowhere")
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(CorruptLogError, match="expected one scenario_\\*.parquet, found none"):
        load_av2_forecasting(empty)
    garbage = tmp_path / "garbage"
    garbage.mkdir()
    (garbage / "scenario_x.parquet").write_bytes(b"not parquet at all")
    with pytest.raises(CorruptLogError, match="scenario_x.parquet: file: not a readable parquet table"):
        load_av2_forecasting(garbage)
    with pytest.raises(CorruptLogError, match="no log_map_archive"):
        load_av2_forecasting(write_scenario(tmp_path / "no-map", archive={}))
    broken = map_archive()
    del broken["lane_segments"]["11"]["right_lane_boundary"]
    with pytest.raises(CorruptLogError, match="log_map_archive_.*lane_segments\\[11\\].right_lane_boundary"):
        load_av2_forecasting(write_scenario(tmp_path / "bad-map", archive=broken))


# ------------------------------------------------------------------------------------- the public sample
@pytest.fixture(scope="module")
def sample(shared_data: Path) -> SceneLog:
    return load_av2_forecasting(shared_data / SAMPLE)


@pytest.mark.shared_data
def test_sample_steps_and_tracks(sample: SceneLog) -> None:
    assert sample.seq_id == SAMPLE_ID and sample.source == FORECASTING_SOURCE
    assert sample.num_frames == 110 and set(np.diff(sample.timestamps_us)) == {STEP_US}
    assert len(sample.tracks) == 57  # 58 tracks, the AV is the ego
    assert collections.Counter(o.category for o in sample.objects) == {
        "vehicle": 31, "pedestrian": 12, "static": 8, "cyclist": 4, "other": 2}
    (focal,) = [o for o in sample.objects if o.attributes["av2_track_category"] == "focal"]
    assert focal.object_id == "138951" == sample.metadata["focal_track_id"] and focal.category == "vehicle"
    assert json.loads(sample.metadata["scored_track_ids"]) == ["138951", "139344"]
    focal_track = next(t for t in sample.tracks if t.object_id == "138951")
    assert focal_track.frame_idx.tolist() == list(range(110))
    assert sample.metadata["current_time_index"] == "49" and sample.metadata["city_name"] == "austin"
    types = {o.attributes["av2_object_type"] for o in sample.objects}
    assert types == {"vehicle", "pedestrian", "static", "riderless_bicycle", "background"}


@pytest.mark.shared_data
def test_sample_map_and_agents_on_it(sample: SceneLog, shared_data: Path) -> None:
    kinds = collections.Counter(f.kind for f in sample.map_features)
    assert kinds == {"lane": 34, "crosswalk": 6, "drivable_area": 2, "road_edge": kinds["road_edge"]}
    assert kinds["road_edge"] > 0
    successors = lane_successors(sample)
    assert successors is not None and len(successors) == 34 and any(successors.values())
    # the lanes from the boundaries lie on the archive's own (2D) centre lines
    doc = json.loads(next((shared_data / SAMPLE).glob("log_map_archive_*.json")).read_text())
    world_from_city = np.linalg.inv(np.array(json.loads(sample.metadata["city_SE3_world"])))
    for key in ("205119124", "205119131"):
        lane = next(f for f in sample.map_features if f.feature_id == f"lane_{key}")
        given = np.array([[p["x"], p["y"], 0.0] for p in doc["lane_segments"][key]["centerline"]])
        given = given @ world_from_city[:3, :3].T + world_from_city[:3, 3]
        dense = resample_polyline(lane.points[:, :2], 500)
        gap = np.linalg.norm(given[:, None, :2] - dense[None], axis=-1).min(axis=1)
        assert gap.max() < 0.2
    # the ego and the focal vehicle drive on lanes; so do most moving vehicles (some turn off the map crop)
    lanes = np.concatenate([resample_polyline(f.points[:, :2], 200) for f in sample.map_features if f.kind == "lane"])

    def lane_gap(xy: np.ndarray) -> np.ndarray:
        return np.linalg.norm(xy[:, None] - lanes[None], axis=-1).min(axis=1)

    focal_track = next(t for t in sample.tracks if t.object_id == "138951")
    assert lane_gap(sample.ego_poses[:, :2, 3]).max() < 1.0 and lane_gap(focal_track.center[:, :2]).max() < 1.0
    vehicles = {o.object_id for o in sample.objects if o.category == "vehicle"}
    moving = np.concatenate([t.center[t.speed > 3.0, :2] for t in sample.tracks if t.object_id in vehicles])
    assert moving.shape[0] > 200 and np.median(lane_gap(moving)) < 1.0
    # heights follow the map: boxes stand on the ground within a metre
    assert abs(np.median(np.concatenate([t.center[:, 2] - t.size[:, 2] / 2 for t in sample.tracks]))) < 1.0


@pytest.mark.shared_data
def test_sample_lane_attributes_reference_lanes_and_agree_with_the_archive(sample: SceneLog, shared_data: Path) -> None:
    attrs = map_feature_attributes(sample)
    assert attrs is not None
    lanes = {f.feature_id for f in sample.map_features if f.kind == "lane"}
    assert set(attrs) == lanes
    for attributes in attrs.values():
        assert attributes["type"] == "TYPE_SURFACE_STREET"  # the sample's drivable lanes are all VEHICLE lanes
        for key in ("entry_lanes", "left_neighbors", "right_neighbors"):
            assert set(attributes.get(key, [])) <= lanes
    doc = json.loads(next((shared_data / SAMPLE).glob("log_map_archive_*.json")).read_text())
    archive = {f"lane_{k}": v for k, v in doc["lane_segments"].items()}
    reciprocal = 0
    for lane_id in lanes:
        entry = {f"lane_{p}" for p in archive[lane_id]["predecessors"]} & lanes
        assert set(attrs[lane_id].get("entry_lanes", [])) == entry
        for side, other in (("left", "right"), ("right", "left")):
            neighbour = f"lane_{archive[lane_id][f'{side}_neighbor_id']}"
            if neighbour in lanes and archive[neighbour][f"{other}_neighbor_id"] == archive[lane_id]["id"]:
                # AV2 names the pair from both sides the same way round: same direction, kept on both.
                assert attrs[lane_id][f"{side}_neighbors"] == [neighbour]
                assert attrs[neighbour][f"{other}_neighbors"] == [lane_id]
                reciprocal += 1
            elif neighbour in lanes and archive[neighbour][f"{side}_neighbor_id"] == archive[lane_id]["id"]:
                # opposite direction (each names the other on the same side): not a WOMD neighbour.
                assert neighbour not in attrs[lane_id].get(f"{side}_neighbors", [])
    assert reciprocal > 0  # the sample has multi-lane roads
