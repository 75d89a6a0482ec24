"""The overview in a real browser: it loads without console errors and links every page group."""

from __future__ import annotations

from typing import Any

from tests.flows.dashboard.conftest import ServedDashboard, screenshot_dir


def test_the_overview_loads_and_links_every_page(page: Any, dashboard: ServedDashboard) -> None:
    page.goto(dashboard.url + "/")
    assert page.locator("h1").inner_text() == "Overview"
    links = {a.get_attribute("href") for a in page.locator("header nav a").all()}
    assert {"/runs", "/sequences", "/search", "/mining", "/evaluation", "/datasets"} <= links
    if (shots := screenshot_dir()) is not None:
        page.screenshot(path=str(shots / "overview.png"), full_page=True)
