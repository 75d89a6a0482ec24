"""Score the search against the synthetic world's ground truth, one row per query (RefAV's scenario-mining metrics).

    rows = evaluate_queries(items)          # items: prepared synthetic logs (``search.logs.SearchableLog``)
    summarise(rows)                          # means over queries, positives and negatives
    table = SEARCH_SPEC.table(rows)          # the ``search`` table; search_markdown(table, ...) its .md

Per (log, frame) predicted = a hit window covers the frame; per log predicted = any hit; truth from
``eval.search.truth`` (what the world scripted), never from the search code.
"""

from __future__ import annotations

import logging
import math
from typing import Any

import numpy as np
import pyarrow as pa

from simsplat_core.eval.search.metrics import log_ba, timestamp_ba
from simsplat_core.eval.search.queries import ALL_QUERIES, QueryCase
from simsplat_core.eval.search.truth import WorldAgents, query_truth
from simsplat_core.eval.table_headlines import Headline
from simsplat_core.eval.table_spec import Column, TableSpec
from simsplat_core.search.logs import SearchableLog, search_logs
from simsplat_core.search.windows import covered

logger = logging.getLogger(__name__)

#: ``tables/search``: one row per query of the query set; the balanced accuracies are null where undefined.
SEARCH_SPEC = TableSpec("search", "Search: RefAV balanced accuracies", "query", (
    Column("query", pa.string(), "the query text"),
    Column("negative", pa.bool_(), "holds nowhere by the world's ground truth"),
    Column("timestamp_ba", pa.float64(), "balanced accuracy over (log, frame): a hit window covers the frame",
           "share", nullable=True),
    Column("log_ba", pa.float64(), "balanced accuracy over logs: any hit", "share", nullable=True),
    Column("hits", pa.int64(), "hits over all logs", "count"),
    Column("logs_true", pa.int64(), "logs containing the scenario", "count"),
    Column("logs_hit", pa.int64(), "logs with a hit", "count"),
    Column("seconds", pa.float64(), "wall time of the search over all logs", "s"),
), keys=("query",), headlines=(Headline("timestamp_ba", reduce="mean"), Headline("log_ba", reduce="mean")))


def _nullable(value: float) -> float | None:
    return None if math.isnan(value) else round(value, 6)


def evaluate_queries(items: list[SearchableLog], queries: tuple[QueryCase, ...] = ALL_QUERIES) -> list[dict[str, Any]]:
    """One row per query (:data:`SEARCH_SPEC` columns) over prepared synthetic logs."""
    worlds = [WorldAgents.from_log(i.log) for i in items]
    rows = []
    for case in queries:
        found = search_logs(items, case.text)
        truth = [query_truth(w, case.truth) for w in worlds]
        # results come in the order of ``items`` (two stores may both hold a synth-000000)
        predicted = [covered([h.window for h in r.hits], i.log.num_frames) for i, r in zip(items, found.results)]
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


def search_markdown(table: pa.Table, summary: dict[str, Any], logs: int, stores: int) -> str:
    """The ``search`` table's Markdown: a heading, what was searched (``logs`` logs from ``stores`` stores), the
    table and the means of ``summary`` (:func:`summarise`)."""
    return SEARCH_SPEC.render_markdown(
        table,
        before=f"# {SEARCH_SPEC.title}\n\n{logs} logs from {stores} store(s), "
               f"{table.num_rows} queries ({summary['negatives']} hold nowhere).\n\n",
        after=f"\n\nMean timestamp BA {summary['timestamp_ba']}, log BA {summary['log_ba']} "
              f"(positives: {summary['timestamp_ba_positives']}, {summary['log_ba_positives']}); "
              f"negatives without a hit: {summary['negatives_without_hits']}/{summary['negatives']}.\n")


__all__ = ["SEARCH_SPEC", "evaluate_queries", "search_markdown", "summarise"]
