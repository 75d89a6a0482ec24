"""Per-sequence grounding outcomes kept across runs, so that a run evaluates only the sequences it has not seen.

The grounding benchmark's answers for one sequence depend only on that sequence (its log, its language scene, the
benchmark settings and the code), so each sequence's rows of the outcomes table are stored under a key of those::

    cache/grounding_outcomes/<seq_id>/<key>.parquet    the sequence's rows of the outcomes table
    cache/grounding_outcomes/<seq_id>/<key>.json       instead, when the log has no ground truth to evaluate against

One entry per sequence: writing a new key removes the sequence's older entries. A damaged entry is reported (file
named) and treated as absent, so the next evaluation recomputes and replaces it. Entries are derived data: deleting
``cache/`` loses nothing but time.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import pyarrow as pa

from storage.errors import CorruptArtifactError, SchemaError
from storage.store import ArtifactStore, join_relpath

logger = logging.getLogger(__name__)

CACHE_DIR = "cache/grounding_outcomes"


@dataclass(frozen=True)
class CachedOutcomes:
    """A sequence's stored entry: its outcome rows, or ``None`` with the reason it has none to evaluate."""

    rows: pa.Table | None
    no_ground_truth: bool = False


def _entry_dir(seq_id: str) -> str:
    return join_relpath(CACHE_DIR, seq_id)


def read_cached_outcomes(store: ArtifactStore, seq_id: str, key: str, schema: pa.Schema) -> CachedOutcomes | None:
    """The entry of ``seq_id`` under ``key``; ``None`` when there is none or it is damaged (a warning names it)."""
    base = _entry_dir(seq_id)
    rows_rel, none_rel = join_relpath(base, f"{key}.parquet"), join_relpath(base, f"{key}.json")
    try:
        if store.exists(rows_rel):
            return CachedOutcomes(store.read_table(rows_rel, schema))
        if store.exists(none_rel):
            marker = store.read_json(none_rel)
            if not isinstance(marker, dict) or marker.get("seq_id") != seq_id:
                raise CorruptArtifactError(f"{store.uri(none_rel)}: not the entry of {seq_id!r}")
            return CachedOutcomes(None, no_ground_truth=True)
    except (CorruptArtifactError, SchemaError) as exc:
        logger.warning("ignoring a damaged grounding cache entry (it is recomputed): %s", exc)
    return None


def write_cached_outcomes(store: ArtifactStore, seq_id: str, key: str, rows: pa.Table | None,
                          schema: pa.Schema) -> None:
    """Store ``seq_id``'s outcome rows (``None``: its log has no ground truth) under ``key``, atomically, and remove
    its entries under other keys."""
    base = _entry_dir(seq_id)
    if rows is None:
        store.write_json(join_relpath(base, f"{key}.json"), {"seq_id": seq_id, "reason": "no ground-truth masks"})
    else:
        store.write_table(join_relpath(base, f"{key}.parquet"), rows, schema)
    for name in store.listdir(base):
        if name.split(".", 1)[0] != key and not name.startswith("."):
            store.delete(join_relpath(base, name))
