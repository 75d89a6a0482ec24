"""A Parquet dataset read back into per-scenario arrays: grids, densified map, signals."""

from __future__ import annotations

import numpy as np
import pyarrow.compute as pc
import pyarrow.parquet as pq
import pytest

from simsplat_core.export.dataset_arrays import densify_polylines, load_scenario_arrays
from simsplat_core.export.record import MAP_FEATURE_KINDS, SIGNAL_STATES, TRACK_SOURCES

from .conftest import make_scenario
from .parquet_fixtures import write_dataset


def test_densify_keeps_the_ends_closes_polygons_and_bounds_the_spacing():
    points = np.array([[0, 0, 0], [10, 0, 0], [10, 3.5, 1], [5, 5, 0], [0, 0, 0], [4, 0, 0], [4, 4, 0]], float)
    offsets = np.array([0, 3, 4, 7])  # an open polyline, one point, a triangle
    dense, feature = densify_polylines(points, offsets, np.array([False, False, True]), step_m=1.0)
    assert np.all(np.diff(feature) >= 0) and set(feature.tolist()) == {0, 1, 2}
    for f, first, last in ((0, points[0], points[2]), (1, points[3], points[3]), (2, points[4], points[4])):
        mine = dense[feature == f]
        np.testing.assert_allclose(mine[0], first)
        np.testing.assert_allclose(mine[-1], last)  # the triangle ends where it started
        if len(mine) > 1:
            assert np.linalg.norm(np.diff(mine, axis=0), axis=1).max() <= 1.0 + 1e-6
    assert (feature == 0).sum() == 10 + 4 + 1  # 10 m and 3.64 m segments, the last point
    assert (feature == 1).sum() == 1


def test_arrays_match_the_exported_scenarios(tmp_path):
    scenarios = [make_scenario(num_agents=4, num_steps=25, scenario_id=f"s{k}", seed=k) for k in range(2)]
    root = write_dataset(tmp_path / "parquet", {("train", "0"): scenarios})
    arrays = load_scenario_arrays(root, "train")
    assert [a.scenario_id for a in arrays] == ["s0", "s1"]
    for s, a in zip(scenarios, arrays):
        np.testing.assert_array_equal(a.track_ids, s.track_ids)
        np.testing.assert_allclose(a.states, s.states, atol=1e-5)
        np.testing.assert_array_equal(a.valid, s.valid)
        assert a.current_time_index == s.current_time_index and a.split == "train" and a.edited
        assert [TRACK_SOURCES[k] for k in a.sources] == list(s.track_sources)
        assert a.to_predict.tolist() == [row in s.tracks_to_predict for row in range(s.num_tracks)]
        by_id = sorted(s.map_features, key=lambda f: f.feature_id)
        assert a.feature_ids.tolist() == [f.feature_id for f in by_id]
        assert [MAP_FEATURE_KINDS[k] for k in a.feature_kinds] == [f.kind for f in by_id]
        lane = list(a.feature_ids).index(101)
        assert (a.signal_states[:, lane] == SIGNAL_STATES.index("LANE_STATE_GO")).all()
        assert (np.delete(a.signal_states, lane, axis=1) == -1).all()


def test_an_agents_table_without_invalid_rows_fills_the_same_grid(tmp_path):
    s = make_scenario(num_agents=4, num_steps=25)
    root = write_dataset(tmp_path / "parquet", {("train", "0"): [s]})
    path = root / "agents" / "split=train" / "part-0.parquet"
    table = pq.read_table(path)
    valid_rows = table.filter(table.column("valid"))
    pq.write_table(valid_rows.take(np.arange(80)[::-1]), path)  # the first 80 valid rows, in reverse order
    (a,) = load_scenario_arrays(root, "train")
    kept = np.zeros_like(s.valid)
    kept.reshape(-1)[np.flatnonzero(s.valid.reshape(-1))[:80]] = True
    np.testing.assert_array_equal(a.valid, kept)
    np.testing.assert_allclose(a.states[kept], s.states[kept], atol=1e-5)
    assert not a.states[~kept].any()


def test_unknown_values_and_orphan_rows_are_named(tmp_path):
    root = write_dataset(tmp_path / "parquet", {("train", "0"): [make_scenario(num_steps=12)]})
    path = root / "agents" / "split=train" / "part-0.parquet"
    table = pq.read_table(path)
    bad = table.set_column(table.schema.get_field_index("type"), "type", pc.replace_substring(
        table.column("type"), "vehicle", "tank"))
    pq.write_table(bad, path)
    with pytest.raises(ValueError, match="column 'type'.*tank"):
        load_scenario_arrays(root, "train")
    orphan = table.set_column(0, "scenario_id", pc.replace_substring(table.column("scenario_id"), "seq-a", "x"))
    pq.write_table(orphan, path)
    with pytest.raises(ValueError, match="no row in the scenarios table"):
        load_scenario_arrays(root, "train")
