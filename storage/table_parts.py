"""A table that many writers append to without a lock: one immutable Parquet part per append.

Read-modify-write of one file loses rows when two processes append at once and nothing serialises them (an object
store has no lock: between the Ray workers of a cluster the last writer wins). Here an append only ever adds a new
file, so concurrent appends cannot lose each other's rows::

    <dir>/<legacy name>.parquet                 rows written before parts existed (read first, never rewritten)
    <dir>/<name>.parts/<ns>-<id>.parquet        one part per append (<ns>: the writer's clock in ns, zero-padded)
    <dir>/<name>.parts/<ns>-compact-<id>.parquet  a compacted part: the rows of the parts it replaces, in order

Reading concatenates the legacy file and the parts in name order (the writers' clocks: append order on one
machine). :meth:`PartedTable.compact` folds the parts into one: it writes the compacted part (naming the parts it
replaces in its Parquet metadata), then deletes exactly those parts. A reader that lists the folder in between sees
both and skips the replaced ones; a reader whose listed part was deleted meanwhile lists again. A part appended
during a compaction is not among those it read, so it stays. Compaction is meant for one writer at a time (the flow
that owns the table, once its tasks are done): two concurrent compactions of one table would store rows twice.
"""

from __future__ import annotations

import json
import logging
import time
import uuid
from dataclasses import dataclass

import pyarrow as pa
import pyarrow.parquet as pq

from storage.errors import CorruptArtifactError
from storage.store import TMP_TAG, ArtifactStore, join_relpath

logger = logging.getLogger(__name__)

PARTS_SUFFIX = ".parts"
REPLACES_KEY = b"simsplat.parts.replaces"
COMPACTED_TAG = "compact-"  # not hexadecimal: an appended part's name never holds it
_READ_ATTEMPTS = 5


def _new_part_name(ns_prefix: str | None = None, compacted: bool = False) -> str:
    ns = ns_prefix if ns_prefix is not None else f"{time.time_ns():020d}"
    return f"{ns}-{COMPACTED_TAG if compacted else ''}{uuid.uuid4().hex[:16]}.parquet"


def _is_part(name: str) -> bool:
    return name.endswith(".parquet") and TMP_TAG not in name and not name.startswith(".")


def _is_compacted(name: str) -> bool:
    return f"-{COMPACTED_TAG}" in name


@dataclass(frozen=True)
class PartedTable:
    """A Parquet table stored as parts under ``<folder>/<name>.parts/`` (plus an optional legacy single file
    ``<folder>/<name>.parquet``).

    Attributes:
        store: the artifact store.
        folder: the folder holding the table, relative to the store root.
        name: the table's file name without ``.parquet``.
        schema: every part's schema.
    """

    store: ArtifactStore
    folder: str
    name: str
    schema: pa.Schema

    @property
    def legacy_relpath(self) -> str:
        """``<folder>/<name>.parquet``: the single-file layout, still read."""
        return join_relpath(self.folder, f"{self.name}.parquet")

    @property
    def parts_relpath(self) -> str:
        """``<folder>/<name>.parts``."""
        return join_relpath(self.folder, f"{self.name}{PARTS_SUFFIX}")

    def exists(self) -> bool:
        """Whether the table has a legacy file or at least one part."""
        return self.store.exists(self.legacy_relpath) or bool(self.part_names())

    def part_names(self) -> list[str]:
        """The part files' names, in append order (temporaries of writes in progress left out)."""
        return [n for n in self.store.listdir(self.parts_relpath) if _is_part(n)]

    def append(self, table: pa.Table) -> str:
        """Write ``table`` (validated against the schema) as a new part; returns the part's path."""
        rel = join_relpath(self.parts_relpath, _new_part_name())
        self.store.write_table(rel, table, self.schema)
        return rel

    def read(self) -> pa.Table:
        """Every row: the legacy file's, then each live part's in name order (an empty table when there is none).

        Raises:
            CorruptArtifactError, SchemaError: naming the damaged part.
        """
        for attempt in range(_READ_ATTEMPTS):
            try:
                return self._read_once()
            except FileNotFoundError:  # a compaction deleted a listed part: list again
                if attempt == _READ_ATTEMPTS - 1:
                    raise
                logger.debug("%s changed while being read; reading again", self.store.uri(self.parts_relpath))
        raise AssertionError("unreachable")

    def _read_once(self) -> pa.Table:
        tables = []
        if self.store.exists(self.legacy_relpath):
            tables.append(self.store.read_table(self.legacy_relpath, self.schema))
        names = self.part_names()
        replaced = set().union(*(self._replaced_by(n) for n in names if _is_compacted(n)))
        for name in names:
            if name not in replaced:
                tables.append(self.store.read_table(join_relpath(self.parts_relpath, name), self.schema))
        if not tables:
            return self.schema.empty_table()
        return pa.concat_tables(tables)

    def _replaced_by(self, compacted_name: str) -> set[str]:
        rel = join_relpath(self.parts_relpath, compacted_name)
        with self.store.open_input(rel) as f:
            try:
                metadata = pq.read_metadata(f).metadata or {}
            except (pa.ArrowException, OSError) as exc:
                raise CorruptArtifactError(f"{self.store.uri(rel)}: not a readable Parquet file ({exc})") from exc
        if REPLACES_KEY not in metadata:
            raise CorruptArtifactError(f"{self.store.uri(rel)}: a compacted part without its "
                                       f"{REPLACES_KEY.decode()!r} metadata")
        return set(json.loads(metadata[REPLACES_KEY]))

    def compact(self, min_parts: int = 2) -> int:
        """Fold the live parts into one when there are at least ``min_parts``; returns how many were folded (0: none).

        Writes the compacted part first, then deletes the parts it holds: an interruption in between leaves both,
        which readers resolve; a part appended meanwhile is kept.
        """
        names = self.part_names()
        replaced = set().union(*(self._replaced_by(n) for n in names if _is_compacted(n)))
        for stale in sorted(replaced & set(names)):  # left by an interrupted compaction
            self.store.delete(join_relpath(self.parts_relpath, stale))
        live = [n for n in names if n not in replaced]
        if len(live) < min_parts:
            return 0
        rows = pa.concat_tables(self.store.read_table(join_relpath(self.parts_relpath, n), self.schema) for n in live)
        metadata = {**(self.schema.metadata or {}), REPLACES_KEY: json.dumps(live).encode()}
        target = join_relpath(self.parts_relpath, _new_part_name(live[0].split("-", 1)[0], compacted=True))
        self.store.write_table(target, rows, self.schema.with_metadata(metadata))
        for name in live:
            self.store.delete(join_relpath(self.parts_relpath, name))
        logger.info("%s: %d parts (%d rows) compacted into one", self.store.uri(self.parts_relpath), len(live),
                    rows.num_rows)
        return len(live)
