"""Progress reporting for flows: a Prefect progress artifact plus, on a terminal, a rich progress bar."""

from __future__ import annotations

import logging
import os
import sys
from dataclasses import dataclass, field
from typing import Any

from prefect.artifacts import create_progress_artifact, update_progress_artifact
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

logger = logging.getLogger(__name__)


def _want_bar() -> bool:
    """Show a bar on an interactive terminal, or when ``SIMSPLAT_PROGRESS=1``; never when ``=0``."""
    setting = os.environ.get("SIMSPLAT_PROGRESS")
    if setting is not None:
        return setting == "1"
    return sys.stderr.isatty()


@dataclass
class FlowProgress:
    """Counts finished units of work and publishes the fraction done.

    Use as a context manager inside a flow::

        with FlowProgress("generate", total=len(futures)) as progress:
            for future in as_completed(futures):
                progress.advance(future.result().seq_id)
    """

    stage: str
    total: int
    done: int = 0
    _artifact_id: Any = None
    _bar: Progress | None = None
    _bar_task: Any = None
    _extra: dict[str, Any] = field(default_factory=dict)

    def __enter__(self) -> "FlowProgress":
        try:
            self._artifact_id = create_progress_artifact(0.0, description=f"{self.stage}: 0/{self.total}")
        except Exception:  # the API may be unreachable; progress must never break the work
            logger.warning("could not create a Prefect progress artifact for %s", self.stage, exc_info=True)
        if _want_bar():
            self._bar = Progress(
                TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                transient=False,
            )
            self._bar.start()
            self._bar_task = self._bar.add_task(self.stage, total=self.total)
        return self

    def advance(self, label: str = "") -> None:
        self.done += 1
        percent = 100.0 * self.done / max(self.total, 1)
        logger.info("%s: %d/%d done %s", self.stage, self.done, self.total, label)
        if self._artifact_id is not None:
            try:
                update_progress_artifact(self._artifact_id, percent, description=f"{self.stage}: {self.done}/{self.total}")
            except Exception:
                logger.debug("progress artifact update failed", exc_info=True)
        if self._bar is not None:
            self._bar.update(self._bar_task, advance=1, description=f"{self.stage} {label}".strip())

    def __exit__(self, *exc: object) -> None:
        if self._bar is not None:
            self._bar.stop()
