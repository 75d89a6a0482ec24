"""The stages' retry policy: which failures are retried, how long between attempts, and the recorder's resubmission
of a task whose worker crashed (with fake futures: no Prefect server, no Ray)."""

from __future__ import annotations

import errno
import random
from dataclasses import dataclass, field
from types import SimpleNamespace
from typing import Any

import pytest
from prefect.states import Failed

from storage import ArtifactStore
from storage.errors import CorruptArtifactError, MissingInputError, SchemaError, StoreNotWritableError
from storage.run_records import read_stage_matrix
from tasks import align, assets, export, grounding_eval, landing, logs, mine, reconstruct
from tasks.retry_policy import STAGE_RETRIES, RetryPolicy, is_transient, retry_when_transient
from tasks.run_record import StageRecorder, recorded_run

NO_WAIT = RetryPolicy(retries=2, first_delay_s=0.0)


@pytest.mark.parametrize("exc", [ConnectionResetError("peer"), TimeoutError("slow"), OSError(errno.EIO, "I/O error"),
                                 OSError("an object store's network error")])
def test_connection_timeout_and_io_errors_are_transient(exc):
    assert is_transient(exc) and retry_when_transient(None, None, Failed(data=exc))


@pytest.mark.parametrize("exc", [MissingInputError("no log synth-000001"), ValueError("iterations must be > 0"),
                                 SchemaError("frames.parquet: column K"), CorruptArtifactError("truncated"),
                                 OSError(errno.ENOSPC, "No space left on device"), PermissionError(errno.EACCES, "no"),
                                 OSError(errno.EROFS, "Read-only file system"), RuntimeError("a bug"),
                                 StoreNotWritableError("/store/x: cannot write to the store /store: the disk is full")])
def test_input_configuration_space_and_permission_errors_are_not(exc):
    assert not is_transient(exc) and not retry_when_transient(None, None, Failed(data=exc))


def test_delays_grow_by_the_backoff_and_stay_within_the_jitter():
    policy = RetryPolicy(retries=3, first_delay_s=2.0, backoff=3.0, jitter=0.25)
    nominal = policy.delays()
    assert len(nominal) == 3 and nominal[0] == 2.0
    assert all(later == earlier * 3.0 for earlier, later in zip(nominal, nominal[1:]))
    rng = random.Random(0)
    for retry, delay in enumerate(nominal, start=1):
        drawn = [policy.delay(retry, rng) for _ in range(50)]
        assert all(0.75 * delay <= d <= 1.25 * delay for d in drawn) and len(set(drawn)) > 1
    with pytest.raises(ValueError, match="retry policy"):
        RetryPolicy(retries=-1)


@pytest.mark.parametrize("stage_task", [logs.generate_synthetic_log, logs.ingest_real_log, landing.land_log,
                                        reconstruct.reconstruct_scene, align.train_motion_aligner, align.align_scene,
                                        assets.build_asset_bank, mine.mine_sequence_task,
                                        grounding_eval.evaluate_grounding_run, export.export_dataset_task])
def test_every_pipeline_stage_task_retries_by_the_one_policy(stage_task):
    assert stage_task.retries == STAGE_RETRIES.retries
    assert list(stage_task.retry_delay_seconds) == STAGE_RETRIES.delays()
    assert stage_task.retry_condition_fn is retry_when_transient


@dataclass
class Future:
    task_run_id: int
    outcome: Any
    crashed: bool

    def wait(self) -> None:
        """Done at once."""

    @property
    def state(self) -> Any:
        return SimpleNamespace(is_crashed=lambda: self.crashed, timestamp=None)

    def result(self) -> Any:
        if isinstance(self.outcome, BaseException):
            raise self.outcome
        return self.outcome


@dataclass
class ScriptedTask:
    """Each submission takes the next ``(outcome, crashed)`` of ``script``."""

    script: list[tuple[Any, bool]]
    name: str = "reconstruct-scene"
    submitted: list[tuple] = field(default_factory=list)
    hooks: list = field(default_factory=list)

    def with_options(self, on_running: list) -> ScriptedTask:
        self.hooks = on_running
        return self

    def submit(self, *args: Any) -> Future:
        self.submitted.append(args)
        for hook in self.hooks:  # the task run starts
            hook(self, SimpleNamespace(start_time=None, run_count=1, name=self.name), SimpleNamespace(timestamp=None))
        outcome, crashed = self.script[len(self.submitted) - 1]
        return Future(len(self.submitted), outcome, crashed)


def test_a_crashed_task_is_resubmitted_with_its_arguments_until_it_succeeds():
    task = ScriptedTask([(RuntimeError("worker died"), True), ("scene", False)])
    recorder = StageRecorder(NO_WAIT)
    assert recorder.result(recorder.submit(task, "reconstruct", ["synth-000001"], "store", "synth-000001")) == "scene"
    assert task.submitted == [("store", "synth-000001")] * 2


def test_crashes_beyond_the_policys_retries_and_plain_failures_are_raised():
    crashing = ScriptedTask([(RuntimeError("worker died"), True)] * 3)
    recorder = StageRecorder(NO_WAIT)
    with pytest.raises(RuntimeError, match="worker died"):
        recorder.result(recorder.submit(crashing, "reconstruct", ["synth-000001"]))
    assert len(crashing.submitted) == 1 + NO_WAIT.retries
    failing = ScriptedTask([(MissingInputError("no log"), False), ("never", False)])
    with pytest.raises(MissingInputError):
        recorder.result(recorder.submit(failing, "reconstruct", ["synth-000001"]))
    assert len(failing.submitted) == 1


def test_the_run_record_counts_the_crashed_attempt_and_says_why(tmp_path):
    task = ScriptedTask([(RuntimeError("worker died"), True), ("scene", False)])
    with recorded_run(str(tmp_path), "run-1", "simsplat-main", {}) as run:
        run.policy = NO_WAIT
        run.result(run.submit(task, "reconstruct", ["synth-000001"]))
    cell = read_stage_matrix(ArtifactStore(tmp_path), "run-1").cell("synth-000001", "reconstruct")
    assert (cell.status, cell.retries) == ("completed", 1)
    assert "resubmitted after 1 worker crash" in cell.note
