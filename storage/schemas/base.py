"""Schema building blocks shared by every domain: the file-metadata keys, fixed-width vectors, the schema
builder, metadata accessors and the vector column converters."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pyarrow as pa

SCHEMA_NAME_KEY = "schema_name"
SCHEMA_VERSION_KEY = "schema_version"


def vec(width: int) -> pa.DataType:
    """``FixedSizeList<float32>[width]``."""
    return pa.list_(pa.float32(), width)


def make_schema(name: str, version: int, fields: list[tuple[str, pa.DataType]], *, nullable: tuple[str, ...] = (),
                **dims: int) -> pa.Schema:
    """A schema of ``fields`` (non-nullable except ``nullable``) with file metadata ``schema_name``,
    ``schema_version`` and the integer ``dims``."""
    metadata = {SCHEMA_NAME_KEY: name, SCHEMA_VERSION_KEY: str(version)}
    metadata.update({key: str(value) for key, value in dims.items()})
    return pa.schema([pa.field(n, t, nullable=n in nullable) for n, t in fields], metadata=metadata)


def metadata_strings(metadata: Mapping[bytes, bytes] | None) -> dict[str, str]:
    """Arrow schema metadata decoded to ``str -> str``."""
    return {k.decode(): v.decode() for k, v in (metadata or {}).items()}


def schema_name(schema: pa.Schema) -> str:
    return metadata_strings(schema.metadata)[SCHEMA_NAME_KEY]


def schema_version(schema: pa.Schema) -> int:
    return int(metadata_strings(schema.metadata)[SCHEMA_VERSION_KEY])


# ----------------------------------------------------------------------------- column helpers
def vectors_to_arrow(values: np.ndarray, width: int) -> pa.FixedSizeListArray:
    """``[N, width]`` (or anything reshapeable to it) -> ``FixedSizeList<float32>[width]`` array (N rows)."""
    flat = np.ascontiguousarray(np.asarray(values, dtype=np.float32).reshape(-1))
    if flat.size % width:
        raise ValueError(f"cannot split {flat.size} values into rows of width {width}")
    return pa.FixedSizeListArray.from_arrays(pa.array(flat, pa.float32()), width)


def arrow_to_vectors(column: pa.ChunkedArray | pa.Array) -> np.ndarray:
    """``FixedSizeList<float32>[w]`` column -> ``[N, w]`` float32 array."""
    array = column.combine_chunks() if isinstance(column, pa.ChunkedArray) else column
    width = array.type.list_size
    values = array.flatten().to_numpy(zero_copy_only=False)
    return np.asarray(values, dtype=np.float32).reshape(len(array), width)

