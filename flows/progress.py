"""Progress reporting for flows: a Prefect progress artifact plus, on a terminal, rich progress bars.

``FlowProgress`` counts finished tasks of a stage. ``StepBars`` (used by the CLI around a flow run)
draws one live bar per unit of work from the step reports of tasks (``tasks.progress``): those running in
this process (the threads runner) arrive through an in-process listener; with ``relay=True`` (the Ray
runner, whose tasks run in worker processes) a ``RelayedSteps`` also polls the folder the workers write
their latest reports to. Both share one rich display while ``StepBars`` is active (rich allows only one
live display at a time).

Why a folder and not a Ray actor: the workers inherit the relay folder from the driver's environment, so
the tasks stay free of Ray (they only write a small JSON file through ``storage`` every half second) and the
same reports work for any runner; a remote cluster (``RAY_ADDRESS``) gets the variable through its runtime
environment and draws bars when the folder is shared (an object-store URI is fine).
"""

from __future__ import annotations

import logging
import os
import shutil
import tempfile
import threading
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from prefect.artifacts import create_progress_artifact, update_progress_artifact
from rich.progress import Progress

from flows.bars import ProgressLines, new_bar, want_bar, want_lines
from tasks.progress import RELAY_ENV, Listener, listening, read_step_reports

logger = logging.getLogger(__name__)

#: The live display of an active ``StepBars``; ``FlowProgress`` adds its bar to it instead of starting one.
_shared_bar: Progress | None = None
#: Whether a ``StepBars`` is already writing progress lines (nested blocks then write none of their own).
_lines_active = False


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


class RelayedSteps:
    """Step reports of tasks in other processes (Ray workers), relayed through a folder and polled here.

    While the block runs, ``SIMSPLAT_PROGRESS_RELAY`` names a fresh temporary folder (set before the runner
    starts its workers, which inherit it); a thread reads the folder every ``interval_s`` seconds and calls
    ``listener(label, step, total, metrics)`` for each report that changed. On exit it reads once more,
    stops, and removes the folder::

        with RelayedSteps(listener):
            flow.with_options(task_runner=make_task_runner(RunnerKind.ray))(...)
    """

    def __init__(self, listener: Listener, interval_s: float = 0.25) -> None:
        self.listener = listener
        self.interval_s = interval_s
        self.folder = ""
        self._seen: dict[str, tuple[int, int]] = {}
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._previous: str | None = None

    def __enter__(self) -> RelayedSteps:
        self.folder = tempfile.mkdtemp(prefix="simsplat-progress-")
        self._previous = os.environ.get(RELAY_ENV)
        os.environ[RELAY_ENV] = self.folder
        self._thread = threading.Thread(target=self._run, name="simsplat-progress-relay", daemon=True)
        self._thread.start()
        return self

    def poll(self) -> int:
        """Pass the reports that changed since the last poll to the listener; returns how many."""
        changed = 0
        for report in read_step_reports(self.folder):
            state = (report.step, report.total)
            if self._seen.get(report.label) == state:
                continue
            self._seen[report.label] = state
            changed += 1
            try:
                self.listener(report.label, report.step, report.total, report.metrics)
            except Exception:  # progress must never break the work
                logger.debug("progress listener failed", exc_info=True)
        return changed

    def _run(self) -> None:
        while not self._stop.wait(self.interval_s):
            try:
                self.poll()
            except Exception:
                logger.debug("could not read relayed progress", exc_info=True)

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        try:
            self.poll()
        finally:
            if self._previous is None:
                os.environ.pop(RELAY_ENV, None)
            else:
                os.environ[RELAY_ENV] = self._previous
            shutil.rmtree(self.folder, ignore_errors=True)


class StepBars:
    """One live bar per unit of work (e.g. per sequence), fed by ``tasks.progress`` step reports.

    Reports made in this process arrive through a listener; with ``relay=True`` those of tasks in other
    processes (Ray workers) arrive through a ``RelayedSteps`` folder. On an interactive terminal (or with
    ``SIMSPLAT_PROGRESS=1``) they drive live bars; without one (a CI log) plain lines every tenth of each unit's
    work (``flows.bars.ProgressLines``); ``SIMSPLAT_PROGRESS=0`` shows nothing::

        with StepBars(relay=runner == RunnerKind.ray):
            flow(...)
    """

    def __init__(self, headline: str = "psnr", relay: bool = False) -> None:
        self.headline = headline
        self.relay = relay
        self._bar: Progress | None = None
        self._tasks: dict[str, Any] = {}
        self._lock = threading.Lock()
        self._listening: Any = None
        self._relayed: RelayedSteps | None = None
        self._lines: ProgressLines | None = None

    def __enter__(self) -> StepBars:
        global _shared_bar, _lines_active
        if _shared_bar is None and want_bar():
            self._bar = _shared_bar = new_bar()
            self._bar.start()
        elif _shared_bar is None and not _lines_active and want_lines():
            self._lines = ProgressLines()
            _lines_active = True
        if self._bar is not None or self._lines is not None:
            self._listening = listening(self._on_step)
            self._listening.__enter__()
            if self.relay:
                self._relayed = RelayedSteps(self._on_step).__enter__()
        return self

    def _on_step(self, label: str, step: int, total: int, metrics: Mapping[str, float]) -> None:
        description = label + (f" {self.headline} {metrics[self.headline]:.2f}" if self.headline in metrics else "")
        if self._lines is not None:
            with self._lock:
                self._lines.update(label, step, total, description)
            return
        bar = self._bar
        if bar is None:  # steps are listened to only while a bar or lines are shown
            return
        with self._lock:
            if label not in self._tasks:
                self._tasks[label] = bar.add_task(label, total=total)
            bar.update(self._tasks[label], completed=step, total=total, description=description)

    def __exit__(self, *exc: object) -> None:
        global _shared_bar, _lines_active
        if self._bar is None and self._lines is None:
            return
        if self._relayed is not None:
            self._relayed.__exit__(None, None, None)
        self._listening.__exit__(None, None, None)
        if self._bar is not None:
            self._bar.stop()
            _shared_bar = None
        else:
            _lines_active = False
