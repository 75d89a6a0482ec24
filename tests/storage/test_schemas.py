"""Every table schema: round trip, and SchemaError naming file and column for each kind of mismatch."""

from __future__ import annotations

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from storage import (
    TABLES,
    ArtifactStore,
    CorruptArtifactError,
    SchemaError,
    gaussians_schema,
    json_schema,
    nodes_schema,
    schema_name,
    schema_version,
)
from storage.schemas.edits import EDITS_MINING_COLUMNS, TRAJECTORY_BOX_COLUMNS

SCHEMAS: dict[str, pa.Schema] = {
    **{name: spec.build() for name, spec in TABLES.items() if not spec.dims},
    "gaussians": gaussians_schema(feature_dim=8),
    "gaussians_sh_nofeat": gaussians_schema(feature_dim=0, color_dim=48),
    "nodes": nodes_schema(dim=16),
}
COLUMNS = [(key, field.name) for key, schema in SCHEMAS.items() for field in schema]
FIXED_COLUMNS = [(k, c) for k, c in COLUMNS if pa.types.is_fixed_size_list(SCHEMAS[k].field(c).type)]


def _value(t: pa.DataType, i: int):
    if pa.types.is_string(t):
        return f"s{i}"
    if pa.types.is_boolean(t):
        return i % 2 == 0
    if pa.types.is_integer(t):
        return i
    if pa.types.is_floating(t):
        return 0.25 * i
    if pa.types.is_fixed_size_list(t):
        return [_value(t.value_type, i + j) for j in range(t.list_size)]
    if pa.types.is_map(t):
        return [("k", f"v{i}"), ("other", "")]
    if pa.types.is_list(t):
        return [_value(t.value_type, i + j) for j in range(i + 1)]
    raise TypeError(t)


def sample_table(schema: pa.Schema, rows: int = 3) -> pa.Table:
    return pa.Table.from_pylist([{f.name: _value(f.type, i) for f in schema} for i in range(rows)], schema=schema)


def _write_raw(store: ArtifactStore, relpath: str, table: pa.Table) -> None:
    """Write a Parquet file bypassing validation (simulates a foreign or older writer)."""
    with store.open_output(relpath) as out:
        pq.write_table(table, out)


def _replace(table: pa.Table, column: str, array: pa.Array) -> pa.Table:
    return table.set_column(table.schema.get_field_index(column), column, array)


@pytest.mark.parametrize("key", sorted(SCHEMAS))
def test_round_trip_every_schema(store: ArtifactStore, key: str) -> None:
    schema = SCHEMAS[key]
    table = sample_table(schema)
    store.write_table(f"t/{key}.parquet", table, schema)
    back = store.read_table(f"t/{key}.parquet", schema)
    assert back.equals(table) and back.schema.equals(schema, check_metadata=True)
    by_name = store.read_table(f"t/{key}.parquet", schema_name(schema))  # dims from file metadata
    assert by_name.schema.equals(schema, check_metadata=True)
    assert json_schema(schema)["required"] == [f.name for f in schema if not f.nullable]


@pytest.mark.parametrize(("key", "column"), COLUMNS)
def test_missing_column(store: ArtifactStore, key: str, column: str) -> None:
    schema = SCHEMAS[key]
    _write_raw(store, "bad_missing.parquet", sample_table(schema).drop_columns([column]))
    with pytest.raises(SchemaError, match=rf"bad_missing\.parquet.*'{column}' is missing"):
        store.read_table("bad_missing.parquet", schema)


@pytest.mark.parametrize(("key", "column"), COLUMNS)
def test_wrong_type(store: ArtifactStore, key: str, column: str) -> None:
    schema = SCHEMAS[key]
    is_string = pa.types.is_string(schema.field(column).type)
    wrong = pa.array([1, 2, 3], pa.int8()) if is_string else pa.array(["a", "b", "c"])
    _write_raw(store, "bad_type.parquet", _replace(sample_table(schema), column, wrong))
    with pytest.raises(SchemaError, match=rf"bad_type\.parquet.*'{column}' has type"):
        store.read_table("bad_type.parquet", schema)
    with pytest.raises(SchemaError, match=rf"memory\.parquet.*'{column}'"):  # also refused on write
        store.write_table("memory.parquet", _replace(sample_table(schema), column, wrong), schema)
    assert not store.exists("memory.parquet")


@pytest.mark.parametrize(("key", "column"), FIXED_COLUMNS)
def test_wrong_fixed_width(store: ArtifactStore, key: str, column: str) -> None:
    schema = SCHEMAS[key]
    width = schema.field(column).type.list_size
    wrong = pa.array([[0.5] * (width + 1)] * 3, pa.list_(pa.float32(), width + 1))
    _write_raw(store, "bad_width.parquet", _replace(sample_table(schema), column, wrong))
    expected = rf"bad_width\.parquet.*'{column}' has fixed width {width + 1}, expected {width}"
    with pytest.raises(SchemaError, match=expected):
        store.read_table("bad_width.parquet", schema)


@pytest.mark.parametrize("key", sorted(SCHEMAS))
def test_wrong_schema_name(store: ArtifactStore, key: str) -> None:
    schema = SCHEMAS[key]
    meta = {**schema.metadata, b"schema_name": b"something_else"}
    _write_raw(store, "bad_name.parquet", sample_table(schema).replace_schema_metadata(meta))
    with pytest.raises(SchemaError, match=r"bad_name\.parquet.*schema_name is 'something_else'"):
        store.read_table("bad_name.parquet", schema)


@pytest.mark.parametrize("key", sorted(SCHEMAS))
def test_future_schema_version(store: ArtifactStore, key: str) -> None:
    schema = SCHEMAS[key]
    meta = {**schema.metadata, b"schema_version": str(schema_version(schema) + 1).encode()}
    _write_raw(store, "future.parquet", sample_table(schema).replace_schema_metadata(meta))
    with pytest.raises(SchemaError, match=r"future\.parquet.*schema_version \d+ is newer"):
        store.read_table("future.parquet", schema)


@pytest.mark.parametrize("key", sorted(SCHEMAS))
def test_missing_metadata(store: ArtifactStore, key: str) -> None:
    schema = SCHEMAS[key]
    _write_raw(store, "nometa.parquet", sample_table(schema).replace_schema_metadata(None))
    with pytest.raises(SchemaError, match=r"nometa\.parquet.*no 'schema_name'"):
        store.read_table("nometa.parquet", schema)


@pytest.mark.parametrize(("key", "column"), [(k, c) for k, c in COLUMNS if not SCHEMAS[k].field(c).nullable])
def test_nulls_in_non_nullable_column(store: ArtifactStore, key: str, column: str) -> None:
    schema = SCHEMAS[key]
    nullable = pa.schema([f.with_nullable(True) for f in schema], metadata=schema.metadata)
    rows = sample_table(schema).to_pylist()
    rows[1][column] = None
    _write_raw(store, "nulls.parquet", pa.Table.from_pylist(rows, schema=nullable))
    with pytest.raises(SchemaError, match=rf"nulls\.parquet.*'{column}' has 1 null"):
        store.read_table("nulls.parquet", schema)


def test_null_inside_fixed_size_list(store: ArtifactStore) -> None:
    schema = SCHEMAS["tracks"]
    rows = sample_table(schema).to_pylist()
    rows[0]["center"] = [1.0, None, 2.0]
    with pytest.raises(SchemaError, match=r"'center' has 1 null"):
        store.write_table("t.parquet", pa.Table.from_pylist(rows, schema=schema), schema)


def test_extra_column_is_rejected(store: ArtifactStore) -> None:
    schema = SCHEMAS["metrics"]
    table = sample_table(schema).append_column("surprise", pa.array([1, 2, 3]))
    with pytest.raises(SchemaError, match=r"t\.parquet.*'surprise'"):
        store.write_table("t.parquet", table, schema)


def test_dims_come_from_metadata(store: ArtifactStore) -> None:
    store.write_table("g.parquet", sample_table(gaussians_schema(4)), gaussians_schema(4))
    with pytest.raises(SchemaError, match=r"g\.parquet.*'feature' has fixed width 4, expected 8"):
        store.read_table("g.parquet", gaussians_schema(8))
    assert store.read_table("g.parquet", "gaussians").schema.field("feature").type.list_size == 4
    with pytest.raises(SchemaError, match="unknown table"):
        store.read_table("g.parquet", "no_such_table")


@pytest.mark.parametrize("cut", [0, 7, 100, -8])
def test_truncated_parquet_names_the_file(store: ArtifactStore, cut: int) -> None:
    schema = SCHEMAS["frames"]
    store.write_table("logs/s/frames.parquet", sample_table(schema), schema)
    data = store.read_bytes("logs/s/frames.parquet")
    store.write_bytes("logs/s/frames.parquet", data[:cut] if cut >= 0 else data[cut:])
    with pytest.raises(CorruptArtifactError, match=r"logs/s/frames\.parquet: not a readable Parquet file"):
        store.read_table("logs/s/frames.parquet", schema)


def test_missing_parquet_names_the_file(store: ArtifactStore) -> None:
    with pytest.raises(FileNotFoundError, match=r"absent\.parquet"):
        store.read_table("absent.parquet", SCHEMAS["frames"])


def test_every_schema_has_name_and_version() -> None:
    for key, schema in SCHEMAS.items():
        assert schema_name(schema) in TABLES, key
        assert schema_version(schema) >= 1
        later = {"edits": EDITS_MINING_COLUMNS, "trajectories": TRAJECTORY_BOX_COLUMNS}  # columns of a later version
        added = later.get(schema_name(schema), ())
        assert [f.name for f in schema if f.nullable] == list(added), key
