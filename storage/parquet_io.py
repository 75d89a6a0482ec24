"""Parquet encoding of validated tables (stream level; ``ArtifactStore`` supplies the streams).

Written files carry the schema metadata (``schema_name``, ``schema_version``, dims) and use zstd
compression. Reading validates against the expected schema and returns the table cast to it, so
callers always see canonical types (e.g. list child names ``item`` rather than Parquet's ``element``).
"""

from __future__ import annotations

import logging

import pyarrow as pa
import pyarrow.parquet as pq

from storage.errors import CorruptArtifactError
from storage.schemas.base import schema_name
from storage.schemas.registry import schema_from_metadata
from storage.schemas.validation import fill_added_columns, validate_table

logger = logging.getLogger(__name__)

COMPRESSION = "zstd"


def conform(table: pa.Table, schema: pa.Schema, source: str) -> pa.Table:
    """Validate an in-memory table and return it with ``schema`` (column order, metadata) attached.

    Raises:
        SchemaError: naming ``source`` and the offending columns.
    """
    validate_table(table, schema, source, require_metadata=False)
    return table.select(schema.names).cast(schema)


def write_parquet(out: pa.NativeFile, table: pa.Table) -> None:
    """Encode an already conformed ``table`` to ``out``."""
    pq.write_table(table, out, compression=COMPRESSION)


def read_parquet(source_file: pa.NativeFile, schema: pa.Schema | str, source: str) -> pa.Table:
    """Decode, validate and conform one Parquet file.

    Args:
        source_file: random-access input.
        schema: expected schema, or a table name (dims are then read from the file metadata).
        source: the file URI named in errors.

    Raises:
        CorruptArtifactError: the bytes are not a readable Parquet file (truncated, garbage).
        SchemaError: the table does not match the schema.
    """
    try:
        table = pq.read_table(source_file)
    except (pa.ArrowException, OSError) as exc:
        raise CorruptArtifactError(f"{source}: not a readable Parquet file ({exc})") from exc
    if isinstance(schema, str):
        schema = schema_from_metadata(schema, table.schema.metadata, source)
    validate_table(table, schema, source)
    table = fill_added_columns(table, schema)
    logger.debug("read %s (%s, %d rows)", source, schema_name(schema), table.num_rows)
    return table.select(schema.names).cast(schema)
