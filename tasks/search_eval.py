"""The search evaluation: RefAV's scenario-mining metrics of ``simsplat search`` on synthetic logs.

Over every log of the given stores (several stores: two logs a store are too few for a log-level figure), each
query of ``simsplat_core.eval.search.queries.ALL_QUERIES`` is answered and scored by
``simsplat_core.eval.search.evaluate`` (no pictures) against the ground truth that the synthetic world
scripted (``simsplat_core.eval.search.truth``): per (log, frame) predicted = a hit window covers the frame; per log
predicted = any hit. Writes ``OUT/tables/search.parquet`` (``simsplat_core.eval.search.evaluate.SEARCH_SPEC``) and
``search.md``; returns the summary (means over queries).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Sequence
from typing import Any

from simsplat_core.eval.search.evaluate import SEARCH_SPEC, evaluate_queries, search_markdown, summarise
from simsplat_core.eval.search.queries import ALL_QUERIES, QueryCase
from storage import ArtifactStore
from storage.runs import RunTable, run_table
from tasks.search import load_store

logger = logging.getLogger(__name__)


def search_run_table(store_root: str, seq_ids: Sequence[str]) -> RunTable | None:
    """The ``search`` table of ``seq_ids`` in one store, for ``tasks.mining_eval``'s ``search_table`` hook
    (``None`` without sequences)."""
    if not seq_ids:
        return None
    items = load_store(store_root, list(seq_ids))
    rows = evaluate_queries(items)
    table = SEARCH_SPEC.table(rows)
    return run_table(SEARCH_SPEC, table, search_markdown(table, summarise(rows), len(items), 1))


def evaluate_search(stores: list[str], out_root: str, *, queries: tuple[QueryCase, ...] = ALL_QUERIES,
                    out_relpath: str = "tables") -> dict[str, Any]:
    """Evaluate the search over every log of ``stores``; write ``OUT/<out_relpath>/search.{parquet,md}``.

    Returns:
        ``summarise`` of the rows plus ``logs`` (how many), ``load_seconds`` and ``table`` (the Parquet URI).

    Raises:
        FileNotFoundError: a store holds no logs.
    """
    t0 = time.perf_counter()
    items = [item for root in stores for item in load_store(root)]
    load_s = time.perf_counter() - t0
    rows = evaluate_queries(items, queries)
    table = SEARCH_SPEC.table(rows)
    out = ArtifactStore(out_root)
    out.write_table(f"{out_relpath}/search.parquet", table, SEARCH_SPEC.schema)
    summary = summarise(rows)
    out.write_bytes(f"{out_relpath}/search.md", search_markdown(table, summary, len(items), len(stores)).encode())
    logger.info("search evaluation: %s", summary)
    return {**summary, "logs": len(items), "load_seconds": round(load_s, 3),
            "table": out.uri(f"{out_relpath}/search.parquet")}
