"""The search page: ``/search?q=<description>`` answers the description over every log of the store (``&top=N``
hits pictured)."""

from __future__ import annotations

from fastapi import APIRouter, Query

from flows.dashboard.rendering import DashboardState, page
from tasks.dashboard.search import DEFAULT_TOP, SearchView, read_search

router = APIRouter()


@page(router, "/search", "search.html", title="Search")
def search(state: DashboardState, q: str = "", top: int = Query(DEFAULT_TOP, ge=1, le=50)) -> SearchView:
    return read_search(state.store, state.made, q, top)
