"""A run's evaluation outputs: ``tables/<name>.parquet`` + ``tables/<name>.md`` and ``manifest.json``.

    runs/<run_id>/manifest.json           what the run evaluated (inputs, counts, timings)
    runs/<run_id>/tables/<name>.parquet   one table (schema from ``storage.schemas``)
    runs/<run_id>/tables/<name>.md        the same table as Markdown, for people

``run_dir`` names the place inside a store; ``simsplat eval ... --out DIR`` uses ``DIR`` itself as the
run directory (relpath ``""``). Every file is written atomically.
"""

from __future__ import annotations

import datetime
import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import pyarrow as pa

from storage.schemas import motion_outcomes_schema, motion_table_schema
from storage.store import ArtifactStore, join_relpath

RUNS_DIR = "runs"
_RUN_ID = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,127}$")


@dataclass(frozen=True)
class RunTable:
    """One evaluation table: ``table`` validated against ``schema``, and its Markdown rendering."""

    table: pa.Table
    schema: pa.Schema
    markdown: str


def new_run_id(prefix: str = "run") -> str:
    """``<prefix>-YYYYmmddTHHMMSSffffffZ`` (UTC; sorts by time)."""
    return f"{prefix}-{datetime.datetime.now(datetime.UTC).strftime('%Y%m%dT%H%M%S%fZ')}"


def run_dir(run_id: str) -> str:
    """``runs/<run_id>`` (raises ``ValueError`` naming an unsafe id)."""
    if not _RUN_ID.match(run_id):
        raise ValueError(f"run id {run_id!r} must be 1-128 characters of letters, digits, '.', '_' or '-'")
    return join_relpath(RUNS_DIR, run_id)


def write_run_tables(store: ArtifactStore, relpath: str, tables: Mapping[str, RunTable],
                     manifest: Mapping[str, Any] | None = None) -> dict[str, str]:
    """Write each table as ``<relpath>/tables/<name>.parquet`` and ``.md``, then ``manifest.json`` (which
    lists them); returns ``name -> Parquet URI``."""
    uris = {}
    for name, item in tables.items():
        parquet = join_relpath(relpath, "tables", f"{name}.parquet")
        store.write_table(parquet, item.table, item.schema)
        store.write_bytes(join_relpath(relpath, "tables", f"{name}.md"),
                          (item.markdown.rstrip("\n") + "\n").encode("utf-8"))
        uris[name] = store.uri(parquet)
    body = {"written_at": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
            "tables": sorted(tables), **dict(manifest or {})}
    store.write_json(join_relpath(relpath, "manifest.json"), body)
    return uris


def write_motion_table(store: ArtifactStore, relpath: str, table: pa.Table, markdown: str,
                       manifest: Mapping[str, Any] | None = None,
                       outcomes: tuple[pa.Table, str] | None = None) -> str:
    """Write the ``motion`` table as ``<relpath>/tables/motion.{parquet,md}`` (validated, atomic), the
    per-case ``outcomes`` (table, Markdown) as ``motion_outcomes.{parquet,md}`` when given, and the manifest;
    returns the ``motion`` Parquet URI."""
    tables = {"motion": RunTable(table, motion_table_schema(), markdown)}
    if outcomes is not None:
        tables["motion_outcomes"] = RunTable(outcomes[0], motion_outcomes_schema(), outcomes[1])
    uris = write_run_tables(store, relpath, tables, manifest)
    return uris["motion"]


def read_motion_table(store: ArtifactStore, relpath: str) -> pa.Table:
    """``<relpath>/tables/motion.parquet``, validated (``SchemaError`` names the file and the column)."""
    return store.read_table(join_relpath(relpath, "tables", "motion.parquet"), motion_table_schema())


def read_motion_outcomes(store: ArtifactStore, relpath: str) -> pa.Table:
    """``<relpath>/tables/motion_outcomes.parquet``, validated."""
    return store.read_table(join_relpath(relpath, "tables", "motion_outcomes.parquet"), motion_outcomes_schema())
