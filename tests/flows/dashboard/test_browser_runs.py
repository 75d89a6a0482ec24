"""The runs pages in a real browser: the list links each run, a run's stage matrix shows its statuses, and a
running run's matrix picks up a stage recorded while the page is open, without a reload."""

from __future__ import annotations

from typing import Any

from storage import ArtifactStore
from storage.run_records import StageRecord, utc_now, write_stage_record
from tests.flows.dashboard.conftest import ServedDashboard, screenshot_dir
from tests.flows.dashboard.run_records_fixture import LIVE_RUN
from tests.flows.dashboard.store_fixture import DashboardStore


def test_the_runs_list_and_a_runs_matrix_show(page: Any, dashboard: ServedDashboard,
                                               dashboard_store: DashboardStore) -> None:
    page.goto(dashboard.url + "/runs")
    assert page.locator("h1").inner_text() == "Runs"
    page.locator(f"a[href='/runs/{dashboard_store.mining_run}']").click()
    page.wait_for_url(f"**/runs/{dashboard_store.mining_run}")
    row = page.locator(f"table.matrix tr[data-seq='{dashboard_store.seq_id}']")
    statuses = [row.locator("td.stage").nth(i).get_attribute("data-status") for i in range(6)]
    assert statuses == ["completed", "completed", "completed", "completed", "skipped", "completed"]
    assert "1 retry" in row.inner_text()
    if (shots := screenshot_dir()) is not None:
        page.screenshot(path=str(shots / "run.png"), full_page=True)
        page.goto(dashboard.url + "/runs")
        page.screenshot(path=str(shots / "runs.png"), full_page=True)


def test_a_running_runs_matrix_updates_without_reload(page: Any, dashboard: ServedDashboard,
                                                      dashboard_store: DashboardStore) -> None:
    page.goto(dashboard.url + f"/runs/{LIVE_RUN}")
    row = page.locator(f"table.matrix tr[data-seq='{dashboard_store.seq_id}']")
    align = row.locator("td.stage").nth(2)
    assert align.get_attribute("data-status") is None  # not reached yet
    page.evaluate("window.notReloaded = true")
    now = utc_now()
    write_stage_record(ArtifactStore(dashboard_store.root), LIVE_RUN,
                       StageRecord(dashboard_store.seq_id, "align", "running", now, now, retries=2))
    page.wait_for_selector(f"table.matrix tr[data-seq='{dashboard_store.seq_id}'] td.stage[data-status='running'] "
                           ".status.retried", timeout=15000)
    assert page.evaluate("window.notReloaded") is True
    assert "2 retries" in row.locator("td.stage").nth(2).inner_text()
    if (shots := screenshot_dir()) is not None:
        page.screenshot(path=str(shots / "run-live.png"), full_page=True)
