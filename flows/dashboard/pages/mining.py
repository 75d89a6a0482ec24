"""The mining pages: ``/mining`` (every edit run: funnel totals, completion, attempts, plausibility) and
``/mining/{run_id}`` (the run's funnel per category, failure reasons ranked, attempts to acceptance, plausibility,
and its scenario list, filtered by the GET parameters ``category``, ``status``, ``min_plausibility``,
``sequence``)."""

from __future__ import annotations

from fastapi import APIRouter

from flows.dashboard.rendering import DashboardState, NotFound, page
from tasks.dashboard.mining import (
    MiningIndexView,
    MiningRunView,
    ScenarioFilters,
    read_mining_index,
    read_mining_run,
    run_exists,
)

router = APIRouter()


@page(router, "/mining", "mining_index.html", title="Mining")
def mining_index(state: DashboardState) -> MiningIndexView:
    return read_mining_index(state.store)


@page(router, "/mining/{run_id}", "mining_run.html", title=lambda view: f"Mining run {view.run_id}")
def mining_run(state: DashboardState, run_id: str, category: str = "", status: str = "",
               min_plausibility: str = "", sequence: str = "") -> MiningRunView:
    if not run_exists(state.store, run_id):
        raise NotFound(f"run {run_id!r} has no edits in the store")
    least = min_plausibility.strip()
    filters = ScenarioFilters(category.strip(), status.strip(), int(least) if least.isdigit() else None,
                              sequence.strip())
    return read_mining_run(state.store, run_id, filters)
