"""The sequence and search pages in a real browser: the sequence page loads with its pictures, its query box answers
a typed description with a mask picture, the search box answers with ranked hits and their pictures."""

from __future__ import annotations

from typing import Any

from storage import ArtifactStore
from storage.language_scenes import read_language_scene
from tests.flows.dashboard.conftest import ServedDashboard, screenshot_dir
from tests.flows.dashboard.store_fixture import DashboardStore


def _all_loaded(page: Any, selector: str) -> int:
    """How many images match ``selector``, after checking every one decoded (naturalWidth > 0)."""
    page.wait_for_function(
        "s => [...document.querySelectorAll(s)].every(i => i.complete && i.naturalWidth > 0)", arg=selector)
    return int(page.locator(selector).count())


def _unique_vehicle(dashboard_store: DashboardStore) -> tuple[str, str]:
    """``(object id, caption)`` of a vehicle whose caption no other object shares."""
    scene = read_language_scene(ArtifactStore(dashboard_store.root), dashboard_store.seq_id, with_records=False).scene
    captions = [n.caption.text for n in scene.nodes if n.caption is not None]
    return next((n.object_id, n.caption.text) for n in scene.nodes
                if n.category == "vehicle" and n.caption is not None and captions.count(n.caption.text) == 1)


def test_the_sequence_page_shows_its_pictures_and_answers_a_query(page: Any, dashboard: ServedDashboard,
                                                                  dashboard_store: DashboardStore) -> None:
    page.goto(f"{dashboard.url}/sequences")
    page.click(f"a[href='/sequences/{dashboard_store.seq_id}']")
    page.wait_for_url(f"**/sequences/{dashboard_store.seq_id}")
    assert _all_loaded(page, "#contact-sheet img") == 4 * 3
    assert _all_loaded(page, "#bev img, #reconstruction img") == 1 + 2
    assert page.locator("#objects tbody tr").count() > 0
    object_id, caption = _unique_vehicle(dashboard_store)
    page.fill("#query input[name=q]", "the " + caption.removeprefix("a ").removeprefix("an "))
    page.click("#query button[type=submit]")
    page.wait_for_selector(".answer .query-masks img")
    assert _all_loaded(page, ".answer img") == 2  # the matched masks over the cameras, the bird's-eye view
    assert object_id in page.locator("table.ranking tr.chosen").inner_text()
    if (shots := screenshot_dir()) is not None:
        page.screenshot(path=str(shots / "sequence.png"), full_page=True)


def test_the_search_box_answers_with_ranked_hits(page: Any, dashboard: ServedDashboard) -> None:
    page.goto(f"{dashboard.url}/search")
    page.fill("input[name=q]", "a pedestrian walking")
    page.click("form.ask button[type=submit]")
    page.wait_for_selector("li.hit")
    hits = page.locator("li.hit").count()
    assert hits >= 1 and _all_loaded(page, "li.hit img") == hits
    assert page.locator("li.hit").first.locator(".hit-head").inner_text().startswith("#1")
    if (shots := screenshot_dir()) is not None:
        page.screenshot(path=str(shots / "search.png"), full_page=True)
