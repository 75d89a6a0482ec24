"""The dashboard app: ``create_app(settings)`` -> a FastAPI app serving the pages of ``flows.dashboard.pages``,
their JSON twins, the store's files by artifact id (``/files/<id>``) and its own static assets (``/static``).

Read-only: no route writes to the store. Every asset is served by the app (no CDN; FastAPI's interactive docs,
which fetch theirs from one, are off). With a token set, every request must carry it (``?token=``, an
``Authorization: Bearer`` header, or the cookie set by the first request that had it in its query).
"""

from __future__ import annotations

import logging
import secrets
from collections.abc import Awaitable, Callable
from pathlib import Path

from fastapi import FastAPI, Request, Response
from fastapi.responses import JSONResponse
from fastapi.staticfiles import StaticFiles
from starlette.exceptions import HTTPException as StarletteHTTPException

from flows.dashboard.pages import ROUTERS
from flows.dashboard.rendering import DashboardState, render, state_of
from flows.dashboard.settings import DashboardSettings
from storage.errors import CorruptArtifactError
from tasks.dashboard.files import MADE_PREFIX, read_artifact

logger = logging.getLogger(__name__)

TOKEN_COOKIE = "simsplat_dashboard_token"


def _given_token(request: Request) -> str | None:
    header = request.headers.get("authorization", "")
    if header.lower().startswith("bearer "):
        return header[7:].strip()
    return request.query_params.get("token") or request.cookies.get(TOKEN_COOKIE)


def _token_guard(token: str) -> Callable[[Request, Callable[[Request], Awaitable[Response]]], Awaitable[Response]]:
    async def guard(request: Request, call_next: Callable[[Request], Awaitable[Response]]) -> Response:
        given = _given_token(request)
        if given is None or not secrets.compare_digest(given.encode(), token.encode()):
            return JSONResponse({"error": "this dashboard needs its access token (?token=...)"}, status_code=401)
        response = await call_next(request)
        if request.query_params.get("token"):
            response.set_cookie(TOKEN_COOKIE, token, httponly=True, samesite="strict")
        return response

    return guard


def _serve_file(request: Request, aid: str, raw: bool = False) -> Response:
    """A store file by artifact id (EXR as a PNG preview unless ``raw``), or a picture made for an answer."""
    state = state_of(request)
    try:
        served = state.made.get(aid) if aid.startswith(MADE_PREFIX) else read_artifact(
            state.store, state.index, aid, raw=raw)
    except (CorruptArtifactError, OSError) as exc:
        logger.warning("dashboard file %s: %s", aid, exc)
        return JSONResponse({"error": f"artifact {aid}: {exc}"}, status_code=500)
    if served is None:
        return JSONResponse({"error": f"no artifact {aid!r}"}, status_code=404)
    return Response(served.data, media_type=served.media_type, headers={"Cache-Control": "private, max-age=60"})


def create_app(settings: DashboardSettings) -> FastAPI:
    """The dashboard over ``settings.store_root`` (module docstring)."""
    app = FastAPI(title="SIMSplat dashboard", docs_url=None, redoc_url=None, openapi_url="/api/openapi.json")
    app.state.dashboard = DashboardState.open(settings)
    if settings.token:
        app.middleware("http")(_token_guard(settings.token))
    app.mount("/static", StaticFiles(directory=str(Path(__file__).parent / "static")), name="static")
    app.add_api_route("/files/{aid}", _serve_file, methods=["GET"], name="file")
    for router in ROUTERS:
        app.include_router(router)

    @app.exception_handler(StarletteHTTPException)
    async def not_found(request: Request, exc: StarletteHTTPException) -> Response:
        if request.url.path.startswith(("/api/", "/files/")) or exc.status_code != 404:
            return JSONResponse({"error": str(exc.detail)}, status_code=exc.status_code)
        return render(request, "not_found.html", "Not found", f"no page at {request.url.path}", status_code=404)

    return app

