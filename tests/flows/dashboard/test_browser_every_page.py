"""Every page the dashboard links to, crawled in a real browser from the overview: each loads without a console
error or a failed request (its pictures included), its JSON twin answers, and the store is not changed by any of
it (the dashboard is read-only)."""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Any

import httpx

from tests.flows.dashboard.conftest import ServedDashboard
from tests.flows.dashboard.store_fixture import DashboardStore

#: At most this many pages are visited (the test store has fewer).
MAX_PAGES = 60
_NOT_PAGES = ("/files/", "/static/", "/api")


def _store_state(root: str) -> str:
    digest = hashlib.sha256()
    for path in sorted(p for p in Path(root).rglob("*") if p.is_file()):
        stat = path.stat()
        digest.update(f"{path.relative_to(root)}:{stat.st_size}:{stat.st_mtime_ns}".encode())
    return digest.hexdigest()


def _internal_links(page: Any) -> list[str]:
    hrefs = page.eval_on_selector_all("a[href]", "els => els.map(e => e.getAttribute('href'))")
    return [h.split("#", 1)[0] for h in hrefs
            if h.startswith("/") and not h.startswith(_NOT_PAGES) and not h.endswith(".rrd")]


def test_every_linked_page_loads_cleanly_and_changes_nothing(page: Any, dashboard: ServedDashboard,
                                                              dashboard_store: DashboardStore) -> None:
    before = _store_state(dashboard_store.root)
    queue, seen = ["/"], set()
    while queue and len(seen) < MAX_PAGES:
        path = queue.pop(0)
        if path in seen or not path:
            continue
        seen.add(path)
        response = page.goto(dashboard.url + path, wait_until="load")
        assert response is not None and response.ok, f"{path}: HTTP {response.status if response else '?'}"
        assert page.locator("h1").count() == 1, f"{path}: no page title"
        broken = page.eval_on_selector_all("img", "els => els.filter(e => e.complete && e.naturalWidth === 0)"
                                                  ".map(e => e.getAttribute('src'))")
        assert not broken, f"{path}: pictures that did not load: {broken}"
        twin = httpx.get(dashboard.url + "/api" + (path if path != "/" else ""), timeout=60)
        assert twin.status_code == 200 and twin.headers["content-type"].startswith("application/json"), path
        queue.extend(link for link in _internal_links(page) if link not in seen)
    groups = {p.split("/")[1] if p != "/" else "" for p in seen}
    assert {"", "runs", "sequences", "mining", "scenarios"} <= groups, sorted(seen)
    assert _store_state(dashboard_store.root) == before
