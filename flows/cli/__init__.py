"""The ``simsplat`` command line: one subcommand per job, each a thin call into a flow or a task.

Run ``simsplat --help`` or ``simsplat COMMAND --help``. One module per command group, each holding a
``typer.Typer`` named ``commands``; :data:`GROUPS` registers them all here. What the commands print is in
``flows.cli.printers``, what several groups share in ``flows.cli.common``.
"""

from __future__ import annotations

import logging
import os
from typing import Annotated

import typer

from flows.cli import assets, dashboard, deploy, evaluate, explore, export, ingest, logs, recordings, scenarios, scenes

# Our own loggers go to the Prefect UI too when they log inside a flow or task.
os.environ.setdefault("PREFECT_LOGGING_EXTRA_LOGGERS", "simsplat_core,storage,tasks,flows")
os.environ.setdefault("PREFECT_SERVER_ANALYTICS_ENABLED", "false")
os.environ.setdefault("RAY_AUTH_MODE", "disabled")
os.environ.setdefault("PREFECT_LOGGING_TO_API_WHEN_MISSING_FLOW", "ignore")  # CLI work outside flows logs locally

#: Every command group: its commands and the name they sit under (``None``: top-level commands).
GROUPS: tuple[tuple[typer.Typer, str | None], ...] = (
    (scenes.commands, None),  # run, reconstruct, align
    (explore.commands, None),  # query, render, search
    (scenarios.commands, None),  # edit, mine
    (assets.commands, "assets"),
    (evaluate.commands, "eval"),
    (ingest.commands, None),  # ingest SOURCE PATH
    (logs.commands, None),  # world, inspect
    (export.commands, None),  # export
    (dashboard.commands, None),  # dashboard
    (recordings.commands, None),  # export-rerun
    (deploy.commands, "deploy"),  # deploy check
)

app = typer.Typer(help="SIMSplat scenario-mining pipeline.", no_args_is_help=True, add_completion=False)
for group, name in GROUPS:
    app.add_typer(group, name=name)


@app.callback()
def _configure(verbose: Annotated[bool, typer.Option("--verbose", "-v", help="Log INFO messages.")] = False) -> None:
    logging.basicConfig(
        level=logging.INFO if verbose else logging.WARNING, format="%(levelname)s %(name)s: %(message)s"
    )


def main() -> None:
    """The ``simsplat`` console script."""
    app()


if __name__ == "__main__":
    main()
