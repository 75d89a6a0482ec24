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

A task whose worker crashed (the process died: its future's state is ``Crashed``) is resubmitted by the recorder
after a back-off delay, at most ``tasks.retry_policy.STAGE_RETRIES.retries`` times; the resubmission's ``queued``
event says why, and its ``running`` and final events count the crashed attempts in ``retries``.

A record that cannot be written is logged and skipped: recording never fails a run. ``StageRecorder`` is the same
interface recording nothing (but resubmitting crashed tasks), for flows without a run record.
"""

from __future__ import annotations

import datetime
import logging
import threading
import time
from collections.abc import Iterable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from typing import Any

from storage.run_records import (
    HEARTBEAT_S,
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
from tasks.retry_policy import STAGE_RETRIES, RetryPolicy

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
    run (every attempt). Small and picklable: it travels with the task to a Ray worker. ``crashed_attempts`` are
    the earlier task runs of the same stage whose worker crashed (counted in ``retries``)."""

    store_root: str
    run_id: str
    stage: str
    seq_ids: tuple[str, ...]
    crashed_attempts: int = 0

    def __call__(self, task: Any, task_run: Any, state: Any) -> None:
        started = _iso(getattr(task_run, "start_time", None) or getattr(state, "timestamp", None))
        retries = self.crashed_attempts + max(0, int(getattr(task_run, "run_count", 1) or 1) - 1)
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
class _Call:
    """One submission of a stage's task: what to resubmit when its worker crashes.

    Attributes:
        crashes: earlier submissions of the same call whose worker crashed; note: why it was resubmitted.
    """

    task: Any
    stage: str
    seq_ids: tuple[str, ...]
    args: tuple[Any, ...]
    kwargs: dict[str, Any]
    submitted_at: str = field(default_factory=utc_now)
    crashes: int = 0
    note: str = ""

    @property
    def task_name(self) -> str:
        return str(getattr(self.task, "name", ""))


def crashed(future: Any) -> bool:
    """Whether ``future``'s task run crashed (its worker process died) rather than failed with an exception."""
    future.wait()
    state = getattr(future, "state", None)
    return bool(state is not None and state.is_crashed())


class StageRecorder:
    """Submits tasks and gathers their results without recording anything (flows without a run record), resubmitting
    a task whose worker crashed as ``policy`` says; ``RunRecorder`` records the same calls."""

    def __init__(self, policy: RetryPolicy = STAGE_RETRIES) -> None:
        self.policy = policy
        self._calls: dict[Any, _Call] = {}

    def submit(self, task: Any, stage: str, seq_ids: Iterable[str], *args: Any, **kwargs: Any) -> Any:
        """``task.submit(*args, **kwargs)``: the task doing ``stage`` for ``seq_ids``."""
        return self._submit(_Call(task, stage, tuple(seq_ids), args, kwargs))

    def _submit(self, call: _Call) -> Any:
        future = self._start(call)
        self._calls[future.task_run_id] = call
        return future

    def _start(self, call: _Call) -> Any:
        """Submit ``call``'s task; the future."""
        return call.task.submit(*call.args, **call.kwargs)

    def finished(self, future: Any, result: Any) -> None:
        """``future`` finished with ``result``."""

    def failed(self, future: Any, exc: BaseException) -> None:
        """``future`` failed with ``exc``."""

    def result(self, future: Any) -> Any:
        """``future.result()``, recorded as finished or failed (the error re-raised). A future whose worker crashed
        is replaced by a resubmission of its task after the policy's delay, while retries are left."""
        while True:
            try:
                result = future.result()
            except Exception as exc:
                retry = self._resubmit_after_crash(future, exc)
                if retry is None:
                    self.failed(future, exc)
                    self._calls.pop(future.task_run_id, None)
                    raise
                future = retry
                continue
            self.finished(future, result)
            self._calls.pop(future.task_run_id, None)
            return result

    def _resubmit_after_crash(self, future: Any, exc: BaseException) -> Any | None:
        """A resubmission of ``future``'s task when its worker crashed and the policy allows another attempt (after
        its back-off delay); ``None`` otherwise."""
        call = self._calls.get(future.task_run_id)
        if call is None or call.crashes >= self.policy.retries or not crashed(future):
            return None
        delay = self.policy.delay(call.crashes + 1)
        note = (f"worker crashed ({error_text(exc)}); retry {call.crashes + 1} of {self.policy.retries} "
                f"after {delay:.1f} s")
        logger.warning("%s of %s: %s", call.stage, ", ".join(call.seq_ids), note)
        self._calls.pop(future.task_run_id, None)
        time.sleep(delay)
        return self._submit(replace(call, submitted_at=utc_now(), crashes=call.crashes + 1, note=note))

    def skip(self, stage: str, seq_ids: Iterable[str], reason: str) -> None:
        """``seq_ids`` skip ``stage`` because of ``reason``."""

    def count(self, **counts: int) -> None:
        """What the run produced so far (``logs=2``, ``scenes=2``, ...)."""


class RunRecorder(StageRecorder):
    """Records run ``run_id`` of ``flow`` in the store at ``store_root`` (module docstring)."""

    def __init__(self, store_root: str, run_id: str, flow: str, policy: RetryPolicy = STAGE_RETRIES,
                 heartbeat_s: float = HEARTBEAT_S) -> None:
        super().__init__(policy)
        self.store_root = store_root
        self.store = ArtifactStore(store_root)
        self.heartbeat_s = heartbeat_s
        self._record = RunRecord(run_id, flow, "running", utc_now())
        self._record_lock = threading.Lock()
        self._stopped = threading.Event()
        self._heartbeat: threading.Thread | None = None

    @property
    def run_id(self) -> str:
        return self._record.run_id

    @property
    def record(self) -> RunRecord:
        """The run record as last written."""
        return self._record

    def _update(self, **changes: Any) -> None:
        """Rewrite the run record with ``changes`` (from the flow or the heartbeat thread, one at a time)."""
        with self._record_lock:
            if "counts" in changes:
                changes["counts"] = {**self._record.counts, **changes["counts"]}
            self._record = record = replace(self._record, **changes)
            try:
                write_run_record(self.store, record)
            except (OSError, ValueError) as exc:
                logger.warning("run %s: could not write its run record: %s", record.run_id, exc)

    def start(self, parameters: Mapping[str, Any]) -> None:
        """Write the run as ``running`` with its ``parameters`` and the code version, then rewrite it every
        ``heartbeat_s`` seconds until the run ends (``RunRecord.observed_status`` tells a dead run by that)."""
        now = utc_now()
        self._update(started_at=now, heartbeat_at=now, code_version=code_version(),
                     parameters=json_safe(dict(parameters)))
        self._heartbeat = threading.Thread(target=self._beat, name=f"heartbeat-{self.run_id}", daemon=True)
        self._heartbeat.start()

    def _beat(self) -> None:
        while not self._stopped.wait(self.heartbeat_s):
            self._update(heartbeat_at=utc_now())

    def _stop_heartbeat(self) -> None:
        self._stopped.set()
        if self._heartbeat is not None:
            self._heartbeat.join()

    def count(self, **counts: int) -> None:
        self._update(counts=counts)

    def complete(self) -> None:
        """The run finished."""
        self._stop_heartbeat()
        self._update(status="completed", finished_at=utc_now())

    def fail(self, exc: BaseException) -> None:
        """The run failed with ``exc``."""
        self._stop_heartbeat()
        self._update(status="failed", finished_at=utc_now(), error=error_text(exc))

    def _stage(self, record: StageRecord) -> None:
        _write_quietly(self.store, self.run_id, record)

    def _start(self, call: _Call) -> Any:
        for seq_id in call.seq_ids:
            self._stage(StageRecord(seq_id, call.stage, "queued", call.submitted_at, started_at=call.submitted_at,
                                    retries=call.crashes or None, task=call.task_name, note=call.note))
        hook = RunningHook(self.store_root, self.run_id, call.stage, call.seq_ids, call.crashes)
        return call.task.with_options(on_running=[hook]).submit(*call.args, **call.kwargs)

    def _outcome(self, future: Any, status: str, error: str = "", note: str = "") -> None:
        submitted = self._calls.get(future.task_run_id)
        if submitted is None:
            return
        notes = [note,
                 f"resubmitted after {submitted.crashes} worker crash(es)" if submitted.crashes else "",
                 f"one task for {len(submitted.seq_ids)} sequences" if len(submitted.seq_ids) > 1 else ""]
        note = "; ".join(filter(None, notes))
        state = getattr(future, "state", None)
        ended = parse_time(_iso(getattr(state, "timestamp", None))) or datetime.datetime.now(datetime.UTC)
        for seq_id in submitted.seq_ids:
            running = self._running_event(seq_id, submitted.stage)
            started = running.started_at if running and running.started_at else submitted.submitted_at
            start = parse_time(started)
            seconds = max(0.0, (ended - start).total_seconds()) if start else None
            self._stage(StageRecord(seq_id, submitted.stage, status, utc_now(), started_at=started, seconds=seconds,
                                    retries=running.retries if running else None, error=error,
                                    task=(running.task if running and running.task else submitted.task_name),
                                    note=note))

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
    recorder = RunRecorder(store_root, run_id, flow or name)
    recorder.store.check_writable()  # an unwritable store fails here, before any stage runs
    recorder.start(given if parameters is None else parameters)
    try:
        yield recorder
    except BaseException as exc:
        recorder.fail(exc)
        raise
    recorder.complete()
