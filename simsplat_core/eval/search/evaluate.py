"""Score the search against the synthetic world's ground truth, one row per query (RefAV's scenario-mining metrics).

    rows = evaluate_queries(items)          # items: prepared synthetic logs (``search.logs.SearchableLog``)
    summarise(rows)                          # means over queries, positives and negatives

Per (log, frame) predicted = a hit window covers the frame; per log predicted = any hit; truth from
``eval.search.truth`` (what the world scripted), never from the search code.
"""

from __future__ import annotations

import logging
import math
from typing import Any

import numpy as np

from simsplat_core.eval.search.metrics import log_ba, timestamp_ba
from simsplat_core.eval.search.queries import ALL_QUERIES, QueryCase
from simsplat_core.eval.search.truth import WorldAgents, query_truth
from simsplat_core.search.logs import SearchableLog, search_logs
from simsplat_core.search.windows import covered

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


__all__ = ["evaluate_queries", "summarise"]
