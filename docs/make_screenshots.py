"""Screenshots of the dashboard's main pages for the README, taken in headless Chromium from a real store.

    .venv/bin/python docs/make_screenshots.py --store artifacts/demo [--out docs/images] [--query "the red car"]

Serves the dashboard of ``--store`` on a free loopback port, opens the newest run with a run record, the first
sequence (with ``--query`` answered), a search, the newest mining run, one of its accepted scenario cards
(``--scenario``) and the evaluation page, and saves ``dashboard-<page>.png`` in ``--out`` (1280 px wide, the top
``--height`` pixels; more of the scenario card and the sequence page).
"""

from __future__ import annotations

import argparse
import logging
import shutil
import socket
import sys
import threading
import time
from pathlib import Path
from urllib.parse import quote

import httpx
import uvicorn

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from flows.dashboard.app import create_app  # noqa: E402
from flows.dashboard.settings import DashboardSettings  # noqa: E402

logger = logging.getLogger("make_screenshots")

#: Pages shown taller than ``--height`` (the scenario card down to its bird's-eye animation), px.
TALL = {"scenario": 1900, "sequence": 1300}


def _serve(store: str) -> tuple[str, uvicorn.Server]:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    server = uvicorn.Server(uvicorn.Config(create_app(DashboardSettings(store, port=port)), host="127.0.0.1",
                                           port=port, log_level="warning"))
    threading.Thread(target=server.run, daemon=True).start()
    while not server.started:
        time.sleep(0.05)
    return f"http://127.0.0.1:{port}", server


def _value(answer: dict, key: str) -> list | dict:
    """A section's value in a JSON twin (``[]`` when it failed)."""
    return (answer.get(key) or {}).get("value") or []


def _pages(url: str, query: str, scenario: int) -> dict[str, str]:
    """Page name -> path, found through the JSON twins."""
    def get(path: str) -> dict:
        return httpx.get(url + "/api" + path, timeout=120).json()

    pages = {"overview": "/"}
    recorded = [r for r in _value(get("/runs"), "runs") if r.get("status") not in (None, "tables only")]
    if recorded:
        pages["run"] = f"/runs/{recorded[0]['run_id']}"
    logs = _value(get("/sequences"), "rows")
    if logs:
        pages["sequence"] = f"/sequences/{logs[0]['value']['seq_id']}?q={quote(query)}"
    pages["search"] = f"/search?q={quote('a pedestrian crossing in front of us')}"
    mined = [r["value"] for r in _value(get("/mining"), "runs") if r.get("value") and r["value"].get("accepted")]
    if mined:
        run_id = mined[0]["run_id"]
        pages["mining"] = f"/mining/{run_id}"
        content = _value(get(f"/mining/{run_id}"), "content")
        accepted = [s for s in (content or {}).get("scenarios", []) if s.get("status") == "accepted"]
        if accepted:
            chosen = accepted[min(scenario, len(accepted) - 1)]
            pages["scenario"] = f"/scenarios/{run_id}/{chosen['seq_id']}/{chosen['edit_id']}"
    pages["evaluation"] = "/evaluation"
    return pages


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--store", required=True)
    parser.add_argument("--out", default="docs/images")
    parser.add_argument("--query", default="the red car turning right")
    parser.add_argument("--height", type=int, default=900)
    parser.add_argument("--scenario", type=int, default=0, help="Which accepted scenario's card (its rank).")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    from playwright.sync_api import sync_playwright  # noqa: PLC0415 -- a test dependency, needed only here

    url, server = _serve(args.store)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=chromium, args=["--no-sandbox"])
        page = browser.new_page(viewport={"width": 1280, "height": args.height})
        for name, path in _pages(url, args.query, args.scenario).items():
            page.set_viewport_size({"width": 1280, "height": TALL.get(name, args.height)})
            page.goto(url + path, wait_until="networkidle", timeout=120_000)
            target = out / f"dashboard-{name}.png"
            page.screenshot(path=str(target))
            logger.info("%s -> %s", path, target)
        browser.close()
    server.should_exit = True
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
