"""Step-level progress of long tasks: a throttled Prefect progress artifact plus in-process listeners.

A task hands ``StepProgress(label)`` to a core function as its ``progress(step, total, metrics)``
callback. Each call

* notifies the listeners registered in *this process* (``listening``) — the CLI uses this to draw a
  live bar per sequence when tasks run in threads; tasks on Ray workers have no listeners;
* updates a Prefect progress artifact (created on the first call, only inside a task or flow run),
  at most every ``min_interval_s`` seconds and always on the last step;
* when ``SIMSPLAT_PROGRESS_RELAY`` names a folder (the CLI sets it around a Ray run: Ray workers inherit it),
  writes the latest report there as one small JSON file per label, at most every ``RELAY_INTERVAL_S`` seconds
  and always on the last step; the driver polls the folder (``read_step_reports``) and draws the bars that
  in-process listeners draw for the threads runner.

Progress reporting never raises: a failing listener or an unreachable API is logged and ignored.
"""

from __future__ import annotations

import hashlib
import logging
import os
import threading
import time
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

import pyarrow as pa

from simsplat_core.eval.table_spec import TableSpec
from storage import ArtifactStore, CorruptArtifactError

logger = logging.getLogger(__name__)

#: ``listener(label, step, total, metrics)``.
Listener = Callable[[str, int, int, Mapping[str, float]], None]

_listeners: list[Listener] = []
_lock = threading.Lock()

#: Folder (a local path or a URI) where step reports are relayed to a driver in another process.
RELAY_ENV = "SIMSPLAT_PROGRESS_RELAY"
#: Minimum time between two relayed reports of one label.
RELAY_INTERVAL_S = 0.5


@dataclass(frozen=True)
class StepReport:
    """One progress report: ``step`` of ``total`` of the work ``label`` names, with its latest ``metrics``."""

    label: str
    step: int
    total: int
    metrics: dict[str, float] = field(default_factory=dict)


def _report_name(label: str) -> str:
    return hashlib.sha256(label.encode("utf-8")).hexdigest()[:16] + ".json"


def write_step_report(folder: str, report: StepReport) -> None:
    """Replace ``report.label``'s file in the relay ``folder`` (a local path or a URI) with ``report`` (atomically)."""
    body = {"label": report.label, "step": report.step, "total": report.total, "metrics": dict(report.metrics)}
    ArtifactStore(folder).write_json(_report_name(report.label), body)


def read_step_reports(folder: str) -> list[StepReport]:
    """The latest report of every label in the relay ``folder`` (a file being replaced or unreadable is skipped)."""
    relay = ArtifactStore(folder)
    reports = []
    for name in relay.listdir(""):
        if not name.endswith(".json"):
            continue
        try:
            body = relay.read_json(name)
            reports.append(StepReport(str(body["label"]), int(body["step"]), int(body["total"]),
                                      {str(k): float(v) for k, v in dict(body.get("metrics", {})).items()}))
        except (CorruptArtifactError, FileNotFoundError, KeyError, TypeError, ValueError):
            logger.debug("skipping progress report %s", name, exc_info=True)
    return sorted(reports, key=lambda r: r.label)


@contextmanager
def listening(listener: Listener) -> Iterator[None]:
    """Call ``listener`` for every progress report made in this process while the block runs."""
    with _lock:
        _listeners.append(listener)
    try:
        yield
    finally:
        with _lock:
            _listeners.remove(listener)


def _in_prefect_run() -> bool:
    from prefect.context import FlowRunContext, TaskRunContext

    return TaskRunContext.get() is not None or FlowRunContext.get() is not None


class StepProgress:
    """``progress(step, total, metrics)`` callback for one unit of work (e.g. one sequence).

    Args:
        label: names the work in the artifact description and for listeners (``"reconstruct seq0"``).
        min_interval_s: minimum time between two Prefect artifact updates.
        headline: metric shown in the artifact description when present (e.g. ``"psnr"``).
    """

    def __init__(self, label: str, min_interval_s: float = 2.0, headline: str = "psnr") -> None:
        self.label = label
        self.min_interval_s = min_interval_s
        self.headline = headline
        self._artifact_id: Any = None
        self._artifact_failed = False
        self._last_update = float("-inf")
        self._last_relay = float("-inf")

    def __call__(self, step: int, total: int, metrics: Mapping[str, float] | None = None) -> None:
        metrics = dict(metrics or {})
        with _lock:
            listeners = list(_listeners)
        for listener in listeners:
            try:
                listener(self.label, step, total, metrics)
            except Exception:
                logger.debug("progress listener failed", exc_info=True)
        now = time.monotonic()
        if step >= total or now - self._last_update >= self.min_interval_s:
            self._last_update = now
            self._publish(step, total, metrics)
        if step >= total or now - self._last_relay >= RELAY_INTERVAL_S:
            self._last_relay = now
            self._relay(StepReport(self.label, step, total, metrics))

    def _relay(self, report: StepReport) -> None:
        folder = os.environ.get(RELAY_ENV)
        if not folder:
            return
        try:
            write_step_report(folder, report)
        except Exception:  # progress must never break the work
            logger.debug("could not relay progress of %s to %s", self.label, folder, exc_info=True)

    def _describe(self, step: int, total: int, metrics: Mapping[str, float]) -> str:
        text = f"{self.label}: {step}/{total}"
        if self.headline in metrics:
            text += f" ({self.headline} {metrics[self.headline]:.2f})"
        return text

    def _publish(self, step: int, total: int, metrics: Mapping[str, float]) -> None:
        if self._artifact_failed:
            return
        percent = 100.0 * min(step, total) / max(total, 1)
        description = self._describe(step, total, metrics)
        logger.debug("%s", description)
        try:
            from prefect.artifacts import create_progress_artifact, update_progress_artifact

            if self._artifact_id is None:
                if not _in_prefect_run():
                    return
                self._artifact_id = create_progress_artifact(percent, description=description)
            else:
                update_progress_artifact(self._artifact_id, percent, description=description)
        except Exception:  # the API may be unreachable; progress must never break the work
            self._artifact_failed = True
            logger.warning("could not publish Prefect progress for %s", self.label, exc_info=True)


def publish_rows(rows: list[dict[str, Any]], key: str, description: str) -> bool:
    """Publish ``rows`` as a Prefect table artifact named ``key`` (lowercase letters, digits and dashes) when
    inside a task or flow run; returns whether it was published. Never raises (logged and ignored)."""
    try:
        if not _in_prefect_run():
            return False
        from prefect.artifacts import create_table_artifact

        create_table_artifact(rows, key=key, description=description)
        return True
    except Exception:  # the API may be unreachable; publishing must never break the work
        logger.warning("could not publish the Prefect table %s", key, exc_info=True)
        return False


def publish_table(spec: TableSpec, table: pa.Table, description: str = "") -> bool:
    """Publish a declared evaluation table as the Prefect table artifact ``eval-<name>`` (its printed columns and
    rows, as on the console; ``description`` defaults to the spec's title). Never raises."""
    header, cells = spec.rows_for_console(table)
    rows = [dict(zip(header, row)) for row in cells]
    return publish_rows(rows, f"eval-{spec.name.replace('_', '-')}", description or spec.title)
