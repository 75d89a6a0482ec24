"""Checked column reads from Arrow tables on disk: feather (Argoverse 2 sensor logs) and Parquet (Argoverse 2
motion-forecasting scenarios); needs ``pyarrow`` when called."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from simsplat_core.data.errors import CorruptLogError

if TYPE_CHECKING:
    import pyarrow as pa

#: File formats ``read_columns`` reads.
TABLE_FORMATS: tuple[str, ...] = ("feather", "parquet")


def read_columns(
    path: str | Path,
    float_columns: Sequence[str] = (),
    int_columns: Sequence[str] = (),
    str_columns: Sequence[str] = (),
    bool_columns: Sequence[str] = (),
    file_format: str = "feather",
) -> dict[str, np.ndarray]:
    """Read the named columns of a feather or Parquet file as ``[N]`` numpy arrays.

    ``float_columns`` -> float64 (must be finite), ``int_columns`` -> int64, ``str_columns`` -> object
    arrays of ``str``, ``bool_columns`` -> bool. Extra columns are ignored.

    Args:
        file_format: ``"feather"`` or ``"parquet"`` (``TABLE_FORMATS``).

    Raises:
        CorruptLogError: the file is missing or unreadable, or a column is missing, has nulls, has
            the wrong type or non-finite values; the message names the file and the column.
        ValueError: an unknown ``file_format``.
    """
    # pyarrow is imported here so that simsplat_core.data (and the Waymo loader) import without it.
    import pyarrow as pa  # noqa: PLC0415
    import pyarrow.feather as feather  # noqa: PLC0415
    import pyarrow.parquet as pq  # noqa: PLC0415

    if file_format not in TABLE_FORMATS:
        raise ValueError(f"unknown table format {file_format!r}: expected one of {TABLE_FORMATS}")
    path = Path(path)
    if not path.is_file():
        raise CorruptLogError(path, "file", "missing")
    wanted = [*float_columns, *int_columns, *str_columns, *bool_columns]
    try:
        if file_format == "feather":
            table = feather.read_table(path, memory_map=False)
        else:
            table = pq.read_table(path, columns=[c for c in wanted if c in pq.read_schema(path).names])
    except (pa.ArrowException, OSError) as exc:
        raise CorruptLogError(path, "file", f"not a readable {file_format} table: {exc}") from exc
    missing = [c for c in wanted if c not in table.column_names]
    if missing:
        raise CorruptLogError(path, f"column {missing[0]!r}", f"required column missing (have {table.column_names})")
    kinds = {**dict.fromkeys(float_columns, "float"), **dict.fromkeys(int_columns, "int"),
             **dict.fromkeys(bool_columns, "bool"), **dict.fromkeys(str_columns, "str")}
    out: dict[str, np.ndarray] = {}
    for name in wanted:
        column = table.column(name)
        if column.null_count:
            raise CorruptLogError(path, f"column {name!r}", f"{column.null_count} null values")
        try:
            out[name] = _column_values(column, kinds[name])
        except (TypeError, pa.ArrowException) as exc:
            raise CorruptLogError(path, f"column {name!r}", str(exc)) from exc
    return out


def _column_values(column: pa.ChunkedArray, kind: str) -> np.ndarray:
    """One Arrow column as an ``[N]`` array of ``kind`` (``"str"``, ``"bool"``, ``"int"`` or ``"float"``).

    Raises:
        TypeError: the column's type does not hold ``kind``, or a float column has a non-finite value.
    """
    import pyarrow as pa  # noqa: PLC0415 -- optional dependency, as in read_columns
    import pyarrow.compute as pc  # noqa: PLC0415

    if kind == "str":
        if pa.types.is_dictionary(column.type):
            column = pc.cast(column, pa.string())
        if not (pa.types.is_string(column.type) or pa.types.is_large_string(column.type)):
            raise TypeError(f"expected strings, got {column.type}")
        return np.array(column.to_pylist(), dtype=object)
    if kind == "bool":
        if not pa.types.is_boolean(column.type):
            raise TypeError(f"expected booleans, got {column.type}")
        return np.asarray(column.to_numpy(zero_copy_only=False), dtype=bool)
    if kind == "int":
        if not pa.types.is_integer(column.type):
            raise TypeError(f"expected integers, got {column.type}")
        return column.to_numpy().astype(np.int64)
    if not (pa.types.is_floating(column.type) or pa.types.is_integer(column.type)):
        raise TypeError(f"expected numbers, got {column.type}")
    values = pc.cast(column, pa.float64()).to_numpy()
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        raise TypeError(f"non-finite value {values[bad[0]]} in row {bad[0]}")
    return values
