"""Recording a flow run while it runs (``storage.run_records``): the run itself and every sequence's stages.

    with recorded_run(store_root, run_id) as run:                   # run.json: running ... completed / failed
        future = run.submit(reconstruct_scene, "reconstruct", [seq_id], store_root, seq_id, config)   # queued
        scene = run.result(future)                                   # completed (or failed, re-raised)
        run.skip("reconstruct", seq_id, "no camera images")
        run.count(scenes=1)

Who writes which event of a stage:

* the flow (driver): ``queued`` when it submits the task, ``skipped`` when it decides not to, and ``completed`` /
  ``failed`` when it sees the task's future finish (with the error message of a failure);
* the task run itself, through a Prefect ``on_running`` hook: ``running`` at the start of every attempt, with the
  attempt's start time and ``retries`` = the task run's ``run_count`` - 1. Prefect 3 sends task-run states to its
  API as events, so a task run read with the client right after its future resolves is often not there yet; the
  engine's own ``TaskRun`` in the worker knows the run count at once. The driver's ``completed`` / ``failed`` event
  carries the retries and start time of the newest ``running`` event, and the seconds from that start to the
  future's final state.

A record that cannot be written is logged and skipped: recording never fails a run. ``StageRecorder`` is the same
interface recording nothing, for flows without a run record.
"""

from __future__ import annotations

import datetime
import logging
from collections.abc import Iterable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, replace
from typing import Any

from storage.run_records import (
    RunRecord,
    StageRecord,
    json_safe,
    parse_time,
    read_stage_record,
    utc_now,
    write_run_record,
    write_stage_record,
)
from storage.store import ArtifactStore
from tasks.code_version import code_version

logger = logging.getLogger(__name__)

#: Longest error message kept in a record, characters.
MAX_ERROR_CHARS = 2000


def error_text(exc: BaseException) -> str:
    """``"<ExceptionType>: <message>"``, cut to ``MAX_ERROR_CHARS``."""
    text = f"{type(exc).__name__}: {exc}"
    return text if len(text) <= MAX_ERROR_CHARS else text[: MAX_ERROR_CHARS - 1] + "…"


def _iso(when: datetime.datetime | None) -> str | None:
    if when is None:
        return None
    return (when if when.tzinfo else when.replace(tzinfo=datetime.UTC)).isoformat(timespec="microseconds")


@dataclass(frozen=True)
class RunningHook:
    """A Prefect ``on_running`` hook writing the ``running`` event of ``stage`` for ``seq_ids`` from inside the task
    run (every attempt). Small and picklable: it travels with the task to a Ray worker."""

    store_root: str
    run_id: str
    stage: str
    seq_ids: tuple[str, ...]

    def __call__(self, task: Any, task_run: Any, state: Any) -> None:
        started = _iso(getattr(task_run, "start_time", None) or getattr(state, "timestamp", None))
        retries = max(0, int(getattr(task_run, "run_count", 1) or 1) - 1)
        store = ArtifactStore(self.store_root)
        for seq_id in self.seq_ids:
            _write_quietly(store, self.run_id, StageRecord(seq_id, self.stage, "running", utc_now(), started_at=started,
                                                           retries=retries, task=str(getattr(task_run, "name", ""))))


def _write_quietly(store: ArtifactStore, run_id: str, record: StageRecord) -> None:
    try:
        write_stage_record(store, run_id, record)
    except (OSError, ValueError) as exc:
        logger.warning("run %s: could not record %s/%s %s: %s", run_id, record.seq_id, record.stage, record.status,
                       exc)


@dataclass(frozen=True)
class _Submitted:
    stage: str
    seq_ids: tuple[str, ...]
    submitted_at: str
    task: str


class StageRecorder:
    """Submits tasks and gathers their results without recording anything (flows without a run record);
    ``RunRecorder`` records the same calls."""

    def submit(self, task: Any, stage: str, seq_ids: Iterable[str], *args: Any, **kwargs: Any) -> Any:
        """``task.submit(*args, **kwargs)``: the task doing ``stage`` for ``seq_ids``."""
        return task.submit(*args, **kwargs)

    def finished(self, future: Any, result: Any) -> None:
        """``future`` finished with ``result``."""

    def failed(self, future: Any, exc: BaseException) -> None:
        """``future`` failed with ``exc``."""

    def result(self, future: Any) -> Any:
        """``future.result()``, recorded as finished or failed (the error re-raised)."""
        try:
            result = future.result()
        except Exception as exc:
            self.failed(future, exc)
            raise
        self.finished(future, result)
        return result

    def skip(self, stage: str, seq_ids: Iterable[str], reason: str) -> None:
        """``seq_ids`` skip ``stage`` because of ``reason``."""

    def count(self, **counts: int) -> None:
        """What the run produced so far (``logs=2``, ``scenes=2``, ...)."""


class RunRecorder(StageRecorder):
    """Records run ``run_id`` of ``flow`` in the store at ``store_root`` (module docstring)."""

    def __init__(self, store_root: str, run_id: str, flow: str) -> None:
        self.store_root = store_root
        self.store = ArtifactStore(store_root)
        self._record = RunRecord(run_id, flow, "running", utc_now())
        self._submitted: dict[Any, _Submitted] = {}

    @property
    def run_id(self) -> str:
        return self._record.run_id

    @property
    def record(self) -> RunRecord:
        """The run record as last written."""
        return self._record

    def _write_run(self, record: RunRecord) -> None:
        self._record = record
        try:
            write_run_record(self.store, record)
        except (OSError, ValueError) as exc:
            logger.warning("run %s: could not write its run record: %s", record.run_id, exc)

    def start(self, parameters: Mapping[str, Any]) -> None:
        """Write the run as ``running`` with its ``parameters`` and the code version."""
        self._write_run(replace(self._record, started_at=utc_now(), code_version=code_version(),
                                parameters=json_safe(dict(parameters))))

    def count(self, **counts: int) -> None:
        self._write_run(replace(self._record, counts={**self._record.counts, **counts}))

    def complete(self) -> None:
        """The run finished."""
        self._write_run(replace(self._record, status="completed", finished_at=utc_now()))

    def fail(self, exc: BaseException) -> None:
        """The run failed with ``exc``."""
        self._write_run(replace(self._record, status="failed", finished_at=utc_now(), error=error_text(exc)))

    def _stage(self, record: StageRecord) -> None:
        _write_quietly(self.store, self.run_id, record)

    def submit(self, task: Any, stage: str, seq_ids: Iterable[str], *args: Any, **kwargs: Any) -> Any:
        seq_ids = tuple(seq_ids)
        now, name = utc_now(), str(getattr(task, "name", ""))
        for seq_id in seq_ids:
            self._stage(StageRecord(seq_id, stage, "queued", now, started_at=now, task=name))
        hooked = task.with_options(on_running=[RunningHook(self.store_root, self.run_id, stage, seq_ids)])
        future = hooked.submit(*args, **kwargs)
        self._submitted[future.task_run_id] = _Submitted(stage, seq_ids, now, name)
        return future

    def _outcome(self, future: Any, status: str, error: str = "", note: str = "") -> None:
        submitted = self._submitted.pop(future.task_run_id, None)
        if submitted is None:
            return
        state = getattr(future, "state", None)
        ended = parse_time(_iso(getattr(state, "timestamp", None))) or datetime.datetime.now(datetime.UTC)
        if len(submitted.seq_ids) > 1:
            note = "; ".join(filter(None, [note, f"one task for {len(submitted.seq_ids)} sequences"]))
        for seq_id in submitted.seq_ids:
            running = self._running_event(seq_id, submitted.stage)
            started = running.started_at if running and running.started_at else submitted.submitted_at
            start = parse_time(started)
            seconds = max(0.0, (ended - start).total_seconds()) if start else None
            self._stage(StageRecord(seq_id, submitted.stage, status, utc_now(), started_at=started, seconds=seconds,
                                    retries=running.retries if running else None, error=error,
                                    task=(running.task if running and running.task else submitted.task), note=note))

    def _running_event(self, seq_id: str, stage: str) -> StageRecord | None:
        try:
            return read_stage_record(self.store, self.run_id, seq_id, stage, "running")
        except (OSError, ValueError) as exc:
            logger.warning("run %s: the running event of %s/%s cannot be read: %s", self.run_id, seq_id, stage, exc)
            return None

    def finished(self, future: Any, result: Any) -> None:
        """Recorded as ``completed``; a result whose ``skipped`` is true reused stored work (noted)."""
        self._outcome(future, "completed", note="reused stored output" if getattr(result, "skipped", False) else "")

    def failed(self, future: Any, exc: BaseException) -> None:
        self._outcome(future, "failed", error=error_text(exc))

    def skip(self, stage: str, seq_ids: Iterable[str], reason: str) -> None:
        now = utc_now()
        for seq_id in seq_ids:
            self._stage(StageRecord(seq_id, stage, "skipped", now, skip_reason=reason))


def _flow_run_facts() -> tuple[str, Mapping[str, Any]]:
    """The current Prefect flow run's name and parameters (``("", {})`` outside a flow run)."""
    from prefect.runtime import flow_run

    return str(flow_run.flow_name or ""), dict(flow_run.parameters or {})


@contextmanager
def recorded_run(store_root: str, run_id: str, flow: str | None = None,
                 parameters: Mapping[str, Any] | None = None) -> Iterator[RunRecorder]:
    """Record run ``run_id``: ``running`` on entry, ``completed`` on a normal exit, ``failed`` with the error when
    the block raises (the error re-raised). ``flow`` and ``parameters`` default to the current Prefect flow run's.

    Raises:
        StoreNotWritableError: on entry, when the store cannot be written (``ArtifactStore.check_writable``).
    """
    name, given = _flow_run_facts() if flow is None or parameters is None else ("", {})
    ArtifactStore(store_root).check_writable()  # an unwritable store fails here, before any stage runs
    recorder = RunRecorder(store_root, run_id, flow or name)
    recorder.start(given if parameters is None else parameters)
    try:
        yield recorder
    except BaseException as exc:
        recorder.fail(exc)
        raise
    recorder.complete()
