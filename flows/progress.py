"""Progress reporting for flows: a Prefect progress artifact plus, on a terminal, rich progress bars.

``FlowProgress`` counts finished tasks of a stage. ``StepBars`` (used by the CLI around a flow run)
draws one live bar per unit of work from the step reports of tasks running in this process
(``tasks.progress``; i.e. with the threads runner). Both share one rich display while ``StepBars`` is
active (rich allows only one live display at a time).
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from prefect.artifacts import create_progress_artifact, update_progress_artifact
from rich.progress import Progress

from flows.bars import new_bar, want_bar
from tasks.progress import listening

logger = logging.getLogger(__name__)

#: The live display of an active ``StepBars``; ``FlowProgress`` adds its bar to it instead of starting one.
_shared_bar: Progress | None = None


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
    _owns_bar: bool = False
    _extra: dict[str, Any] = field(default_factory=dict)

    def __enter__(self) -> FlowProgress:
        try:
            self._artifact_id = create_progress_artifact(0.0, description=f"{self.stage}: 0/{self.total}")
        except Exception:  # the API may be unreachable; progress must never break the work
            logger.warning("could not create a Prefect progress artifact for %s", self.stage, exc_info=True)
        if _shared_bar is not None:
            self._bar = _shared_bar
        elif want_bar():
            self._bar = new_bar()
            self._bar.start()
            self._owns_bar = True
        if self._bar is not None:
            self._bar_task = self._bar.add_task(self.stage, total=self.total)
        return self

    def advance(self, label: str = "") -> None:
        self.done += 1
        percent = 100.0 * self.done / max(self.total, 1)
        logger.info("%s: %d/%d done %s", self.stage, self.done, self.total, label)
        if self._artifact_id is not None:
            try:
                update_progress_artifact(
                    self._artifact_id, percent, description=f"{self.stage}: {self.done}/{self.total}"
                )
            except Exception:
                logger.debug("progress artifact update failed", exc_info=True)
        if self._bar is not None:
            self._bar.update(self._bar_task, advance=1, description=f"{self.stage} {label}".strip())

    def __exit__(self, *exc: object) -> None:
        if self._bar is not None and self._owns_bar:
            self._bar.stop()


class StepBars:
    """One live bar per unit of work (e.g. per sequence), fed by ``tasks.progress`` step reports.

    Only reports made in this process arrive (tasks on Ray workers report to Prefect only). Does
    nothing unless a bar is wanted (interactive terminal or ``SIMSPLAT_PROGRESS=1``)::

        with StepBars():
            flow(...)
    """

    def __init__(self, headline: str = "psnr") -> None:
        self.headline = headline
        self._bar: Progress | None = None
        self._tasks: dict[str, Any] = {}
        self._lock = threading.Lock()
        self._listening: Any = None

    def __enter__(self) -> StepBars:
        global _shared_bar
        if _shared_bar is None and want_bar():
            self._bar = _shared_bar = new_bar()
            self._bar.start()
            self._listening = listening(self._on_step)
            self._listening.__enter__()
        return self

    def _on_step(self, label: str, step: int, total: int, metrics: Mapping[str, float]) -> None:
        description = label + (f" {self.headline} {metrics[self.headline]:.2f}" if self.headline in metrics else "")
        with self._lock:
            if label not in self._tasks:
                self._tasks[label] = self._bar.add_task(label, total=total)
            self._bar.update(self._tasks[label], completed=step, total=total, description=description)

    def __exit__(self, *exc: object) -> None:
        global _shared_bar
        if self._bar is not None:
            self._listening.__exit__(None, None, None)
            self._bar.stop()
            _shared_bar = None
