"""The runs pages: ``/runs`` (every run folder) and ``/runs/<run_id>`` (one run with its sequence x stage matrix),
plus ``/runs/<run_id>/matrix``, the HTML fragment a running run's page re-fetches to update without reload."""

from __future__ import annotations

import html

from fastapi import APIRouter, Request
from fastapi.responses import HTMLResponse

from flows.dashboard.rendering import DashboardState, NotFound, page, render, state_of
from tasks.dashboard.runs import RunsView, RunView, UnknownRun, read_run, read_runs

router = APIRouter()


@page(router, "/runs", "runs.html", title="Runs")
def runs(state: DashboardState) -> RunsView:
    return read_runs(state.store)


def _run_view(state: DashboardState, run_id: str) -> RunView:
    try:
        return read_run(state.store, run_id)
    except UnknownRun as exc:
        raise NotFound(str(exc)) from exc


@page(router, "/runs/{run_id}", "run.html", title=lambda view: f"Run {view.run_id}")
def run(state: DashboardState, run_id: str) -> RunView:
    return _run_view(state, run_id)


@router.get("/runs/{run_id}/matrix", response_class=HTMLResponse, name="run_matrix")
def run_matrix(request: Request, run_id: str) -> HTMLResponse:
    """The live part of a run's page (status, counts, stage matrix) as an HTML fragment."""
    try:
        view = _run_view(state_of(request), run_id)
    except NotFound as exc:
        return HTMLResponse(f'<div class="problem" role="alert">{html.escape(str(exc))}</div>', status_code=404)
    return render(request, "run_live.html", f"Run {run_id}", view)
