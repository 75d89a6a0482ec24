"""The mining pages in a real browser: the run page loads and links its scenarios; a scenario card shows its
before/after images, its frame slider changes the frame shown, and its BEV animation plays."""

from __future__ import annotations

from typing import Any

from tests.flows.dashboard.conftest import ServedDashboard, screenshot_dir
from tests.flows.dashboard.store_fixture import DashboardStore


def _card_url(dashboard: ServedDashboard, store: DashboardStore) -> str:
    return f"{dashboard.url}/scenarios/{store.mining_run}/{store.seq_id}/{store.mining.scenarios[0].edit_id}"


def test_the_mining_pages_load_and_link_the_scenarios(page: Any, dashboard: ServedDashboard,
                                                      dashboard_store: DashboardStore) -> None:
    page.goto(f"{dashboard.url}/mining")
    page.click(f"a[href='/mining/{dashboard_store.mining_run}']")
    page.wait_for_selector("#funnel")
    total = page.locator("#funnel tr[data-category='total'] td[data-stage='accepted']")
    assert total.get_attribute("data-count") == str(dashboard_store.mining.accepted)
    links = page.locator("#scenarios a").count()
    assert links == len(page.locator("#scenarios tr[data-status]").all()) and links > 0
    if (shots := screenshot_dir()) is not None:
        page.screenshot(path=str(shots / "mining_run.png"), full_page=True)
    page.select_option("select[name=status]", "accepted")
    page.click("form.filters button")
    page.wait_for_url("**status=accepted**")
    assert page.locator("#scenarios tr[data-status]").count() == dashboard_store.mining.accepted


def _loaded(page: Any, selector: str) -> bool:
    return bool(page.eval_on_selector(selector, "img => img.complete && img.naturalWidth > 0"))


def test_a_scenario_card_shows_its_frames_and_slides_through_them(page: Any, dashboard: ServedDashboard,
                                                                  dashboard_store: DashboardStore) -> None:
    page.goto(_card_url(dashboard, dashboard_store))
    first = "figure.pair img.after"
    page.wait_for_function("document.querySelector('figure.pair img.after').naturalWidth > 0")
    page.wait_for_function("document.querySelector('figure.pair img.before').naturalWidth > 0")
    assert _loaded(page, "figure.pair img.before") and _loaded(page, first)
    before_src = page.get_attribute(first, "src")
    slider = page.locator("#frame")
    last = int(slider.get_attribute("max"))
    assert last > 0
    page.wait_for_selector("#frame[data-ready='true']")  # the script has the card's data (fetched after load)
    slider.fill(str(last))  # a range input: fill sets the value and fires input
    page.wait_for_function(f"document.querySelector('{first}').getAttribute('src') !== {before_src!r} && "
                           f"document.querySelector('{first}').naturalWidth > 0")
    assert page.get_attribute(first, "src") != before_src
    assert page.locator("#frame-label").inner_text() != "0"
    if (shots := screenshot_dir()) is not None:
        page.screenshot(path=str(shots / "scenario_card.png"), full_page=True)


def test_the_bev_animation_plays_and_pauses(page: Any, dashboard: ServedDashboard,
                                            dashboard_store: DashboardStore) -> None:
    page.goto(_card_url(dashboard, dashboard_store))
    page.wait_for_selector("svg#bev rect.box")
    assert page.get_attribute("svg#bev", "data-step") == "0"
    moving = "svg#bev rect.box:not(.log):not(.ghost)"
    start = [page.get_attribute(f"{moving} >> nth={k}", "transform") for k in range(page.locator(moving).count())]
    page.click("#bev-play")
    page.wait_for_function("Number(document.querySelector('svg#bev').dataset.step) >= 2")
    assert page.get_attribute("svg#bev", "data-playing") == "true"
    now = [page.get_attribute(f"{moving} >> nth={k}", "transform") for k in range(len(start))]
    assert now != start  # the boxes moved with the steps
    page.click("#bev-play")
    assert page.get_attribute("svg#bev", "data-playing") == "false"
    paused = page.get_attribute("svg#bev", "data-step")
    page.wait_for_timeout(400)
    assert page.get_attribute("svg#bev", "data-step") == paused
