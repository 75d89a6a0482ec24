"""The evaluation and datasets pages in a real browser: they load without console errors, the headline trend
chart draws a point per run, a dataset page shows its checked shards and data card."""

from __future__ import annotations

from typing import Any

from tests.flows.dashboard.conftest import ServedDashboard, screenshot_dir
from tests.flows.dashboard.evaluation_fixture import EVAL_RUNS
from tests.flows.dashboard.store_fixture import DashboardStore


def test_the_evaluation_page_draws_the_trends(page: Any, dashboard: ServedDashboard) -> None:
    page.goto(dashboard.url + "/evaluation")
    assert page.locator("h1").inner_text() == "Evaluation"
    chart = page.locator("figure.trend[data-table='editing'][data-column='rate'] svg.chart")
    assert chart.is_visible()
    ours = chart.locator("g.series[data-label='ours'] circle")
    assert ours.count() == len(EVAL_RUNS)
    assert chart.locator("g.series[data-label='ours'] polyline").count() == 1
    assert chart.bounding_box()["width"] > 200
    assert page.locator("table.paper-figures").is_visible()
    if (shots := screenshot_dir()) is not None:
        page.screenshot(path=str(shots / "evaluation.png"), full_page=True)
    page.locator("section.run h4 a").first.click()
    page.wait_for_load_state()
    assert page.locator("table.columns").is_visible()


def test_the_dataset_pages_show_the_checked_shards(page: Any, dashboard: ServedDashboard,
                                                   dashboard_store: DashboardStore) -> None:
    page.goto(dashboard.url + "/datasets")
    page.locator(f"tr[data-dataset='{dashboard_store.dataset}'] a").click()
    page.wait_for_load_state()
    assert page.locator("h1").inner_text() == f"Dataset {dashboard_store.dataset}"
    assert page.locator("table.shards tbody tr").count() > 0
    assert page.locator("table.shards tr[data-state='ok']").count() == page.locator("table.shards tbody tr").count()
    assert page.locator("pre.datacard").is_visible()
    if (shots := screenshot_dir()) is not None:
        page.screenshot(path=str(shots / "dataset.png"), full_page=True)
    page.locator("a.verify").click()
    page.wait_for_load_state()
    assert page.locator("table.shards tr[data-state='verified']").count() > 0
