"""Fixtures of the dashboard tests: the store they read (built once per session), the app served on 127.0.0.1 by
uvicorn in a thread, and headless Chromium driven by playwright through its executable path (Debian's
``chromium``; ``make test`` installs it). A browser page fails its test on any console error or failed request."""

from __future__ import annotations

import os
import shutil
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import uvicorn

from flows.dashboard.app import create_app
from flows.dashboard.settings import DashboardSettings
from tests.flows.dashboard.store_fixture import DashboardStore, build_dashboard_store
from tests.flows.prefect_processes import free_port

#: Where the browser is looked for (``SIMSPLAT_CHROMIUM`` overrides).
CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome")


@pytest.fixture(scope="session")
def dashboard_store(tmp_path_factory: pytest.TempPathFactory) -> DashboardStore:
    return build_dashboard_store(tmp_path_factory.mktemp("dashboard_store"))


class ServedDashboard:
    """A dashboard app served by uvicorn on a thread (``url``: its address); ``stop()`` shuts it down."""

    def __init__(self, settings: DashboardSettings) -> None:
        self.url = f"http://{settings.host}:{settings.port}"
        config = uvicorn.Config(create_app(settings), host=settings.host, port=settings.port, log_level="warning")
        self._server = uvicorn.Server(config)
        self._thread = threading.Thread(target=self._server.run, daemon=True)
        self._thread.start()
        deadline = time.monotonic() + 20
        while not self._server.started:
            if time.monotonic() > deadline or not self._thread.is_alive():
                raise RuntimeError("the dashboard did not start")
            time.sleep(0.05)

    def stop(self) -> None:
        self._server.should_exit = True
        self._thread.join(timeout=10)


def serve(store_root: str, **kw: Any) -> ServedDashboard:
    """The dashboard of ``store_root`` on a free loopback port."""
    return ServedDashboard(DashboardSettings(store_root, port=free_port(), **kw))


@pytest.fixture(scope="package")
def dashboard(dashboard_store: DashboardStore) -> Iterator[ServedDashboard]:
    served = serve(dashboard_store.root, refresh_s=0.5)
    yield served
    served.stop()


def chromium_path() -> str | None:
    """The Chromium executable, ``None`` when the machine has none."""
    given = os.environ.get("SIMSPLAT_CHROMIUM")
    if given:
        return given
    return next((p for p in map(shutil.which, CHROMIUM_NAMES) if p), None)


@pytest.fixture(scope="package")
def browser() -> Iterator[Any]:
    """Chromium, for this package's tests only: playwright's sync API keeps an asyncio loop running on the main
    thread while it is open, and Prefect would then take every later test for async code."""
    path = chromium_path()
    if path is None:
        if os.environ.get("CI"):
            pytest.fail("no Chromium on this CI machine: `make test` installs Debian's chromium package")
        pytest.skip("no Chromium here (apt-get install chromium)")
    sync_api = pytest.importorskip("playwright.sync_api")
    with sync_api.sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=path, args=["--no-sandbox", "--disable-gpu"])
        yield browser
        browser.close()


class PageProblems:
    """Console errors, uncaught exceptions and failed requests a page met."""

    def __init__(self, page: Any) -> None:
        self.errors: list[str] = []
        page.on("console", lambda msg: self.errors.append(f"console: {msg.text}") if msg.type == "error" else None)
        page.on("pageerror", lambda exc: self.errors.append(f"page error: {exc}"))
        page.on("requestfailed", lambda req: self.errors.append(f"request failed: {req.url}"))
        page.on("response", lambda r: self.errors.append(f"HTTP {r.status}: {r.url}") if r.status >= 400 else None)


@pytest.fixture
def page(browser: Any) -> Iterator[Any]:
    """A fresh browser page; the test fails if the page logged a console error or a request failed (tests that
    expect an error status call ``page.problems.errors.clear()``)."""
    context = browser.new_context(viewport={"width": 1400, "height": 1000})
    page = context.new_page()
    page.problems = PageProblems(page)
    yield page
    errors = list(page.problems.errors)
    context.close()
    assert not errors, errors


def screenshot_dir() -> Path | None:
    """Where browser tests save screenshots of the main pages (``SIMSPLAT_SCREENSHOTS``), ``None``: nowhere."""
    given = os.environ.get("SIMSPLAT_SCREENSHOTS")
    return Path(given) if given else None
