"""The scenario card: ``/scenarios/{run_id}/{seq_id}/{edit_id}`` (a stable URL: flows publish links to it)."""

from __future__ import annotations

from fastapi import APIRouter

from flows.dashboard.rendering import DashboardState, NotFound, page
from tasks.dashboard.scenarios import ScenarioView, read_scenario

router = APIRouter()


@page(router, "/scenarios/{run_id}/{seq_id}/{edit_id}", "scenario.html",
      title=lambda view: f"Scenario {view.edit_id}")
def scenario(state: DashboardState, run_id: str, seq_id: str, edit_id: str) -> ScenarioView:
    try:
        view = read_scenario(state.store, run_id, seq_id, edit_id)
    except ValueError as exc:  # a name that cannot be a run, sequence or edit id
        raise NotFound(str(exc)) from exc
    if view is None:
        raise NotFound(f"scenario {edit_id!r} of {seq_id!r} is not in run {run_id!r}")
    return view
