"""A run's evaluation outputs: ``tables/<name>.parquet`` + ``tables/<name>.md`` and ``manifest.json``.

    runs/<run_id>/manifest.json           what the run evaluated (inputs, counts, timings)
    runs/<run_id>/tables/<name>.parquet   one table (schema from its declaration, ``DeclaredTable``)
    runs/<run_id>/tables/<name>.md        the same table as Markdown, for people

``run_dir`` names the place inside a store; ``simsplat eval ... --out DIR`` uses ``DIR`` itself as the
run directory (relpath ``""``). Every file is written atomically.

Any declared table (an object with ``name``, ``schema`` and ``render_markdown(table)``: the evaluation tables'
``simsplat_core.eval.table_spec.TableSpec``) is written and read generically:

    write_run_tables(store, rel, {spec.name: run_table(spec, table)}, manifest)
    table = read_run_table(store, rel, spec)      # validated; SchemaError names the file and the column
"""

from __future__ import annotations

import datetime
import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Protocol

import pyarrow as pa

from storage.store import ArtifactStore, join_relpath

RUNS_DIR = "runs"
_RUN_ID = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,127}$")


class DeclaredTable(Protocol):
    """What storage needs of a table declaration: its name (file stem), its schema (with ``schema_name`` and
    ``schema_version`` metadata) and its Markdown."""

    @property
    def name(self) -> str: ...

    @property
    def schema(self) -> pa.Schema: ...

    def render_markdown(self, table: pa.Table) -> str: ...


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
        parquet = run_table_relpath(relpath, name)
        store.write_table(parquet, item.table, item.schema)
        store.write_bytes(join_relpath(relpath, "tables", f"{name}.md"),
                          (item.markdown.rstrip("\n") + "\n").encode("utf-8"))
        uris[name] = store.uri(parquet)
    body = {"written_at": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
            "tables": sorted(tables), **dict(manifest or {})}
    store.write_json(join_relpath(relpath, "manifest.json"), body)
    return uris


def run_table(spec: DeclaredTable, table: pa.Table, markdown: str | None = None) -> RunTable:
    """``table`` of the declared ``spec`` with its Markdown (``spec.render_markdown(table)`` unless given)."""
    return RunTable(table, spec.schema, spec.render_markdown(table) if markdown is None else markdown)


def run_table_relpath(relpath: str, name: str) -> str:
    """``<relpath>/tables/<name>.parquet``."""
    return join_relpath(relpath, "tables", f"{name}.parquet")


def read_run_table(store: ArtifactStore, relpath: str, spec: DeclaredTable) -> pa.Table:
    """``<relpath>/tables/<spec.name>.parquet``, validated against the declaration (``SchemaError`` names the file
    and the column; ``FileNotFoundError`` when absent)."""
    return store.read_table(run_table_relpath(relpath, spec.name), spec.schema)


def list_run_tables(store: ArtifactStore, relpath: str) -> list[str]:
    """Names of the tables written under ``<relpath>/tables`` (sorted)."""
    base = join_relpath(relpath, "tables")
    if not store.is_dir(base):
        return []
    return sorted(name[: -len(".parquet")] for name in store.listdir(base) if name.endswith(".parquet"))
