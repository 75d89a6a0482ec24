"""The ``motion`` table: schema (columns, nullable ADE, schema_version), atomic write + validated read round trip,
and a clear error naming the file and the column for a bad file."""

from __future__ import annotations

import math

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from simsplat_core.eval.refinement.table import MOTION_SPEC, OUTCOMES_SPEC, motion_table
from storage import ArtifactStore
from storage.errors import SchemaError
from storage.runs import read_run_table, run_table, write_run_tables
from storage.schemas.base import schema_version

COLUMNS = ["dataset", "method", "predictor", "scenarios", "refused", "collision_vehicle", "collision_pedestrian",
           "offroad", "kinematic", "failure", "progress", "stopped_share", "ade_3s", "ade_8s", "agent_collision",
           "agent_offroad"]


def _rows() -> list[dict]:
    base = dict(scenarios=1, refused=0, collision_vehicle=0.0, collision_pedestrian=1.0, offroad=1.0, kinematic=0.0,
                failure=1.0, progress=1.0, stopped_share=0.1, agent_collision=0.08, agent_offroad=0.06)
    return [base | {"dataset": "waymo-motion", "method": "log", "predictor": "", "ade_3s": None, "ade_8s": None},
            base | {"dataset": "waymo-motion", "method": "full", "predictor": "constant-velocity", "ade_3s": 0.38,
                    "ade_8s": 0.70, "progress": math.nan}]


def test_schema_columns_and_version() -> None:
    schema = MOTION_SPEC.schema
    assert schema.names == COLUMNS
    assert schema_version(schema) == 2
    assert schema.field("ade_3s").nullable and not schema.field("failure").nullable
    assert schema.field("scenarios").type == pa.int64() and schema.field("dataset").type == pa.string()


def test_round_trip(store: ArtifactStore, tmp_path) -> None:
    table = motion_table(_rows())
    uri = write_run_tables(store, "run1", {"motion": run_table(MOTION_SPEC, table)}, {"stage": "motion"})["motion"]
    assert uri.endswith("run1/tables/motion.parquet")
    back = read_run_table(store, "run1", MOTION_SPEC)
    assert back.to_pylist()[0]["ade_3s"] is None and back.to_pylist()[1]["ade_3s"] == pytest.approx(0.38)
    assert math.isnan(back.to_pylist()[1]["progress"])
    assert "| waymo-motion | log |  | 1 | 0 |" in (tmp_path / "root" / "run1" / "tables" / "motion.md").read_text()


def test_bad_file_names_file_and_column(store: ArtifactStore, tmp_path) -> None:
    table = motion_table(_rows())
    write_run_tables(store, "run1", {"motion": run_table(MOTION_SPEC, table)})
    path = tmp_path / "root" / "run1" / "tables" / "motion.parquet"
    damaged = pq.read_table(path).drop(["agent_offroad"])
    pq.write_table(damaged.replace_schema_metadata(MOTION_SPEC.schema.metadata), path)
    with pytest.raises(SchemaError, match=r"motion\.parquet.*'agent_offroad' is missing"):
        read_run_table(store, "run1", MOTION_SPEC)


def test_nulls_in_non_nullable_columns_are_refused(store: ArtifactStore) -> None:
    table = motion_table(_rows()).set_column(9, "failure", pa.array([None, 1.0], pa.float64()))
    with pytest.raises(SchemaError, match="'failure' has 1 null"):
        write_run_tables(store, "run2", {"motion": run_table(MOTION_SPEC, table, "")})


def test_outcomes_written_beside_the_motion_table(store: ArtifactStore, tmp_path) -> None:
    from simsplat_core.eval.refinement.synthetic import MotionCase, MotionOutcome, outcome_row
    from simsplat_core.eval.refinement.table import outcomes_table

    table = motion_table(_rows())
    outcome = MotionOutcome(MotionCase("c1", "seq0", "editing", "add_vehicle", "add a car"), "full", failures=None)
    outcomes = outcomes_table([outcome_row(outcome)])
    write_run_tables(store, "run3", {"motion": run_table(MOTION_SPEC, table),
                                     "motion_outcomes": run_table(OUTCOMES_SPEC, outcomes)})
    back = read_run_table(store, "run3", OUTCOMES_SPEC)
    assert back.num_rows == 1 and back.to_pylist()[0]["case_id"] == "c1"
    assert schema_version(OUTCOMES_SPEC.schema) == 1
    assert (tmp_path / "root" / "run3" / "tables" / "motion_outcomes.md").exists()
