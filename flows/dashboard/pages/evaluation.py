"""The evaluation pages: ``/evaluation`` (every run's declared tables, headline trends as charts, the paper's
figures beside ours) and ``/evaluation/<run_id>/<table>`` (one table with every column's meaning and unit)."""

from __future__ import annotations

from fastapi import APIRouter

from flows.dashboard.charts import line_chart
from flows.dashboard.rendering import TEMPLATES, DashboardState, NotFound, page
from tasks.dashboard.evaluation import EvaluationView, TableView, read_evaluation, read_evaluation_table

router = APIRouter()

# The templates draw each trend's chart from its runs and series.
TEMPLATES.env.globals.setdefault("line_chart", line_chart)


@page(router, "/evaluation", "evaluation.html", title="Evaluation")
def evaluation(state: DashboardState) -> EvaluationView:
    return read_evaluation(state.store)


@page(router, "/evaluation/{run_id}/{table}", "evaluation_table.html",
      title=lambda view: f"{view.run_id} · {view.declaration['title']}")
def evaluation_table(state: DashboardState, run_id: str, table: str) -> TableView:
    view = read_evaluation_table(state.store, run_id, table)
    if view is None:
        raise NotFound(f"run {run_id!r} has no declared evaluation table {table!r}")
    return view
