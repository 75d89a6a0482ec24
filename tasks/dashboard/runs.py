"""The runs pages: every run folder of the store, and one run with its sequence x stage matrix.

A run folder holds a run record (``storage.run_records``: flows record themselves while they run) and/or, for runs
that evaluated something, ``manifest.json`` with tables (``storage.runs``); older evaluation-only runs have no
record, and the pages show what they have. Each run's record, manifest, matrix and tables are read on their own:
a garbled file shows its message where it is used and the rest still renders.
"""

from __future__ import annotations

import datetime
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from storage.artifact_ids import artifact_id
from storage.errors import CorruptArtifactError
from storage.logs import list_logs
from storage.run_records import (
    RunRecord,
    StageRecord,
    list_run_ids,
    parse_time,
    read_run_record,
    read_stage_matrix,
)
from storage.runs import list_run_tables, run_dir
from storage.store import ArtifactStore, join_relpath
from tasks.dashboard.sections import Section, section

#: The status shown for a run folder without a run record (an evaluation-only run).
TABLES_ONLY = "tables only"


@dataclass(frozen=True)
class RunSummary:
    """One row of the runs list.

    Attributes:
        run_id: the run folder; flow: the flow that made it (``""``: unknown, an evaluation-only run).
        status: ``running``, ``completed``, ``failed``, ``interrupted`` (``RunRecord.observed_status``: a running run
            whose heartbeat stopped), ``tables only`` for a run without a record, or ``unreadable``.
        started_at: ISO 8601 UTC (an evaluation-only run: when its manifest was written), ``None``: unknown.
        seconds: duration (so far, for a running run), s; ``None``: unknown.
        code_version: ``git describe`` of the code that ran (``""``: unknown).
        counts: what the run produced (a record's counts, or an evaluation manifest's whole-number fields).
        tables: the run's evaluation tables.
        error: a failed run's error.
        problem: why part of this run could not be read (``""``: none).
    """

    run_id: str
    flow: str
    status: str
    started_at: str | None
    seconds: float | None
    code_version: str
    counts: Mapping[str, int]
    tables: tuple[str, ...]
    error: str = ""
    problem: str = ""


@dataclass(frozen=True)
class RunsView:
    """Attributes: store: the store's URI; runs: every run folder, newest start first."""

    store: str
    runs: Section[tuple[RunSummary, ...]]


@dataclass(frozen=True)
class MatrixRow:
    """One sequence's stages, in the matrix's column order (``None``: the stage was never reached); ``in_store``:
    the store holds its log (a log that failed to load has none, so nothing to link to)."""

    seq_id: str
    cells: tuple[StageRecord | None, ...]
    in_store: bool = True


@dataclass(frozen=True)
class RunMatrix:
    """A run's sequence x stage matrix.

    Attributes:
        stages: the columns; rows: one per sequence; problems: stage files that could not be read (named).
        statuses: how many cells are in each status.
    """

    stages: tuple[str, ...]
    rows: tuple[MatrixRow, ...]
    problems: tuple[str, ...]
    statuses: Mapping[str, int]


@dataclass(frozen=True)
class RunTableLink:
    """One evaluation table of a run: its name, where the evaluation page shows it, its Markdown's artifact id."""

    name: str
    href: str
    markdown_id: str


@dataclass(frozen=True)
class RunView:
    """One run.

    Attributes:
        run_id: the run.
        live: whether the run is still running (its matrix refreshes).
        summary: the run as in the runs list.
        record: its run record (``None`` inside: none, an evaluation-only run).
        manifest: its evaluation manifest (``None`` inside: none).
        matrix: its sequence x stage matrix.
        tables: its evaluation tables, with links.
    """

    run_id: str
    live: bool
    summary: RunSummary
    record: Section[RunRecord | None]
    manifest: Section[dict[str, Any] | None]
    matrix: Section[RunMatrix]
    tables: Section[tuple[RunTableLink, ...]]


def _manifest(store: ArtifactStore, run_id: str) -> dict[str, Any] | None:
    relpath = join_relpath(run_dir(run_id), "manifest.json")
    if not store.exists(relpath):
        return None
    data = store.read_json(relpath)
    if not isinstance(data, dict):
        raise CorruptArtifactError(f"{store.uri(relpath)}: a manifest must be a JSON object")
    return data


def _manifest_counts(manifest: Mapping[str, Any]) -> dict[str, int]:
    return {k: v for k, v in manifest.items() if isinstance(v, int) and not isinstance(v, bool)}


def _summary(store: ArtifactStore, run_id: str, record: Section[RunRecord | None],
             manifest: Section[dict[str, Any] | None], now: datetime.datetime) -> RunSummary:
    tables = tuple(list_run_tables(store, run_dir(run_id)))
    problem = "; ".join(s.error for s in (record, manifest) if not s.ok)
    rec = record.value
    if rec is not None:
        return RunSummary(run_id, rec.flow, rec.observed_status(now), rec.started_at, rec.seconds(now),
                          rec.code_version, dict(rec.counts), tables, rec.error, problem)
    man = manifest.value or {}
    written = man.get("written_at")
    status = "unreadable" if not record.ok else TABLES_ONLY
    return RunSummary(run_id, str(man.get("stage", "")), status, written if isinstance(written, str) else None, None,
                      str(man.get("code_version", "")), _manifest_counts(man), tables, "", problem)


def _start_key(summary: RunSummary) -> tuple[int, float, str]:
    try:
        start = parse_time(summary.started_at)
    except ValueError:
        start = None
    return (0, 0.0, summary.run_id) if start is None else (1, start.timestamp(), summary.run_id)


def _read_run(store: ArtifactStore, run_id: str, now: datetime.datetime
              ) -> tuple[Section[RunRecord | None], Section[dict[str, Any] | None], RunSummary]:
    record = section("run record", lambda: read_run_record(store, run_id))
    manifest = section("evaluation manifest", lambda: _manifest(store, run_id))
    return record, manifest, _summary(store, run_id, record, manifest, now)


def list_runs(store: ArtifactStore, now: datetime.datetime | None = None) -> tuple[RunSummary, ...]:
    """Every run folder of ``store`` as a ``RunSummary``, newest start first (a run whose files cannot be read
    says so in its ``problem``)."""
    now = now or datetime.datetime.now(datetime.UTC)
    summaries = [_read_run(store, run_id, now)[2] for run_id in list_run_ids(store)]
    return tuple(sorted(summaries, key=_start_key, reverse=True))


def read_runs(store: ArtifactStore) -> RunsView:
    """The runs list of ``store`` (a missing store or runs folder gives an empty list)."""
    return RunsView(store.uri(), section("runs", lambda: list_runs(store)))


def _matrix(store: ArtifactStore, run_id: str) -> RunMatrix:
    stage_matrix = read_stage_matrix(store, run_id)
    logs = set(list_logs(store))
    rows = tuple(MatrixRow(seq, tuple(stage_matrix.cell(seq, stage) for stage in stage_matrix.stages), seq in logs)
                 for seq in stage_matrix.seq_ids)
    statuses: dict[str, int] = {}
    for cell in stage_matrix.cells.values():
        statuses[cell.status] = statuses.get(cell.status, 0) + 1
    return RunMatrix(stage_matrix.stages, rows, stage_matrix.problems, statuses)


def _tables(store: ArtifactStore, run_id: str) -> tuple[RunTableLink, ...]:
    return tuple(RunTableLink(name, f"/evaluation?run={run_id}#{name}",
                              artifact_id(join_relpath(run_dir(run_id), "tables", f"{name}.md")))
                 for name in list_run_tables(store, run_dir(run_id)))


class UnknownRun(LookupError):
    """The store has no run folder of that name (the message names it)."""


def read_run(store: ArtifactStore, run_id: str) -> RunView:
    """Run ``run_id`` of ``store``.

    Raises:
        UnknownRun: no such run folder (or a name that cannot be one).
    """
    try:
        relpath = run_dir(run_id)
    except ValueError as exc:
        raise UnknownRun(f"run {run_id!r} is not in the store ({exc})") from exc
    if not store.is_dir(relpath):
        raise UnknownRun(f"run {run_id!r} is not in the store {store.uri()}")
    record, manifest, summary = _read_run(store, run_id, datetime.datetime.now(datetime.UTC))
    live = summary.status == "running"
    return RunView(run_id, live, summary, record, manifest, section("stage matrix", lambda: _matrix(store, run_id)),
                   section("evaluation tables", lambda: _tables(store, run_id)))

