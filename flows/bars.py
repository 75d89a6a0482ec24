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


def want_lines() -> bool:
    """Without a terminal (a CI log, ``| tee``), report progress as plain lines instead of a live bar, unless
    ``SIMSPLAT_PROGRESS`` says otherwise (``lines`` asks for them anywhere)."""
    setting = os.environ.get("SIMSPLAT_PROGRESS")
    if setting is not None:
        return setting == "lines"
    return not sys.stderr.isatty()


class ProgressLines:
    """Progress as plain lines on stderr, for logs: one line per unit of work each time it passes another
    ``1 / steps`` of its total (its first report included) and when it finishes (``description: step/total
    (pct %)``)."""

    def __init__(self, steps: int = 10) -> None:
        self.steps = steps
        self._shown: dict[str, int] = {}

    def update(self, label: str, step: int, total: int, description: str) -> bool:
        """Write a line if ``step`` reached a new fraction of ``total`` for ``label``; returns whether it did."""
        fraction = self.steps if total <= 0 or step >= total else (step * self.steps) // total
        if fraction <= self._shown.get(label, -1):
            return False
        self._shown[label] = fraction
        percent = 100.0 * step / total if total > 0 else 100.0
        sys.stderr.write(f"{description}: {step}/{total} ({percent:.0f} %)\n")
        sys.stderr.flush()
        return True
