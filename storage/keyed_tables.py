"""A per-key Parquet cache: one file per item, ``cache/<name>/<item>.parquet``, stamped with the key of what it
was computed from.

The stamp (``cache_key`` in the file metadata) is the content key of the item's inputs and the digest of the code
that computed it. ``load`` returns the table only when the stamp matches; a missing entry is ``None`` silently, a
stale (other stamp) or unreadable (corrupt, wrong schema) entry is ``None`` with a warning naming the file, so the
caller recomputes and ``save``s it. Writes go through ``ArtifactStore.write_table`` (atomic).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import pyarrow as pa
import pyarrow.parquet as pq

from storage.errors import CorruptArtifactError, SchemaError
from storage.store import ArtifactStore, join_relpath

logger = logging.getLogger(__name__)

#: The file-metadata key holding an entry's stamp.
CACHE_KEY = "cache_key"


@dataclass(frozen=True)
class KeyedTables:
    """The cache ``name`` of one store, whose entries are tables of ``schema``."""

    store: ArtifactStore
    name: str
    schema: pa.Schema

    def relpath(self, item: str) -> str:
        """``cache/<name>/<item>.parquet``."""
        return join_relpath("cache", self.name, f"{item}.parquet")

    def load(self, item: str, key: str) -> pa.Table | None:
        """The cached table of ``item`` when its stamp is ``key``, else ``None`` (stale or corrupt: warned)."""
        rel = self.relpath(item)
        if not self.store.exists(rel):
            return None
        try:
            with self.store.open_input(rel) as f:
                stamp = (pq.read_schema(f).metadata or {}).get(CACHE_KEY.encode(), b"").decode()
            if stamp != key:
                logger.warning("%s: stale cache entry (key %s, wanted %s); recomputing", self.store.uri(rel),
                               stamp or "missing", key)
                return None
            return self.store.read_table(rel, self.schema)
        except (pa.ArrowException, OSError, CorruptArtifactError, SchemaError) as exc:
            logger.warning("%s: unreadable cache entry (%s); recomputing", self.store.uri(rel), exc)
            return None

    def save(self, item: str, key: str, table: pa.Table) -> None:
        """Write ``table`` as ``item``'s entry stamped ``key`` (atomic; replaces an older entry)."""
        stamped = self.schema.with_metadata({**(self.schema.metadata or {}), CACHE_KEY.encode(): key.encode()})
        self.store.write_table(self.relpath(item), table, stamped)
