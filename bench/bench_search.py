"""Search latency over stores: load (read logs, per-frame facts) once, then every query of the query set.

    PYTHONPATH=. python bench/bench_search.py /tmp/s15/store4 /tmp/s17/store_61 ...

Prints load seconds, per-query latency (median, max) over all logs, and the per-log cost of the per-frame facts.
"""

from __future__ import annotations

import logging
import statistics
import sys
import time

from simsplat_core.eval.search.queries import ALL_QUERIES
from simsplat_core.search.logs import search_logs
from tasks.search import load_store

logger = logging.getLogger("bench_search")


def main(stores: list[str]) -> None:
    t0 = time.perf_counter()
    items = [item for root in stores for item in load_store(root)]
    load_s = time.perf_counter() - t0
    times = []
    for case in ALL_QUERIES:
        t = time.perf_counter()
        search_logs(items, case.text)
        times.append(time.perf_counter() - t)
    logger.info("%d logs: load %.2f s (%.3f s/log); %d queries: median %.4f s, max %.4f s over all logs",
                len(items), load_s, load_s / len(items), len(times), statistics.median(times), max(times))


if __name__ == "__main__":
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    main(sys.argv[1:] or ["/tmp/s15/store4"])
