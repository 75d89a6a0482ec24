"""``simsplat dashboard``: serve the read-only dashboard over a store (``flows.dashboard``)."""

from __future__ import annotations

import logging
from typing import Annotated

import typer
import uvicorn

from flows.dashboard.app import create_app
from flows.dashboard.settings import DEFAULT_HOST, DEFAULT_PORT, DashboardSettings, UnsafeBindError, token_from_env

logger = logging.getLogger(__name__)

commands = typer.Typer()


@commands.command("dashboard")
def dashboard(
    store: Annotated[str, typer.Option(help="Artifact store root to show (read only; a local path or a URI).")],
    host: Annotated[str, typer.Option(help="Address to bind. Anything but a loopback address needs a token.")]
    = DEFAULT_HOST,
    port: Annotated[int, typer.Option(min=1, max=65535, help="Port to listen on.")] = DEFAULT_PORT,
    token: Annotated[str | None, typer.Option(help="Access token every request must carry (default: "
                                              "SIMSPLAT_DASHBOARD_TOKEN).", show_default=False)] = None,
) -> None:
    """Serve the dashboard: runs, sequences, search, mining, scenario cards, evaluation tables and datasets."""
    try:
        settings = DashboardSettings(store, host=host, port=port, token=token or token_from_env())
    except (UnsafeBindError, ValueError) as exc:
        raise typer.BadParameter(str(exc)) from exc
    logger.warning("dashboard of %s at http://%s:%d/%s", store, host, port,
                   " (token required)" if settings.token else "")
    uvicorn.run(create_app(settings), host=host, port=port, log_level="warning")
