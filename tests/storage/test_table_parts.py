"""A parted table: appends add immutable parts, reads see every row once, compaction keeps concurrent appends."""

from __future__ import annotations

from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from storage import ArtifactStore
from storage.errors import CorruptArtifactError
from storage.table_parts import PartedTable

SCHEMA = pa.schema([pa.field("row", pa.int64(), nullable=False)], metadata={"schema_name": "rows",
                                                                            "schema_version": "1"})


def _rows(*values: int) -> pa.Table:
    return pa.table({"row": pa.array(values, pa.int64())}, schema=SCHEMA)


def _table(store: ArtifactStore) -> PartedTable:
    return PartedTable(store, "runs/r1", "rows", SCHEMA)


def _values(table: PartedTable) -> list[int]:
    return table.read().column("row").to_pylist()


def test_appends_are_parts_read_in_order(store: ArtifactStore) -> None:
    table = _table(store)
    assert not table.exists() and _values(table) == []
    for start in (0, 2, 4):
        table.append(_rows(start, start + 1))
    assert table.exists() and len(table.part_names()) == 3
    assert _values(table) == [0, 1, 2, 3, 4, 5]


def test_the_legacy_single_file_is_read_first(store: ArtifactStore) -> None:
    table = _table(store)
    store.write_table(table.legacy_relpath, _rows(-2, -1), SCHEMA)
    table.append(_rows(0))
    assert _values(table) == [-2, -1, 0]
    table.append(_rows(1))
    assert table.compact() == 2 and _values(table) == [-2, -1, 0, 1]
    assert store.exists(table.legacy_relpath)  # never rewritten


def test_compaction_folds_parts_into_one_and_keeps_the_order(store: ArtifactStore) -> None:
    table = _table(store)
    for value in range(5):
        table.append(_rows(value))
    assert table.compact() == 5
    assert len(table.part_names()) == 1 and _values(table) == [0, 1, 2, 3, 4]
    table.append(_rows(5))
    assert table.compact(min_parts=3) == 0  # two live parts only
    assert table.compact() == 2 and _values(table) == [0, 1, 2, 3, 4, 5] and len(table.part_names()) == 1


def test_an_interrupted_compaction_is_read_once_and_finished_later(store: ArtifactStore, monkeypatch) -> None:
    table = _table(store)
    for value in range(3):
        table.append(_rows(value))
    monkeypatch.setattr(store, "delete", lambda relpath: (_ for _ in ()).throw(OSError("interrupted")))
    with pytest.raises(OSError, match="interrupted"):
        table.compact()
    monkeypatch.undo()
    assert len(table.part_names()) == 4  # the compacted part beside the three it replaces
    assert _values(table) == [0, 1, 2]  # the replaced parts are skipped, not counted twice
    table.append(_rows(3))
    assert table.compact() == 2 and _values(table) == [0, 1, 2, 3] and len(table.part_names()) == 1


def test_a_part_appended_while_a_compaction_reads_is_kept(store: ArtifactStore, monkeypatch) -> None:
    table = _table(store)
    table.append(_rows(0))
    table.append(_rows(1))
    real_read = store.read_table
    appended = []

    def read_then_append(relpath, schema):
        if not appended:  # another writer appends while the compaction reads its parts
            appended.append(table.append(_rows(2)))
        return real_read(relpath, schema)

    monkeypatch.setattr(store, "read_table", read_then_append)
    assert table.compact() == 2
    monkeypatch.undo()
    assert sorted(_values(table)) == [0, 1, 2] and len(table.part_names()) == 2


def test_a_reader_that_races_a_compaction_lists_again(store: ArtifactStore, monkeypatch) -> None:
    table = _table(store)
    for value in range(3):
        table.append(_rows(value))
    real_read = store.read_table
    compacted = []

    def compact_during_read(relpath, schema):
        if not compacted:  # the listed parts disappear before they are read
            monkeypatch.setattr(store, "read_table", real_read)
            compacted.append(table.compact())
            monkeypatch.setattr(store, "read_table", compact_during_read)
        return real_read(relpath, schema)

    monkeypatch.setattr(store, "read_table", compact_during_read)
    assert _values(table) == [0, 1, 2] and compacted == [3]


def test_a_damaged_part_is_named(store: ArtifactStore) -> None:
    table = _table(store)
    part = table.append(_rows(0))
    Path(store.root, part).write_bytes(b"PAR1 not parquet")
    with pytest.raises(CorruptArtifactError, match=r"rows\.parts/.*not a readable Parquet file"):
        table.read()


def test_a_compacted_part_without_its_list_is_named(store: ArtifactStore) -> None:
    table = _table(store)
    table.append(_rows(0))
    table.append(_rows(1))
    table.compact()
    (name,) = table.part_names()
    pq.write_table(_rows(0, 1), str(Path(store.root, table.parts_relpath, name)))  # metadata dropped
    with pytest.raises(CorruptArtifactError, match="compacted part without"):
        table.read()
