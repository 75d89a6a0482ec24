"""The overview page (``/``): what the store holds, with links to every page group."""

from __future__ import annotations

from fastapi import APIRouter

from flows.dashboard.rendering import DashboardState, page
from tasks.dashboard.overview import OverviewView, read_overview

router = APIRouter()


@page(router, "/", "overview.html", title="Overview")
def overview(state: DashboardState) -> OverviewView:
    return read_overview(state.store)
