"""The local Ray instance a run starts gives its workers the driver's niceness (Ray's own default is 15)."""

from __future__ import annotations

import os

import pytest
from prefect import flow, task

from flows.runtime import RunnerKind, make_task_runner

pytestmark = pytest.mark.orchestration


@task
def _worker_niceness() -> tuple[int, int]:
    """``(niceness, pid)`` of the process the task runs in."""
    return os.nice(0), os.getpid()


@flow
def _report_niceness() -> tuple[int, int]:
    return _worker_niceness.submit().result()


def test_local_ray_workers_run_at_the_drivers_priority(prefect_api_url):
    niceness, pid = _report_niceness.with_options(task_runner=make_task_runner(RunnerKind.ray, 1))()

    assert pid != os.getpid()  # it did run in a Ray worker process
    assert niceness == os.nice(0) != 15
