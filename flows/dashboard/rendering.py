"""Pages and their JSON twins from one view function, and the state every page reads.

    router = APIRouter()

    @page(router, "/runs/{run_id}", "run.html", title="Run")
    def run_page(state: DashboardState, run_id: str) -> RunView:   # a read model from tasks.dashboard
        return read_run(state.store, run_id)

registers ``GET /runs/{run_id}`` (the template rendered with ``view``) and ``GET /api/runs/{run_id}`` (the view as
JSON). A view function raising :class:`NotFound` gives a 404 page (or JSON ``{"error": ...}``) naming what is
missing. Path and query parameters are declared on the view function as FastAPI reads them.
"""

from __future__ import annotations

import functools
import inspect
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fastapi import APIRouter, Request
from fastapi.responses import HTMLResponse, JSONResponse, Response
from fastapi.templating import Jinja2Templates

from flows.dashboard.settings import DashboardSettings
from storage.artifact_ids import ArtifactIndex
from storage.run_records import json_safe
from storage.store import ArtifactStore
from tasks.dashboard.files import MadePictures

TEMPLATES = Jinja2Templates(directory=str(Path(__file__).parent / "templates"))

#: The navigation bar: (label, path).
NAV: tuple[tuple[str, str], ...] = (
    ("Overview", "/"), ("Runs", "/runs"), ("Sequences", "/sequences"), ("Search", "/search"), ("Mining", "/mining"),
    ("Evaluation", "/evaluation"), ("Datasets", "/datasets"),
)


class NotFound(LookupError):
    """What a page shows does not exist (an unknown run, sequence or scenario); the message names it."""


@dataclass(frozen=True)
class DashboardState:
    """What every page reads: the settings, the store, its artifact index and the pictures made on request."""

    settings: DashboardSettings
    store: ArtifactStore
    index: ArtifactIndex
    made: MadePictures

    @classmethod
    def open(cls, settings: DashboardSettings) -> DashboardState:
        store = ArtifactStore(settings.store_root)
        return cls(settings, store, ArtifactIndex(store), MadePictures())


def state_of(request: Request) -> DashboardState:
    """The app's ``DashboardState``."""
    state: DashboardState = request.app.state.dashboard
    return state


def render(request: Request, template: str, title: str, view: Any, status_code: int = 200) -> HTMLResponse:
    """``template`` rendered with ``view``, the page title and the navigation."""
    context = {"view": view, "title": title, "nav": NAV, "path": request.url.path,
               "refresh_s": state_of(request).settings.refresh_s}
    return TEMPLATES.TemplateResponse(request, template, context, status_code=status_code)


def page(router: APIRouter, path: str, template: str, *, title: str | Callable[[Any], str]
         ) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Register a view function as the HTML page ``path`` and its JSON twin ``/api<path>`` (module docstring).

    ``title``: the page title, or a function of the view giving it.
    """

    def register(view_fn: Callable[..., Any]) -> Callable[..., Any]:
        params = [p for name, p in inspect.signature(view_fn).parameters.items() if name != "state"]
        request_param = inspect.Parameter("request", inspect.Parameter.POSITIONAL_OR_KEYWORD, annotation=Request)
        signature = inspect.Signature([request_param, *params])

        def call(request: Request, kwargs: dict[str, Any]) -> Any:
            return view_fn(state_of(request), **kwargs)

        @functools.wraps(view_fn)
        def html(request: Request, **kwargs: Any) -> HTMLResponse:
            try:
                view = call(request, kwargs)
            except NotFound as exc:
                return render(request, "not_found.html", "Not found", str(exc), status_code=404)
            return render(request, template, title(view) if callable(title) else title, view)

        @functools.wraps(view_fn)
        def api(request: Request, **kwargs: Any) -> JSONResponse:
            try:
                view = call(request, kwargs)
            except NotFound as exc:
                return JSONResponse({"error": str(exc)}, status_code=404)
            return JSONResponse(json_safe(view))

        api_path = "/api" + (path if path != "/" else "")
        endpoints: tuple[tuple[Callable[..., Any], str, type[Response], str], ...] = (
            (html, path, HTMLResponse, view_fn.__name__), (api, api_path, JSONResponse, f"{view_fn.__name__}_api"))
        for endpoint, route, response, name in endpoints:
            setattr(endpoint, "__signature__", signature)  # noqa: B010 -- FastAPI reads the request and view parameters
            router.add_api_route(route, endpoint, methods=["GET"], response_class=response, name=name)
        return view_fn

    return register
