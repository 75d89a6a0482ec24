"""The Parquet dataset's tables: schemas, one scenario's rows, and the hive layout read back."""

from __future__ import annotations

import dataclasses

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from simsplat_core.export.parquet_tables import (
    META_ATTEMPT,
    META_EDIT_ID,
    META_FOLLOWS_PROMPT,
    META_PLAUSIBILITY,
    META_PROMPT,
    TABLE_SCHEMAS,
    MissingTableError,
    RenderRef,
    read_dataset_table,
    scenario_tables,
    shard_path,
)
from simsplat_core.export.record import STATE_COLUMNS, SignalState

from .conftest import make_scenario
from .parquet_fixtures import write_dataset


def test_every_schema_declares_its_name_and_version_and_keeps_strings_non_null():
    for table, schema in TABLE_SCHEMAS.items():
        meta = {k.decode(): v.decode() for k, v in schema.metadata.items()}
        assert meta["schema_name"] == f"dataset_{table}"
        assert int(meta["schema_version"]) >= 1
        strings = [f for f in schema if f.type == pa.string()]
        assert strings and not any(f.nullable for f in strings), table


def test_scenario_tables_have_the_declared_schemas_and_row_counts():
    s = make_scenario(num_agents=4, num_steps=30)
    tables = scenario_tables(s, "train")
    assert list(tables) == list(TABLE_SCHEMAS)
    for name, table in tables.items():
        assert table.schema.equals(TABLE_SCHEMAS[name], check_metadata=True), name
    assert tables["scenarios"].num_rows == 1
    assert tables["agents"].num_rows == 4 * 30
    assert tables["map_features"].num_rows == len(s.map_features)
    assert tables["signals"].num_rows == sum(len(step) for step in s.signals)


def test_agent_rows_hold_the_scenario_states_track_major():
    s = make_scenario(num_agents=4, num_steps=30)
    agents = scenario_tables(s, "train")["agents"].to_pydict()
    a, t = s.num_tracks, s.num_steps
    for name, column in zip(("x", "y", "z", "length", "width", "height", "heading", "velocity_x", "velocity_y"),
                            range(len(STATE_COLUMNS))):
        np.testing.assert_allclose(np.reshape(agents[name], (a, t)), s.states[..., column], rtol=1e-6, atol=1e-5)
    np.testing.assert_array_equal(np.reshape(agents["valid"], (a, t)), s.valid)
    np.testing.assert_array_equal(np.reshape(agents["track_id"], (a, t)), np.repeat(s.track_ids[:, None], t, 1))
    np.testing.assert_array_equal(np.reshape(agents["step"], (a, t))[2], np.arange(t))
    np.testing.assert_allclose(np.reshape(agents["t_s"], (a, t))[3], s.timestamps_s)
    per_track = {key: np.reshape(np.asarray(agents[key], dtype=object), (a, t))[:, 0].tolist()
                 for key in ("is_sdc", "of_interest", "to_predict", "source", "object_id", "type")}
    assert per_track["is_sdc"] == [row == s.sdc_index for row in range(a)]
    assert per_track["of_interest"] == [int(i) in s.objects_of_interest for i in s.track_ids]
    assert per_track["to_predict"] == [row in s.tracks_to_predict for row in range(a)]
    assert per_track["source"] == list(s.track_sources)
    assert per_track["object_id"] == list(s.source_object_ids)
    assert per_track["type"] == list(s.agent_types)
    assert not any(np.reshape(agents["valid"], (a, t))[-1, :5])  # the fixture's late-appearing track


def test_scenario_row_reads_known_metadata_and_leaves_missing_edit_facts_null():
    s = make_scenario()
    row = scenario_tables(s, "val")["scenarios"].to_pylist()[0]
    assert row["split"] == "val" and row["seq_id"] == "seq-a"
    assert row["attempt"] is None and row["follows_prompt"] is None and row["plausibility"] is None
    assert row["edit_id"] == "" and row["prompt"] == ""
    assert row["sdc_track_id"] == int(s.track_ids[s.sdc_index])
    assert row["tracks_to_predict"] == [int(s.track_ids[r]) for r in s.tracks_to_predict]
    assert row["objects_of_interest"] == list(s.objects_of_interest)
    assert row["num_tracks"] == s.num_tracks and row["num_steps"] == s.num_steps
    assert row["dt_s"] == pytest.approx(0.1)
    assert row["renders"] == []

    edited = dataclasses.replace(s, metadata={**s.metadata, META_EDIT_ID: "e1", META_ATTEMPT: "2",
                                              META_FOLLOWS_PROMPT: "true", META_PLAUSIBILITY: "4",
                                              META_PROMPT: "the car brakes"})
    renders = [RenderRef("front", 10, "renders/front/10.exr", "renders/front/10.png")]
    row = scenario_tables(edited, "train", renders)["scenarios"].to_pylist()[0]
    assert (row["edit_id"], row["attempt"], row["follows_prompt"], row["plausibility"]) == ("e1", 2, True, 4)
    assert row["prompt"] == "the car brakes"
    assert row["renders"] == [{"camera": "front", "frame": 10, "exr_path": "renders/front/10.exr",
                               "png_path": "renders/front/10.png"}]


def test_bad_metadata_numbers_are_named():
    s = make_scenario()
    with pytest.raises(ValueError, match="'attempt'.*'two'"):
        scenario_tables(dataclasses.replace(s, metadata={META_ATTEMPT: "two"}), "train")
    with pytest.raises(ValueError, match="'follows_prompt'"):
        scenario_tables(dataclasses.replace(s, metadata={META_FOLLOWS_PROMPT: "maybe"}), "train")


def test_map_rows_keep_points_and_connectivity():
    s = make_scenario()
    rows = {r["feature_id"]: r for r in scenario_tables(s, "train")["map_features"].to_pylist()}
    for feature in s.map_features:
        row = rows[feature.feature_id]
        np.testing.assert_allclose(np.asarray(row["points"]), feature.points, atol=1e-5)
        assert (row["kind"], row["type"], row["source_id"]) == (feature.kind, feature.type, feature.source_id)
        assert row["controlled_lanes"] == list(feature.controlled_lanes)
        assert row["left_neighbors"] == list(feature.left_neighbors)
        assert row["speed_limit_mph"] == pytest.approx(feature.speed_limit_mph)


def test_signal_rows_with_and_without_a_stop_point():
    s = make_scenario(num_steps=3)
    signals = ((SignalState(101, "LANE_STATE_STOP"),), (), (SignalState(100, "LANE_STATE_GO", np.array([1., 2, 3])),))
    rows = scenario_tables(dataclasses.replace(s, signals=signals), "train")["signals"].to_pylist()
    assert [(r["step"], r["lane_id"], r["state"]) for r in rows] == [(0, 101, "LANE_STATE_STOP"),
                                                                     (2, 100, "LANE_STATE_GO")]
    assert (rows[0]["stop_x"], rows[0]["stop_y"], rows[0]["stop_z"]) == (None, None, None)
    assert (rows[1]["stop_x"], rows[1]["stop_y"], rows[1]["stop_z"]) == (1.0, 2.0, 3.0)


def _two_split_dataset(tmp_path):
    return write_dataset(tmp_path / "parquet", {
        ("train", "000"): [make_scenario(num_steps=20, scenario_id=f"t{k}") for k in range(2)],
        ("train", "001"): [make_scenario(num_steps=20, scenario_id="t2")],
        ("val", "000"): [make_scenario(num_agents=2, num_steps=20, scenario_id="v0")],
        ("val", "001"): [make_scenario(num_agents=2, num_steps=20, scenario_id="v1")],
    })


def test_hive_layout_reads_every_split_with_its_partition_column(tmp_path):
    root = _two_split_dataset(tmp_path)
    agents = read_dataset_table(root, "agents")
    splits = agents.column("split").to_pylist()
    assert splits.count("train") == 3 * 3 * 20 and splits.count("val") == 2 * 2 * 20
    assert agents.schema.metadata[b"schema_name"] == b"dataset_agents"
    scenarios = read_dataset_table(root, "scenarios", split="val")
    assert sorted(scenarios.column("scenario_id").to_pylist()) == ["v0", "v1"]
    assert set(scenarios.column("split").to_pylist()) == {"val"}
    subset = read_dataset_table(root, "signals", split="train", columns=["scenario_id", "split"])
    assert subset.column_names == ["scenario_id", "split"] and subset.num_rows == 3 * 20


def test_reading_names_missing_splits_tables_and_foreign_files(tmp_path):
    root = _two_split_dataset(tmp_path)
    with pytest.raises(MissingTableError, match="split 'test'"):
        read_dataset_table(root, "agents", split="test")
    with pytest.raises(ValueError, match="unknown dataset table"):
        read_dataset_table(root, "tracks")
    foreign = pa.table({"scenario_id": ["x"]}).replace_schema_metadata({"schema_name": "other"})
    stray = root / "scenarios" / "split=val" / "part-zzz.parquet"
    pq.write_table(foreign, stray)
    with pytest.raises(ValueError, match="part-zzz.parquet.*schema_name"):
        read_dataset_table(root, "scenarios", split="val")


def test_shard_paths_refuse_names_that_break_the_partition():
    assert shard_path("agents", "train", "00ab") == "agents/split=train/part-00ab.parquet"
    for split, shard in (("a/b", "0"), ("train", ""), ("x=y", "0"), ("train", "../0")):
        with pytest.raises(ValueError):
            shard_path("agents", split, shard)
