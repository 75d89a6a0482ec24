"""Benchmark: how fast the dashboard answers, page by page, on a real store.

    .venv/bin/python bench/bench_dashboard.py --store artifacts/demo [--pages 200] [--repeats 3]
        [--extra "/sequences/synth-000000?q=the+red+car+turning+right"] [--out bench/results] [--name dashboard]

Crawls the app in process (FastAPI's test client, no network) from ``/`` (and each ``--extra`` URL, e.g. a query
or a search), following every internal link of every
page (pages, their ``/api`` JSON twins and the pictures they reference by artifact id), at most ``--pages`` pages.
Each URL is fetched ``--repeats`` times; the first fetch (cold: listings, EXR decoding, renders made on request)
and the median of the others (warm) are reported per route pattern (``/scenarios/{...}``), with the largest
response. Every fetch must answer below 400; a failing one is reported and the script exits 1. The store is
hashed before and after: the dashboard must not change it. Writes ``<out>/<name>.json``.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import logging
import os
import platform
import re
import statistics
import sys
import time
from collections import defaultdict
from pathlib import Path
from typing import Any

from fastapi.testclient import TestClient

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from flows.dashboard.app import create_app  # noqa: E402
from flows.dashboard.settings import DashboardSettings  # noqa: E402

logger = logging.getLogger("bench_dashboard")

_LINK = re.compile(r"""(?:href|src)="(/[^"#]*)""")
_SKIP = ("/static/",)


def _pattern(url: str) -> str:
    """``/scenarios/run/seq/edit?x=1`` -> ``/scenarios/{}/{}/{}`` (first path part kept, the rest anonymised)."""
    path = url.split("?", 1)[0]
    parts = [p for p in path.split("/") if p]
    if not parts:
        return "/"
    head = parts[0] if parts[0] != "api" else "api/" + (parts[1] if len(parts) > 1 else "")
    rest = len(parts) - len(head.split("/"))
    return "/" + head + "/{}" * rest + ("?" if "?" in url else "")


def _store_digest(root: Path) -> str:
    digest = hashlib.sha256()
    for path in sorted(p for p in root.rglob("*") if p.is_file()):
        digest.update(str(path.relative_to(root)).encode())
        digest.update(str(path.stat().st_size).encode())
        digest.update(str(path.stat().st_mtime_ns).encode())
    return digest.hexdigest()


def crawl(client: TestClient, max_pages: int, repeats: int, extra: list[str]
          ) -> tuple[dict[str, dict[str, Any]], list[str]]:
    """Fetch every URL reachable from ``/`` and ``extra``; returns per-pattern timings and the failures."""
    seen: set[str] = set()
    queue = ["/", *extra]
    timings: dict[str, list[tuple[float, float, int]]] = defaultdict(list)
    failures: list[str] = []
    pages = 0
    while queue and pages < max_pages:
        url = queue.pop(0)
        if url in seen or url.startswith(_SKIP):
            continue
        seen.add(url)
        times = []
        response = None
        for _ in range(repeats):
            start = time.perf_counter()
            response = client.get(url)
            times.append(time.perf_counter() - start)
        assert response is not None
        if response.status_code >= 400:
            failures.append(f"{url}: HTTP {response.status_code}")
            continue
        warm = statistics.median(times[1:]) if len(times) > 1 else times[0]
        timings[_pattern(url)].append((times[0], warm, len(response.content)))
        if response.headers.get("content-type", "").startswith("text/html"):
            pages += 1
            for link in _LINK.findall(response.text):
                if link not in seen:
                    queue.append(link)
                    if not link.startswith(("/files/", "/api", *_SKIP)) and link != "/":
                        queue.append("/api" + link)
    summary = {
        pattern: {"urls": len(rows), "cold_ms_median": round(1e3 * statistics.median(r[0] for r in rows), 1),
                  "cold_ms_max": round(1e3 * max(r[0] for r in rows), 1),
                  "warm_ms_median": round(1e3 * statistics.median(r[1] for r in rows), 1),
                  "max_bytes": max(r[2] for r in rows)}
        for pattern, rows in sorted(timings.items())}
    return summary, failures


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--store", required=True)
    parser.add_argument("--pages", type=int, default=200)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", default="bench/results")
    parser.add_argument("--name", default="dashboard")
    parser.add_argument("--extra", action="append", default=[],
                        help="More URLs to start from, e.g. a query: /sequences/SEQ?q=the+red+car (repeatable).")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    root = Path(args.store)
    before = _store_digest(root)
    client = TestClient(create_app(DashboardSettings(str(root))))
    started = time.perf_counter()
    summary, failures = crawl(client, args.pages, args.repeats, args.extra)
    wall = time.perf_counter() - started
    unchanged = _store_digest(root) == before
    width = max((len(p) for p in summary), default=10)
    logger.info("%-*s %5s %10s %10s %10s %10s", width, "route", "urls", "cold med", "cold max", "warm med", "bytes")
    for pattern, row in summary.items():
        logger.info("%-*s %5d %8.1f ms %8.1f ms %8.1f ms %10d", width, pattern, row["urls"], row["cold_ms_median"],
                    row["cold_ms_max"], row["warm_ms_median"], row["max_bytes"])
    logger.info("crawled in %.1f s; store unchanged: %s; failures: %d", wall, unchanged, len(failures))
    for failure in failures:
        logger.error("%s", failure)
    result = {"store": str(root), "machine": {"cpus": os.cpu_count(), "platform": platform.platform()},
              "repeats": args.repeats, "wall_s": round(wall, 2), "store_unchanged": unchanged,
              "failures": failures, "routes": summary}
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{args.name}.json").write_text(json.dumps(result, indent=2) + "\n")
    return 1 if failures or not unchanged else 0


if __name__ == "__main__":
    raise SystemExit(main())
