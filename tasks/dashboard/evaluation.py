"""The evaluation pages: every declared evaluation table of every run in the store, read through the table
declarations (``simsplat_core.eval.table_registry``), the trends of their headline metrics across runs and the
paper's figures beside ours.

    view = read_evaluation(store)                    # runs with their tables, trends, the paper's figures
    one = read_evaluation_table(store, run_id, name)   # one table with every column's meaning and unit

Nothing here knows a particular table: names, columns, meanings, units, keys, printing, headline metrics and the
paper's figures all come from the ``TableSpec`` declarations. A table that cannot be read (truncated Parquet, a
schema that does not match its declaration) becomes a section whose message names the file; the others render.
"""

from __future__ import annotations

import functools
import logging
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import pyarrow as pa

from simsplat_core.eval.table_headlines import Headline, PaperFigure, headline_values
from simsplat_core.eval.table_registry import EVAL_TABLES
from simsplat_core.eval.table_spec import TableSpec, cell
from storage.runs import RUNS_DIR, list_run_tables, read_run_table, run_dir, run_table_relpath
from storage.store import ArtifactStore, join_relpath
from tasks.dashboard.sections import READ_ERRORS, Section, section

logger = logging.getLogger(__name__)

#: Rows a table page shows at most (the JSON twin and the Parquet file hold them all).
MAX_ROWS = 2000
#: Series a trend chart draws at most (the rest are named on the table's page).
MAX_SERIES = 8


@dataclass(frozen=True)
class ColumnInfo:
    """A shown column: its name, meaning and unit from the declaration, and whether it is a row key."""

    name: str
    meaning: str
    unit: str
    key: bool


@dataclass(frozen=True)
class Cell:
    """One shown value, formatted as the declaration prints it; ``paper``: the paper's figure for it (``""``)."""

    text: str
    paper: str = ""


@dataclass(frozen=True)
class TableData:
    """One run's table as shown.

    Attributes:
        name, title, row: the declaration's name, title and what one row is.
        detail: a per-item table (every prompt or query): the run overview links it instead of showing it.
        columns: the shown columns (the declaration's printed columns, or every column on the table's own page).
        rows: the shown rows' cells (the declaration's row filter on the overview; every row, up to
            :data:`MAX_ROWS`, on the table's own page).
        num_rows: rows in the file; shown_rows: rows in ``rows``.
        file: the Parquet file's path inside the store.
    """

    name: str
    title: str
    row: str
    detail: bool
    columns: tuple[ColumnInfo, ...]
    rows: tuple[tuple[Cell, ...], ...]
    num_rows: int
    shown_rows: int
    file: str


@dataclass(frozen=True)
class RunTables:
    """One run's evaluation tables.

    Attributes:
        run_id: the run; written_at: when its tables were written (``""``: unknown).
        stage: what the run evaluated (its manifest's ``stage``, ``""`` when it says none).
        tables: one section per declared table present (its content, or the message naming the file at fault).
        undeclared: Parquet files under ``tables/`` that no declaration names (not shown).
    """

    run_id: str
    written_at: str
    stage: str
    tables: tuple[Section[TableData], ...]
    undeclared: tuple[str, ...]


@dataclass(frozen=True)
class TrendSeries:
    """One line of a trend: its label (the row's key values, or ``mean``) and its value per run (``None``: none)."""

    label: str
    values: tuple[float | None, ...]


@dataclass(frozen=True)
class Trend:
    """A headline metric across the runs that hold its table, oldest first.

    Attributes:
        table, title: the table's name and title; column, meaning, unit: the metric from the declaration.
        rows: which rows it follows (``"category = total"``, ``"mean of every row"``, ``"every row"``).
        better: ``"higher"`` or ``"lower"``.
        runs: the runs on the x axis; series: at most :data:`MAX_SERIES` lines; more_series: lines left out.
    """

    table: str
    title: str
    column: str
    meaning: str
    unit: str
    rows: str
    better: str
    runs: tuple[str, ...]
    series: tuple[TrendSeries, ...]
    more_series: int


@dataclass(frozen=True)
class PaperRow:
    """A figure the paper reports next to ours: ``ours`` from the latest run holding the table (``None``: none)."""

    table: str
    column: str
    unit: str
    rows: str
    paper: float
    source: str
    note: str
    ours: float | None
    ours_run: str


@dataclass(frozen=True)
class PaperComparison:
    """The paper's figures beside ours, and the summary tables for which the paper reports none."""

    rows: tuple[PaperRow, ...]
    without_paper: tuple[str, ...]


@dataclass(frozen=True)
class EvaluationView:
    """The evaluation overview: every run with declared tables (newest first), trends, the paper's figures."""

    store: str
    runs: Section[tuple[RunTables, ...]]
    trends: Section[tuple[Trend, ...]]
    paper: PaperComparison


@dataclass(frozen=True)
class TableView:
    """One run's table on its own page: every column with its meaning and unit, every row, the headline values
    and the paper's figures for its cells."""

    run_id: str
    table: Section[TableData]
    headlines: tuple[tuple[str, str, float], ...]
    paper: tuple[PaperRow, ...]
    declaration: dict[str, Any]


# ----------------------------------------------------------------------------- reading tables
def _where_text(where: Sequence[tuple[str, str]]) -> str:
    return ", ".join(f"{c} = {v}" for c, v in where)


def _paper_cells(spec: TableSpec, table: pa.Table) -> dict[tuple[int, str], str]:
    """``(row index, column) -> the paper's figure`` for the cells of ``table`` the paper reports."""
    found: dict[tuple[int, str], str] = {}
    rows = table.to_pylist()
    for figure in spec.paper:
        for k, row in enumerate(rows):
            if all(str(row.get(c)) == v for c, v in figure.where):
                found[(k, figure.column)] = cell(figure.value, spec.digits, escape=False)
                break
    return found


def table_data(spec: TableSpec, table: pa.Table, file: str, *, full: bool) -> TableData:
    """``table`` of declaration ``spec`` as shown: its printed columns and rows, or (``full``) every column and
    every row up to :data:`MAX_ROWS`, cells formatted as the declaration prints them."""
    names = list(spec.column_names if full else (spec.printed or spec.column_names))
    shown = table if full else spec.printed_rows(table)
    shown = shown.slice(0, MAX_ROWS)
    paper = _paper_cells(spec, shown)
    rows = tuple(tuple(Cell(cell(r[n], spec.digits, escape=False), paper.get((k, n), "")) for n in names)
                 for k, r in enumerate(shown.select(names).to_pylist()))
    columns = tuple(ColumnInfo(n, spec.column(n).meaning, spec.column(n).unit, n in spec.keys) for n in names)
    return TableData(spec.name, spec.title, spec.row, spec.detail, columns, rows, table.num_rows, len(rows), file)


def _manifest(store: ArtifactStore, run_id: str) -> dict[str, Any]:
    try:
        value = store.read_json(join_relpath(run_dir(run_id), "manifest.json"))
    except READ_ERRORS as exc:
        logger.info("evaluation: run %s has no readable manifest: %s", run_id, exc)
        return {}
    return value if isinstance(value, dict) else {}


def _read_table(store: ArtifactStore, run_id: str, spec: TableSpec) -> pa.Table:
    return read_run_table(store, run_dir(run_id), spec)


def _run_tables(store: ArtifactStore, run_id: str, present: Sequence[str]) -> tuple[RunTables, dict[str, pa.Table]]:
    """One run's sections and its tables that could be read (for trends and the paper's figures)."""
    manifest = _manifest(store, run_id)
    sections, read = [], {}
    for name, spec in EVAL_TABLES.items():
        if name not in present:
            continue
        file = run_table_relpath(run_dir(run_id), name)
        loaded = section(f"table {name}", functools.partial(_read_table, store, run_id, spec))
        if loaded.value is not None:
            read[name] = loaded.value
            sections.append(Section(loaded.name, value=table_data(spec, loaded.value, file, full=False)))
        else:
            sections.append(Section(loaded.name, error=loaded.error))
    undeclared = tuple(n for n in present if n not in EVAL_TABLES)
    return RunTables(run_id, str(manifest.get("written_at", "")), str(manifest.get("stage", "")), tuple(sections),
                     undeclared), read


def _evaluated_runs(store: ArtifactStore) -> list[tuple[str, list[str]]]:
    """``(run id, table names)`` of every run folder with tables, by run id."""
    if not store.is_dir(RUNS_DIR):
        return []
    runs = []
    for run_id in sorted(store.listdir(RUNS_DIR)):
        if run_id.startswith("."):
            continue
        names = list_run_tables(store, run_dir(run_id))
        if names:
            runs.append((run_id, names))
    return runs


# ----------------------------------------------------------------------------- trends and the paper's figures
def _rows_text(headline: Headline) -> str:
    selected = _where_text(headline.where) or "every row"
    return f"mean over {selected}" if headline.reduce == "mean" else selected


def headline_trend(spec: TableSpec, headline: Headline, tables: Sequence[tuple[str, pa.Table]]) -> Trend | None:
    """The trend of one headline over ``(run id, table)`` pairs (oldest first); ``None`` when no run has a value."""
    per_run = [(run_id, dict(headline_values(headline, table, spec.keys))) for run_id, table in tables]
    per_run = [(run_id, values) for run_id, values in per_run if values]
    if not per_run:
        return None
    labels = list(dict.fromkeys(label for _, values in per_run for label in values))
    series = tuple(TrendSeries(label, tuple(values.get(label) for _, values in per_run))
                   for label in labels[:MAX_SERIES])
    column = spec.column(headline.column)
    return Trend(spec.name, spec.title, column.name, column.meaning, column.unit, _rows_text(headline),
                 headline.better, tuple(r for r, _ in per_run), series, max(0, len(labels) - MAX_SERIES))


def trends(by_run: Sequence[tuple[str, dict[str, pa.Table]]]) -> tuple[Trend, ...]:
    """Every declared headline's trend over the runs (oldest first) whose table could be read."""
    out = []
    for name, spec in EVAL_TABLES.items():
        tables = [(run_id, read[name]) for run_id, read in by_run if name in read]
        for headline in spec.headlines:
            trend = headline_trend(spec, headline, tables)
            if trend is not None:
                out.append(trend)
    return tuple(out)


def paper_rows(spec: TableSpec, latest: tuple[str, pa.Table] | None) -> tuple[PaperRow, ...]:
    """The paper's figures of ``spec`` beside ours from ``latest`` (``(run id, table)``, or ``None``)."""

    def ours(figure: PaperFigure) -> float | None:
        return None if latest is None else figure.matching_value(latest[1])

    return tuple(PaperRow(spec.name, f.column, spec.column(f.column).unit, _where_text(f.where), f.value, f.source,
                          f.note, ours(f), latest[0] if latest else "") for f in spec.paper)


def paper_comparison(by_run: Sequence[tuple[str, dict[str, pa.Table]]]) -> PaperComparison:
    """The paper's figures of every declaration beside the latest run's values; the summary tables without any."""
    rows: list[PaperRow] = []
    for name, spec in EVAL_TABLES.items():
        latest = next(((run_id, read[name]) for run_id, read in reversed(by_run) if name in read), None)
        rows.extend(paper_rows(spec, latest))
    without = tuple(s.name for s in EVAL_TABLES.values() if not s.paper and not s.detail)
    return PaperComparison(tuple(rows), without)


# ----------------------------------------------------------------------------- the pages
def _read_runs(store: ArtifactStore) -> list[tuple[RunTables, dict[str, pa.Table]]]:
    """Every evaluated run, oldest first (by the time its tables were written, then by id)."""
    runs = [_run_tables(store, run_id, names) for run_id, names in _evaluated_runs(store)]
    return sorted(runs, key=lambda item: (item[0].written_at, item[0].run_id))


def read_evaluation(store: ArtifactStore) -> EvaluationView:
    """Every run's declared tables (newest first), the headline trends and the paper's figures (module
    docstring). A store without runs gives empty sections; nothing is created."""
    loaded = section("evaluation runs", lambda: _read_runs(store))
    runs = loaded.value or []
    by_run = [(r.run_id, read) for r, read in runs]
    view_runs: Section[tuple[RunTables, ...]] = (
        Section(loaded.name, value=tuple(r for r, _ in reversed(runs))) if loaded.ok
        else Section(loaded.name, error=loaded.error))
    return EvaluationView(store.uri(), view_runs, section("trends", lambda: trends(by_run)),
                          paper_comparison(by_run))


def read_evaluation_table(store: ArtifactStore, run_id: str, name: str) -> TableView | None:
    """Table ``name`` of run ``run_id`` with every column and row; ``None`` when the run has no such declared
    table (an unsafe run id included). A file that cannot be read is the section's message."""
    spec = EVAL_TABLES.get(name)
    try:
        present = spec is not None and name in list_run_tables(store, run_dir(run_id))
    except ValueError:
        return None
    if spec is None or not present:
        return None
    file = run_table_relpath(run_dir(run_id), name)
    loaded = section(f"table {name}", lambda: _read_table(store, run_id, spec))
    if loaded.value is None:
        return TableView(run_id, Section(loaded.name, error=loaded.error), (), paper_rows(spec, None), spec.describe())
    table = loaded.value
    headlines = tuple((h.column, label, value) for h in spec.headlines
                      for label, value in headline_values(h, table, spec.keys))
    return TableView(run_id, Section(loaded.name, value=table_data(spec, table, file, full=True)), headlines,
                     paper_rows(spec, (run_id, table)), spec.describe())


__all__ = ["Cell", "ColumnInfo", "EvaluationView", "PaperComparison", "PaperRow", "RunTables", "TableData",
           "TableView", "Trend", "TrendSeries", "headline_trend", "paper_comparison", "read_evaluation",
           "read_evaluation_table", "table_data", "trends"]
