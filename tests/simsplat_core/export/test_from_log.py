"""Stored logs, unedited and edited, as exported scenarios: tracks, ids, map, signals, windows, re-validation."""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from simsplat_core.export.from_log import edit_source, export_log_scenarios, export_unedited, log_agent_states
from simsplat_core.export.map_features import export_map
from simsplat_core.export.validate import revalidate
from simsplat_core.scenario.agents import EGO_ID

from .log_fixtures import straight_road_log


def test_an_unedited_log_keeps_every_track_and_the_ego_box() -> None:
    log = straight_road_log()
    (s,) = export_unedited([log])
    assert s.scenario_id == "road-seq-log-w0" and s.num_steps == 91 and s.current_time_index == 10
    assert s.source_object_ids[s.sdc_index] == EGO_ID
    np.testing.assert_allclose(s.states[s.sdc_index, 0, 3:6], [4.6, 2.0, 1.5])
    np.testing.assert_allclose(s.states[s.sdc_index, 0, 2], 0.75)  # pose at the ground, centre half a box up
    row = s.source_object_ids.index("car_a")
    np.testing.assert_allclose(s.states[row, :40, 0], 30.0 + 6.0 * np.arange(40) / 10.0)
    np.testing.assert_allclose(s.states[row, :40, 7], 6.0)  # velocity along the heading
    assert s.valid[:, :40].all() and not s.valid[:, 40:].any() and not s.states[:, 40:].any()
    assert dict(zip(s.source_object_ids, s.track_ids.tolist())) == {"ego": 0, "car_a": 1, "car_b": 2}
    assert s.track_sources == ("log",) * 3 and s.objects_of_interest == () and s.tracks_to_predict == ()
    assert "padded with 51 invalid steps" in s.metadata["notes"]


def test_the_map_keeps_kinds_connectivity_types_and_signals() -> None:
    log = straight_road_log()
    exported = export_map(log)
    by_source = {f.source_id: f for f in exported.features}
    assert Counter(f.kind for f in exported.features) == {"lane": 3, "road_line": 1, "crosswalk": 1,
                                                         "road_edge": 2, "stop_sign": 1, "speed_bump": 1}
    lane1, lane2 = by_source["lane_1"], by_source["lane_2"]
    assert lane1.exit_lanes == (lane2.feature_id,) and lane2.entry_lanes == (lane1.feature_id,)
    assert lane1.type == "TYPE_SURFACE_STREET" and lane1.left_neighbors == (3,) and lane1.speed_limit_mph == 30.0
    assert by_source["lane_3"].type == ""  # an unknown type name is dropped, not exported
    assert by_source["stop_sign_20"].controlled_lanes == (lane2.feature_id,)
    assert any("sidewalk: 1 left out" in n for n in exported.notes)
    (s,) = export_unedited([log])
    assert len(s.signals) == 91 and s.signals[0][0].lane_id == lane1.feature_id and s.signals[0][0].state == \
        "LANE_STATE_GO" and s.signals[60] == ()


def test_drivable_area_outlines_become_counter_clockwise_road_edges_when_there_are_none() -> None:
    exported = export_map(straight_road_log(road_edges=False))
    (edge,) = [f for f in exported.features if f.kind == "road_edge"]
    x, y = edge.points[:-1, 0], edge.points[:-1, 1]
    assert 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) > 0
    np.testing.assert_array_equal(edge.points[0], edge.points[-1])
    (s,) = export_unedited([straight_road_log(road_edges=False)])
    assert revalidate(s).ok


def test_an_edit_exports_its_agents_interest_and_predictions() -> None:
    log = straight_road_log()
    states = log_agent_states(log)
    braking = np.maximum(6.0 - 3.0 * np.clip(states.times - 1.0, 0, None), 0.0)
    xy, speed = states.xy.copy(), states.speed.copy()
    a = states.index("car_a")  # the lead car brakes
    xy[a, :, 0] = states.xy[a, 0, 0] + np.concatenate([[0.0], np.cumsum(braking[:-1] * 0.1)])
    speed[a] = braking
    xy[states.index("car_b"), :, 1] = np.minimum(states.times, 1.0) * 3.5  # the car behind it moves over (refined)
    sources = tuple("edited" if o == "car_a" else "refined" if o == "car_b" else s
                    for o, s in zip(states.object_ids, states.sources))
    from dataclasses import replace

    edited = replace(states, xy=xy, speed=speed, sources=sources)
    edited = edited.with_agent("inserted_1", "vehicle", "inserted", xy=np.tile([[80.0, 3.5]], (40, 1)),
                               heading=np.zeros(40), speed=np.zeros(40), valid=np.ones(40, bool), size=(8.0, 2.5, 3.0))
    src = edit_source(log, edited, "road-seq-abc-a1", {"run_id": "r1", "prompt": "the lead car brakes hard"})
    (s,) = export_log_scenarios(src)
    ids = dict(zip(s.source_object_ids, s.track_ids.tolist()))
    assert ids["inserted_1"] == 3 and ids["car_a"] == 1  # log ids as in the unedited export, new ones after
    assert set(s.objects_of_interest) == {ids["car_a"], ids["inserted_1"]}
    assert {s.source_object_ids[r] for r in s.tracks_to_predict} == {"car_a", "car_b", "inserted_1"}
    row = s.source_object_ids.index("car_a")
    assert s.track_sources[row] == "edited"
    assert s.states[row, 39, 7] == pytest.approx(0.0) and s.states[row, 0, 7] == pytest.approx(6.0)
    truck = s.source_object_ids.index("inserted_1")
    np.testing.assert_allclose(s.states[truck, 5, 3:6], [8.0, 2.5, 3.0])
    assert s.metadata["prompt"] == "the lead car brakes hard" and s.scenario_id == "road-seq-abc-a1-w0"
    report = revalidate(s)
    assert len(report.agents) == 3 and report.ok


def test_revalidation_catches_a_collision_written_into_the_tracks() -> None:
    log = straight_road_log()
    states = log_agent_states(log)
    a = states.index("car_a")
    xy = states.xy.copy()
    xy[a] = states.xy[states.index(EGO_ID)]  # drive the edited car through the ego
    from dataclasses import replace

    sources = tuple("edited" if k == a else s for k, s in enumerate(states.sources))
    (s,) = export_log_scenarios(edit_source(log, replace(states, xy=xy, sources=sources), "k", {}))
    report = revalidate(s)
    assert not report.ok and "collides" in report.failures()[0]


@pytest.mark.shared_data
def test_the_waymo_motion_sample_matches_its_source_record(shared_data: Path) -> None:
    from simsplat_core.data.tfrecord import iter_tfrecords
    from simsplat_core.data.waymo_scenario import load_waymo_scenario
    from simsplat_core.data.waymo_scenario_proto import parse_scenario
    from simsplat_core.geometry import invert_transform, transform_points, wrap_angle

    path = shared_data / "waymo" / "motion_data_one_scenario.tfrecord"
    log = load_waymo_scenario(path)
    (s,) = export_unedited([log])
    source = parse_scenario(next(iter(iter_tfrecords(path))).data)
    world_from_global = invert_transform(np.asarray(json.loads(log.metadata["global_SE3_world"])))
    yaw = float(np.arctan2(world_from_global[1, 0], world_from_global[0, 0]))
    rows = {int(t): k for k, t in enumerate(s.track_ids)}
    assert int(s.track_ids[s.sdc_index]) == source.tracks[source.sdc_track_index].track_id
    for track in source.tracks:
        k, v = rows[track.track_id], track.valid
        np.testing.assert_array_equal(s.valid[k], v)
        np.testing.assert_allclose(s.states[k, v, :3], transform_points(world_from_global, track.states[v, :3]),
                                   atol=0.01)
        np.testing.assert_allclose(wrap_angle(s.states[k, v, 6] - track.states[v, 6] - yaw), 0.0, atol=1e-3)
        np.testing.assert_allclose(s.states[k, v, 3:6], track.states[v, 3:6], atol=1e-4)
    predicted = {int(s.track_ids[r]) for r in s.tracks_to_predict}
    assert predicted == {source.tracks[i].track_id for i, _ in source.tracks_to_predict}
    kinds = Counter(f.kind for f in s.map_features)
    logged = Counter(f.kind for f in log.map_features)
    assert kinds["lane"] == logged["lane"] and kinds["road_edge"] == logged["road_edge"]
    assert kinds["road_line"] == logged["lane_marking"] and kinds["crosswalk"] == logged["crosswalk"]
    assert kinds["stop_sign"] == len(json.loads(log.metadata["stop_signs"])) > 0
    assert kinds["speed_bump"] == len(json.loads(log.metadata["speed_bumps"])) > 0
    assert sum(len(step) for step in s.signals) > 0 and revalidate(s).ok


def test_road_edges_are_turned_so_that_the_road_lies_on_their_left() -> None:
    import dataclasses

    from simsplat_core.types import MapFeature

    log = straight_road_log()
    xs = np.linspace(-50, 250, 31)
    wrong = MapFeature("road_edge_7", "road_edge", np.stack([xs, np.full_like(xs, -1.75), np.zeros_like(xs)], 1)[::-1])
    area = MapFeature("drivable_area_9", "drivable_area",
                      np.array([[-50, -1.75, 0], [250, -1.75, 0], [250, 5.25, 0], [-50, 5.25, 0.0]]))
    features = tuple(f for f in log.map_features if f.feature_id != "road_edge_7") + (wrong, area)
    exported = export_map(dataclasses.replace(log, map_features=features))
    by_source = {f.source_id: f for f in exported.features}
    assert by_source["road_edge_7"].points[0, 0] < by_source["road_edge_7"].points[-1, 0]  # now runs along +x
    assert by_source["road_edge_8"].points[0, 0] > by_source["road_edge_8"].points[-1, 0]  # was right: kept
    assert any("1 reversed" in n for n in exported.notes)
    (s,) = export_unedited([dataclasses.replace(log, map_features=features)])
    assert revalidate(s).ok
