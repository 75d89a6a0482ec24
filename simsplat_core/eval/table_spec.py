"""Declarations of evaluation tables: what each column means, its unit, the keys, and how the table prints.

An evaluation table is declared once, beside the code that computes it, as a :class:`TableSpec`. Everything
that handles tables generically works from the declaration: storage validates and writes any declared table
(Parquet whose file metadata carries ``schema_name`` / ``schema_version``, plus Markdown), the CLI prints it and
Prefect table artifacts render it. ``simsplat_core.eval.table_registry`` lists every declaration.

    SPEC = TableSpec("editing", "Editing: task completion", "(method, category)", (
        Column("method", pa.string(), "the editing method"),
        Column("rate", pa.float64(), "completed / prompts", "share"), ...), keys=("method", "category"))
    table = pa.Table.from_pylist(rows, schema=SPEC.schema)
    text = SPEC.render_markdown(table)                    # the .md file
    header, cells = SPEC.rows_for_console(table)          # strings for a console table

Framework-free (pyarrow only).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import pyarrow as pa

from simsplat_core.eval.table_headlines import Headline, PaperFigure

#: File-metadata keys of every persisted table (the same keys ``storage.schemas`` validates).
SCHEMA_NAME_KEY = "schema_name"
SCHEMA_VERSION_KEY = "schema_version"

#: ``row_filter(table) -> indices of the rows to print`` (Markdown and console), e.g. only the failed outcomes.
RowFilter = Callable[[pa.Table], Sequence[int]]


@dataclass(frozen=True)
class Column:
    """One column of a declared table.

    Attributes:
        name: the column name.
        type: its arrow type.
        meaning: what one value says (one line).
        unit: ``"dB"``, ``"s"``, ``"m"``, ``"share"`` (in ``[0, 1]``), ``"count"``, ... (``""``: none).
        nullable: may hold nulls (undefined values); every other column must not.
    """

    name: str
    type: pa.DataType
    meaning: str
    unit: str = ""
    nullable: bool = False


@dataclass(frozen=True)
class TableSpec:
    """One evaluation table: its schema, the meaning of its columns, its keys, and how it prints.

    Attributes:
        name: the table's name (file stem: ``tables/<name>.parquet`` and ``.md``).
        title: a one-line title (console tables, summaries).
        row: what one row is (``"method"``, ``"(method, category)"``).
        columns: the columns, in file order.
        keys: the columns that identify a row.
        version: the ``schema_version`` written into the file metadata.
        schema_name: the ``schema_name`` of the file metadata (default: ``name``).
        digits: decimals of floats in Markdown and console cells.
        printed: the columns the Markdown and the console show, in order (default: every column).
        row_filter: the rows the Markdown and the console show (default: every row).
        detail: a per-item table (every prompt, every query) rather than a summary; consoles leave it out.
        headlines: the metrics that summarise the table across runs (trends), ``()``: none.
        paper: the paper's figures for cells of this table, ``()``: the paper reports none.
    """

    name: str
    title: str
    row: str
    columns: tuple[Column, ...]
    keys: tuple[str, ...]
    version: int = 1
    schema_name: str = ""
    digits: int = 3
    printed: tuple[str, ...] = ()
    row_filter: RowFilter | None = field(default=None, compare=False)
    detail: bool = False
    headlines: tuple[Headline, ...] = ()
    paper: tuple[PaperFigure, ...] = ()

    def __post_init__(self) -> None:
        names = [c.name for c in self.columns]
        if len(set(names)) != len(names):
            raise ValueError(f"table {self.name!r}: duplicate column names in {names}")
        unknown = [c for c in (*self.keys, *self.printed) if c not in names]
        if unknown:
            raise ValueError(f"table {self.name!r}: keys / printed columns {unknown} are not columns {names}")
        named = [c for h in self.headlines for c in h.columns if c not in names]
        named += [c for f in self.paper for c in f.columns if c not in names]
        if named:
            raise ValueError(f"table {self.name!r}: headline / paper columns {named} are not columns {names}")

    @property
    def column_names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.columns)

    @property
    def schema(self) -> pa.Schema:
        """The table's arrow schema with file metadata ``schema_name`` and ``schema_version``."""
        metadata = {SCHEMA_NAME_KEY: self.schema_name or self.name, SCHEMA_VERSION_KEY: str(self.version)}
        return pa.schema([pa.field(c.name, c.type, nullable=c.nullable) for c in self.columns], metadata=metadata)

    def column(self, name: str) -> Column:
        """The column ``name`` (``KeyError`` naming the table and its columns)."""
        for c in self.columns:
            if c.name == name:
                return c
        raise KeyError(f"table {self.name!r} has no column {name!r}; it has {list(self.column_names)}")

    def table(self, rows: Sequence[dict[str, Any]]) -> pa.Table:
        """``rows`` (dicts by column name) as a table of this schema."""
        return pa.Table.from_pylist(list(rows), schema=self.schema)

    def printed_rows(self, table: pa.Table) -> pa.Table:
        """The rows the Markdown and the console show (:attr:`row_filter`)."""
        if self.row_filter is None:
            return table
        return table.take(pa.array(list(self.row_filter(table)), pa.int64()))

    def render_markdown(self, table: pa.Table, *, digits: int | None = None, before: str = "", after: str = "") -> str:
        """The table as GitHub Markdown (the ``.md`` file): :attr:`printed` columns of the :attr:`row_filter`
        rows, floats with :attr:`digits` decimals (or ``digits``), NaN as ``–``, null blank; ``before`` /
        ``after`` wrap it."""
        shown = self.digits if digits is None else digits
        return before + markdown(self.printed_rows(table), shown, self.printed or None) + after

    def rows_for_console(self, table: pa.Table) -> tuple[list[str], list[list[str]]]:
        """``(header, rows)`` of strings for a console table: the same columns, rows and formats as the Markdown."""
        names = list(self.printed or self.column_names)
        rows = self.printed_rows(table).select(names).to_pylist()
        return names, [[cell(r[n], self.digits, escape=False) for n in names] for r in rows]

    def describe(self) -> dict[str, Any]:
        """The declaration as plain data (for listings: name, title, row, keys, version and every column)."""
        return {"name": self.name, "title": self.title, "row": self.row, "keys": list(self.keys),
                "version": self.version, "detail": self.detail,
                "headlines": [h.column for h in self.headlines], "paper_figures": len(self.paper),
                "columns": [{"name": c.name, "type": str(c.type), "meaning": c.meaning, "unit": c.unit,
                             "nullable": c.nullable} for c in self.columns]}


def columns_of(types: Sequence[tuple[str, pa.DataType]], meanings: dict[str, tuple[str, str]],
               nullable: Sequence[str] = ()) -> tuple[Column, ...]:
    """:class:`Column` s from ``(name, type)`` pairs and ``name -> (meaning, unit)`` (``KeyError`` naming a column
    without a meaning)."""
    missing = [n for n, _ in types if n not in meanings]
    if missing:
        raise KeyError(f"columns without a meaning: {missing}")
    return tuple(Column(n, t, *meanings[n], nullable=n in nullable) for n, t in types)


def cell(value: Any, digits: int, *, escape: bool = True) -> str:
    """One printed value: floats with ``digits`` decimals, NaN as ``–``, ``None`` blank, ``|`` escaped."""
    if value is None:
        return ""
    if isinstance(value, float):
        return "–" if math.isnan(value) else f"{value:.{digits}f}"
    return str(value).replace("|", "\\|") if escape else str(value)


def markdown(table: pa.Table, digits: int = 3, columns: Sequence[str] | None = None) -> str:
    """A GitHub Markdown table of ``table`` (floats with ``digits`` decimals, NaN as ``–``).

    Raises:
        KeyError: ``columns`` names a column the table lacks.
    """
    names = list(columns) if columns is not None else table.column_names
    missing = [c for c in names if c not in table.column_names]
    if missing:
        raise KeyError(f"table has no columns {missing}; it has {table.column_names}")
    rows = table.select(names).to_pylist()
    header = "| " + " | ".join(names) + " |"
    align = "|" + "|".join(":---" if i == 0 else "---:" for i in range(len(names))) + "|"
    body = ["| " + " | ".join(cell(r[c], digits) for c in names) + " |" for r in rows]
    return "\n".join([header, align, *body]) + "\n"


__all__ = ["Column", "Headline", "PaperFigure", "RowFilter", "SCHEMA_NAME_KEY", "SCHEMA_VERSION_KEY", "TableSpec",
           "cell", "columns_of", "markdown"]
