"""Rich progress bars on the terminal: when to draw them and how they look (no Prefect import: the
interactive commands use them without starting the orchestration stack)."""

from __future__ import annotations

import os
import sys

from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn


def new_bar() -> Progress:
    """A bar: description, bar, ``done/total``, elapsed time."""
    return Progress(
        TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(), transient=False
    )


def want_bar() -> bool:
    """Show a bar on an interactive terminal, or when ``SIMSPLAT_PROGRESS=1``; never when ``=0``."""
    setting = os.environ.get("SIMSPLAT_PROGRESS")
    if setting is not None:
        return setting == "1"
    return sys.stderr.isatty()
