"""The search evaluation (issue 12): RefAV's scenario-mining metrics of ``simsplat search`` on synthetic logs.

Over every log of the given stores (several stores: two logs a store are too few for a log-level figure), each
query of ``simsplat_core.eval.search.queries.ALL_QUERIES`` is answered by the search (``tasks.search.search_logs``;
no pictures) and compared with the ground truth that the synthetic world scripted
(``simsplat_core.eval.search.truth``): per (log, frame) predicted = a hit window covers the frame; per log
predicted = any hit. Writes ``OUT/tables/search.parquet`` (``storage.schemas.search_table_schema``) and
``search.md``; returns the summary (means over queries).
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Sequence
from typing import Any

import numpy as np
import pyarrow as pa

from simsplat_core.eval.search.metrics import log_ba, timestamp_ba
from simsplat_core.eval.search.queries import ALL_QUERIES, QueryCase
from simsplat_core.eval.search.truth import WorldAgents, query_truth
from simsplat_core.eval.tables import markdown
from simsplat_core.search.windows import covered
from storage import ArtifactStore
from storage.runs import RunTable
from storage.schemas import search_table_schema
from tasks.search import SearchableLog, load_store, search_logs

logger = logging.getLogger(__name__)


def _nullable(value: float) -> float | None:
    return None if math.isnan(value) else round(value, 6)


def evaluate_queries(items: list[SearchableLog], queries: tuple[QueryCase, ...] = ALL_QUERIES) -> list[dict[str, Any]]:
    """One row per query (``search_table_schema`` columns) over prepared synthetic logs."""
    worlds = [WorldAgents.from_log(i.log) for i in items]
    rows = []
    for case in queries:
        found = search_logs(items, case.text)
        truth = [query_truth(w, case.truth) for w in worlds]
        by_seq = {r.seq_id: r for r in found.results}
        predicted = [covered([h.window for h in by_seq[i.log.seq_id].hits], i.log.num_frames) for i in items]
        rows.append({
            "query": case.text,
            "negative": not any(t.any() for t in truth),
            "timestamp_ba": _nullable(timestamp_ba(truth, predicted)),
            "log_ba": _nullable(log_ba(truth, predicted)),
            "hits": len(found.hits),
            "logs_true": int(sum(t.any() for t in truth)),
            "logs_hit": int(sum(p.any() for p in predicted)),
            "seconds": round(found.seconds, 6),
        })
        if case.negative and not rows[-1]["negative"]:
            logger.warning("query %r meant as a negative holds in %d logs", case.text, rows[-1]["logs_true"])
    return rows


def summarise(rows: list[dict[str, Any]]) -> dict[str, float | int]:
    """Means over queries (all / positives / negatives), hits and seconds."""
    def mean(key: str, pick: list[dict[str, Any]]) -> float:
        vals = [r[key] for r in pick if r[key] is not None]
        return round(float(np.mean(vals)), 4) if vals else float("nan")

    pos = [r for r in rows if not r["negative"]]
    neg = [r for r in rows if r["negative"]]
    return {"queries": len(rows), "negatives": len(neg), "timestamp_ba": mean("timestamp_ba", rows),
            "log_ba": mean("log_ba", rows), "timestamp_ba_positives": mean("timestamp_ba", pos),
            "log_ba_positives": mean("log_ba", pos), "negatives_without_hits": sum(r["hits"] == 0 for r in neg),
            "seconds_mean": mean("seconds", rows)}


def _search_markdown(table: pa.Table, summary: dict[str, Any], logs: int, stores: int) -> str:
    return (f"# Search: RefAV balanced accuracies\n\n{logs} logs from {stores} store(s), "
            f"{table.num_rows} queries ({summary['negatives']} hold nowhere).\n\n{markdown(table)}\n\n"
            f"Mean timestamp BA {summary['timestamp_ba']}, log BA {summary['log_ba']} "
            f"(positives: {summary['timestamp_ba_positives']}, {summary['log_ba_positives']}); "
            f"negatives without a hit: {summary['negatives_without_hits']}/{summary['negatives']}.\n")


def search_run_table(store_root: str, seq_ids: Sequence[str]) -> RunTable | None:
    """The ``search`` table of ``seq_ids`` in one store, for ``tasks.mining_eval``'s ``search_table`` hook
    (``None`` without sequences)."""
    if not seq_ids:
        return None
    items = load_store(store_root, list(seq_ids))
    rows = evaluate_queries(items)
    schema = search_table_schema()
    table = pa.Table.from_pylist(rows, schema=schema)
    return RunTable(table, schema, _search_markdown(table, summarise(rows), len(items), 1))


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
    schema = search_table_schema()
    table = pa.Table.from_pylist(rows, schema=schema)
    out = ArtifactStore(out_root)
    out.write_table(f"{out_relpath}/search.parquet", table, schema)
    summary = summarise(rows)
    out.write_bytes(f"{out_relpath}/search.md", _search_markdown(table, summary, len(items), len(stores)).encode())
    logger.info("search evaluation: %s", summary)
    return {**summary, "logs": len(items), "load_seconds": round(load_s, 3),
            "table": out.uri(f"{out_relpath}/search.parquet")}
