"""Recording a run without Prefect: the recorder writes queued at submission, completed or failed (with the error)
when the future is seen, the retries and start the task run's own running hook wrote, and the run's failure."""

from __future__ import annotations

import datetime
import time
from dataclasses import dataclass, field
from types import SimpleNamespace
from typing import Any

import pytest

from storage import ArtifactStore
from storage.errors import StoreNotWritableError
from storage.run_records import read_run_record, read_stage_matrix
from tasks.run_record import RunningHook, RunRecorder, recorded_run

T0 = datetime.datetime(2026, 1, 1, 12, 0, 0, tzinfo=datetime.UTC)


@dataclass
class FakeFuture:
    task_run_id: str
    outcome: Any
    state: Any = None

    def result(self) -> Any:
        if isinstance(self.outcome, BaseException):
            raise self.outcome
        return self.outcome

    def wait(self) -> None:
        """Done at once."""


@dataclass
class FakeTask:
    """A task whose submission runs its ``on_running`` hooks as a task run on its ``run_count``-th attempt would."""

    name: str
    outcome: Any
    run_count: int = 1
    hooks: list = field(default_factory=list)

    def with_options(self, on_running: list) -> FakeTask:
        return FakeTask(self.name, self.outcome, self.run_count, on_running)

    def submit(self, *args: Any) -> FakeFuture:
        task_run = SimpleNamespace(start_time=T0, run_count=self.run_count, name=f"{self.name}-0")
        for hook in self.hooks:
            hook(self, task_run, SimpleNamespace(timestamp=T0))
        done = SimpleNamespace(timestamp=T0 + datetime.timedelta(seconds=4), is_crashed=lambda: False)
        return FakeFuture(f"tr-{args}", self.outcome, done)


def test_a_recorded_run_writes_each_stages_outcome_with_its_retries(tmp_path):
    store = ArtifactStore(tmp_path)
    with recorded_run(str(tmp_path), "run-1", "simsplat-main", {"seeds": (1,)}) as run:
        queued = run.submit(FakeTask("reconstruct-scene", SimpleNamespace(skipped=True), run_count=3), "reconstruct",
                            ["synth-000001"], "a")
        assert read_stage_matrix(store, "run-1").cell("synth-000001", "reconstruct").status == "running"
        run.result(queued)
        run.result(run.submit(FakeTask("evaluate-grounding", 1), "evaluate", ["synth-000001", "synth-000002"], "b"))
        run.skip("mine", ["synth-000002"], "no reconstructed scene to render")
        run.count(logs=2)
    record = read_run_record(store, "run-1")
    assert (record.status, record.counts, record.parameters) == ("completed", {"logs": 2}, {"seeds": [1]})
    matrix = read_stage_matrix(store, "run-1")
    cell = matrix.cell("synth-000001", "reconstruct")
    assert (cell.status, cell.retries, cell.seconds, cell.task) == ("completed", 2, 4.0, "reconstruct-scene-0")
    assert cell.started_at == T0.isoformat(timespec="microseconds") and "reused" in cell.note
    shared = matrix.cell("synth-000002", "evaluate")
    assert shared.status == "completed" and shared.retries == 0 and "one task for 2 sequences" in shared.note
    assert matrix.cell("synth-000002", "mine").skip_reason == "no reconstructed scene to render"


def test_a_failing_stage_and_run_are_recorded_and_the_error_re_raised(tmp_path):
    store = ArtifactStore(tmp_path)
    with pytest.raises(RuntimeError, match="out of memory"):
        with recorded_run(str(tmp_path), "run-2", "simsplat-main", {}) as run:
            run.result(run.submit(FakeTask("align-scene", RuntimeError("out of memory")), "align", ["synth-000001"]))
    record = read_run_record(store, "run-2")
    assert (record.status, record.error) == ("failed", "RuntimeError: out of memory") and record.finished_at
    cell = read_stage_matrix(store, "run-2").cell("synth-000001", "align")
    assert (cell.status, cell.error, cell.retries) == ("failed", "RuntimeError: out of memory", 0)


def test_the_running_hook_survives_an_unwritable_store(tmp_path):
    (tmp_path / "runs").write_text("a file where the runs folder should be")
    hook = RunningHook(str(tmp_path), "run-3", "align", ("synth-000001",))
    hook(None, SimpleNamespace(start_time=T0, run_count=1, name="t"), None)  # logged, not raised


def test_the_recorder_beats_while_the_run_runs_and_stops_when_it_ends(tmp_path):
    store = ArtifactStore(tmp_path)
    recorder = RunRecorder(str(tmp_path), "run-1", "simsplat-main", heartbeat_s=0.05)
    recorder.start({})
    first = read_run_record(store, "run-1").heartbeat_at
    deadline = time.monotonic() + 30
    while read_run_record(store, "run-1").heartbeat_at == first and time.monotonic() < deadline:
        time.sleep(0.02)
    assert read_run_record(store, "run-1").heartbeat_at > first
    recorder.complete()
    ended = read_run_record(store, "run-1")
    time.sleep(0.2)
    assert read_run_record(store, "run-1") == ended and ended.status == "completed"


def test_a_run_on_a_store_that_cannot_be_written_fails_on_entry(tmp_path) -> None:
    root = tmp_path / "store"
    root.write_text("a file, not a directory")
    entered = []
    with pytest.raises(StoreNotWritableError, match="cannot write to the store"):
        with recorded_run(str(root), "run-3", "simsplat-main", {}):
            entered.append(True)
    assert not entered and root.read_text() == "a file, not a directory"
