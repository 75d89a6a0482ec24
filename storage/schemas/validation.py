"""Validation of tables against their schemas (``SchemaError`` naming the file and every offending column), the
nulls of columns added in a later version, and the JSON Schema of a table's row."""

from __future__ import annotations

import pyarrow as pa

from storage.errors import SchemaError
from storage.schemas.base import SCHEMA_NAME_KEY, SCHEMA_VERSION_KEY, metadata_strings, schema_version
from storage.schemas.registry import TABLES


def validate_table(table: pa.Table, schema: pa.Schema, source: str, *, require_metadata: bool = True) -> None:
    """Check ``table`` against ``schema``; raise one ``SchemaError`` listing every problem.

    Checks: ``schema_name`` (and ``schema_version`` not newer than supported nor older than the
    oldest readable), each expected column present with the expected type (fixed widths named
    explicitly), no unexpected columns, and no nulls (top-level or inside list values) in
    non-nullable columns.

    Args:
        source: the file (URI) named in the message.
        require_metadata: when False (tables built in memory before writing) missing metadata is
            accepted; present but different metadata is still an error.
    """
    problems = _metadata_problems(metadata_strings(table.schema.metadata), metadata_strings(schema.metadata),
                                  require_metadata)
    actual_names = set(table.schema.names)
    older = _older_version(table.schema, schema)
    for field in schema:
        if field.name not in actual_names:
            if field.nullable and older:  # added in a later version: read as nulls (fill_added_columns)
                continue
            problems.append(f"column {field.name!r} is missing (expected {field.type})")
            continue
        actual = table.schema.field(field.name).type
        if actual != field.type:
            problems.append(_type_problem(field.name, actual, field.type))
        elif not field.nullable:
            nulls = _null_count(table.column(field.name))
            if nulls:
                problems.append(f"column {field.name!r} has {nulls} null value(s) but is not nullable")
    extra = [n for n in table.schema.names if n not in set(schema.names)]
    if extra:
        problems.append(f"unexpected column(s) {extra} (not in schema)")
    if problems:
        name = metadata_strings(schema.metadata).get(SCHEMA_NAME_KEY, "?")
        raise SchemaError(f"{source}: does not match schema {name!r}: " + "; ".join(problems))


def _older_version(actual: pa.Schema, expected: pa.Schema) -> bool:
    """The table's ``schema_version`` is older than ``expected``'s (False when either has none)."""
    try:
        return int(metadata_strings(actual.metadata)[SCHEMA_VERSION_KEY]) < schema_version(expected)
    except (KeyError, ValueError):
        return False


def fill_added_columns(table: pa.Table, schema: pa.Schema) -> pa.Table:
    """``table`` with every nullable column of ``schema`` it lacks appended as nulls (a file written before the
    column was added; :func:`validate_table` accepts it only then)."""
    for field in schema:
        if field.name not in table.schema.names and field.nullable:
            table = table.append_column(field, pa.nulls(table.num_rows, field.type))
    return table


def _metadata_problems(actual: dict[str, str], expected: dict[str, str], required: bool) -> list[str]:
    problems: list[str] = []
    name = expected[SCHEMA_NAME_KEY]
    if SCHEMA_NAME_KEY not in actual:
        if required:
            problems.append(f"metadata has no {SCHEMA_NAME_KEY!r} (expected {name!r})")
    elif actual[SCHEMA_NAME_KEY] != name:
        problems.append(f"{SCHEMA_NAME_KEY} is {actual[SCHEMA_NAME_KEY]!r}, expected {name!r}")
    if SCHEMA_VERSION_KEY not in actual:
        if required:
            problems.append(f"metadata has no {SCHEMA_VERSION_KEY!r}")
        return problems
    current = int(expected[SCHEMA_VERSION_KEY])
    oldest = TABLES[name].min_version if name in TABLES else current
    try:
        version = int(actual[SCHEMA_VERSION_KEY])
    except ValueError:
        return [*problems, f"{SCHEMA_VERSION_KEY} {actual[SCHEMA_VERSION_KEY]!r} is not an integer"]
    if version > current:
        problems.append(f"{SCHEMA_VERSION_KEY} {version} is newer than supported version {current} (upgrade simsplat)")
    elif version < oldest:
        problems.append(f"{SCHEMA_VERSION_KEY} {version} is older than the oldest readable version {oldest}")
    return problems


def _type_problem(column: str, actual: pa.DataType, expected: pa.DataType) -> str:
    if (
        pa.types.is_fixed_size_list(actual)
        and pa.types.is_fixed_size_list(expected)
        and actual.value_type == expected.value_type
    ):
        return f"column {column!r} has fixed width {actual.list_size}, expected {expected.list_size}"
    return f"column {column!r} has type {actual}, expected {expected}"


def _is_list(t: pa.DataType) -> bool:
    return pa.types.is_list(t) or pa.types.is_large_list(t) or pa.types.is_fixed_size_list(t)


def _null_count(column: pa.ChunkedArray) -> int:
    """Nulls in ``column`` and in the values of (nested) list columns."""
    total = 0
    for chunk in column.chunks:
        array: pa.Array = chunk
        total += array.null_count
        while _is_list(array.type):
            array = array.flatten()
            total += array.null_count
    return total


# ----------------------------------------------------------------------------- JSON Schema export
def json_schema(schema: pa.Schema) -> dict:
    """JSON Schema (draft 2020-12) of one row of ``schema``, for documentation and external tools."""
    meta = metadata_strings(schema.metadata)
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": meta.get(SCHEMA_NAME_KEY, ""),
        "description": f"one row of table {meta.get(SCHEMA_NAME_KEY, '')!r}, schema_version "
        f"{meta.get(SCHEMA_VERSION_KEY, '?')}",
        "type": "object",
        "properties": {field.name: _json_type(field.type) if not field.nullable
                       else {"anyOf": [_json_type(field.type), {"type": "null"}]} for field in schema},
        "required": [field.name for field in schema if not field.nullable],
        "additionalProperties": False,
    }


def _json_type(t: pa.DataType) -> dict:
    if pa.types.is_string(t) or pa.types.is_large_string(t):
        return {"type": "string"}
    if pa.types.is_boolean(t):
        return {"type": "boolean"}
    if pa.types.is_integer(t):
        return {"type": "integer"}
    if pa.types.is_floating(t):
        return {"type": "number"}
    if pa.types.is_fixed_size_list(t):
        return {"type": "array", "items": _json_type(t.value_type), "minItems": t.list_size, "maxItems": t.list_size}
    if pa.types.is_map(t):
        return {"type": "object", "additionalProperties": _json_type(t.item_type)}
    if pa.types.is_list(t) or pa.types.is_large_list(t):
        return {"type": "array", "items": _json_type(t.value_type)}
    raise TypeError(f"no JSON Schema mapping for arrow type {t}")
