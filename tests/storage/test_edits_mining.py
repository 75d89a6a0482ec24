"""The edits table's mining columns (schema version 3): round trip, batch appends, and older tables still read:
version 1 (before the mining columns) with every mining column null, version 2 (before ``judge_reasons``) with that
one null."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from storage import ArtifactStore, SchemaError
from storage.edits import EditRecord, append_edit_record, append_edit_records, edits_table, read_edit_records
from storage.schemas.base import schema_version
from storage.schemas.edits import EDITS_MINING_COLUMNS, EDITS_SCHEMA

_EDIT_COLUMNS = [n for n in EDITS_SCHEMA.names if n not in EDITS_MINING_COLUMNS]


def _mined(edit_id: str, status: str, mining_status: str, reason: str = "") -> EditRecord:
    return EditRecord(run_id="mine1", seq_id="unit", edit_id=edit_id, prompt="remove the car", command_json="{}",
                      status=status, failure_reason=reason,
                      mining={"mining_status": mining_status, "scenario": 0, "source": "client",
                              "category": "remove", "follows_prompt": mining_status == "accepted",
                              "plausibility": 4 if mining_status == "accepted" else 2, "adjustment": "",
                              "export": mining_status == "accepted", "client": "rule-based",
                              "seconds_edit": 0.5})


def _write_edit_columns_only(store: ArtifactStore, run_id: str, rows: list[dict], version: int) -> None:
    """An edits table of ``version`` with the eight edit columns only (as version 1 wrote it)."""
    fields = [EDITS_SCHEMA.field(n) for n in _EDIT_COLUMNS]
    schema = pa.schema(fields, metadata={"schema_name": "edits", "schema_version": str(version)})
    path = Path(store.root) / edits_table(store, run_id).legacy_relpath
    path.parent.mkdir(parents=True, exist_ok=True)
    pq.write_table(pa.Table.from_pylist(rows, schema=schema), str(path))


def test_edits_schema_is_version_3_with_nullable_mining_columns() -> None:
    assert schema_version(EDITS_SCHEMA) == 3
    assert all(EDITS_SCHEMA.field(n).nullable for n in EDITS_MINING_COLUMNS)
    assert not any(EDITS_SCHEMA.field(n).nullable for n in _EDIT_COLUMNS)


def test_mining_columns_round_trip_and_batch_appends_number_attempts(store: ArtifactStore) -> None:
    plain = append_edit_record(store, EditRecord(run_id="mine1", seq_id="unit", edit_id="e0", prompt="p",
                                                 command_json="", status="refused", failure_reason="x: y"))
    assert plain.mining == {} and not plain.export
    batch = [_mined("e1", "failed", "rejected", "rejected: judge: no"), _mined("e1", "succeeded", "accepted")]
    numbered = append_edit_records(store, batch)
    assert [r.attempt for r in numbered] == [1, 2]
    rows = read_edit_records(store, "mine1")
    assert [(r.edit_id, r.attempt, r.status) for r in rows] == [("e0", 1, "refused"), ("e1", 1, "failed"),
                                                                ("e1", 2, "succeeded")]
    assert rows[0].mining == {"export": False}  # a plain edit: mining columns null, not exported
    assert rows[2].export and rows[2].mining["mining_status"] == "accepted" and rows[2].mining["plausibility"] == 4
    assert "seconds_judge" not in rows[2].mining  # null stays absent
    table = edits_table(store, "mine1").read()
    assert table.column("export").to_pylist() == [False, False, True]


def test_append_edit_records_refuses_mixed_runs_and_unknown_columns(store: ArtifactStore) -> None:
    other = EditRecord(run_id="other", seq_id="unit", edit_id="e9", prompt="p", command_json="", status="refused",
                       failure_reason="x: y")
    with pytest.raises(ValueError, match="several runs"):
        append_edit_records(store, [_mined("e1", "succeeded", "accepted"), other])
    with pytest.raises(ValueError, match="unknown column"):
        EditRecord(run_id="r", seq_id="s", edit_id="e", prompt="p", command_json="", status="succeeded",
                   mining={"colour": "red"})


def test_version_1_edits_tables_still_read_and_append(store: ArtifactStore) -> None:
    _write_edit_columns_only(store, "old", [{"run_id": "old", "seq_id": "unit", "edit_id": "e1", "attempt": 1,
                                             "prompt": "p", "command_json": "", "status": "succeeded",
                                             "failure_reason": ""}], version=1)
    (old,) = read_edit_records(store, "old")
    assert old.status == "succeeded" and old.mining == {} and not old.export
    table = edits_table(store, "old").read()
    assert table.schema.names == EDITS_SCHEMA.names and table.column("mining_status").null_count == 1
    appended = append_edit_record(store, EditRecord(run_id="old", seq_id="unit", edit_id="e1", prompt="p",
                                                    command_json="", status="refused", failure_reason="x: y"))
    assert appended.attempt == 2 and len(read_edit_records(store, "old")) == 2


def test_version_2_edits_tables_read_without_judge_reasons(store: ArtifactStore) -> None:
    fields = [EDITS_SCHEMA.field(n) for n in EDITS_SCHEMA.names if n != "judge_reasons"]
    schema = pa.schema(fields, metadata={"schema_name": "edits", "schema_version": "2"})
    row = {"run_id": "v2", "seq_id": "unit", "edit_id": "e1", "attempt": 1, "prompt": "p", "command_json": "{}",
           "status": "succeeded", "failure_reason": "", "mining_status": "accepted", "scenario": 0, "plausibility": 4,
           "export": True}
    path = Path(store.root) / edits_table(store, "v2").legacy_relpath
    path.parent.mkdir(parents=True, exist_ok=True)
    pq.write_table(pa.Table.from_pylist([row], schema=schema), str(path))
    (old,) = read_edit_records(store, "v2")
    assert old.mining["plausibility"] == 4 and "judge_reasons" not in old.mining


def test_judge_reasons_round_trip(store: ArtifactStore) -> None:
    record = _mined("e1", "succeeded", "accepted")
    record = dataclasses.replace(record, mining={**record.mining, "judge_reasons": '["fits the lane"]'})
    append_edit_records(store, [record])
    (back,) = read_edit_records(store, "mine1")
    assert back.mining["judge_reasons"] == '["fits the lane"]'


def test_a_current_table_without_the_mining_columns_is_an_error(store: ArtifactStore) -> None:
    _write_edit_columns_only(store, "bad", [], version=3)
    with pytest.raises(SchemaError, match="mining_status"):
        read_edit_records(store, "bad")
