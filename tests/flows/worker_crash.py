"""A test-only stage task whose first attempt for one sequence kills the process running it, in the middle of
committing its outputs (the worker dies as if the OOM killer had struck).

The wrapped task is built in the test and submitted by the flow in the test process; Ray pickles it to a worker. The
module is registered for pickling by value, so a worker needs no import of the test tree, and nothing of it is
reachable from production code: the crash can only happen in a task built here.
"""

from __future__ import annotations

import functools
import inspect
import os
import signal
import sys
import uuid
from pathlib import Path
from typing import Any

import ray.cloudpickle
from prefect import Task, task

from storage.store import ArtifactStore

ray.cloudpickle.register_pickle_by_value(sys.modules[__name__])


def crashing_once(stage_task: Task, seq_id: str, folder: Path) -> Task:
    """``stage_task`` with the same name and retry options, recording every attempt as a file
    ``folder/attempts/<seq_id>.<uuid>``; the first attempt for ``seq_id`` writes ``folder/crashed`` (its pid) and
    SIGKILLs its own process when it starts committing a group of files (``ArtifactStore.staged_directory``)."""
    inner = stage_task.fn
    signature = inspect.signature(inner)

    @functools.wraps(inner)
    def run_or_crash(*args: Any, **kwargs: Any) -> Any:
        this_seq = signature.bind(*args, **kwargs).arguments.get("seq_id", "")
        (folder / "attempts").mkdir(parents=True, exist_ok=True)
        (folder / "attempts" / f"{this_seq}.{uuid.uuid4().hex}").touch()
        crashed = folder / "crashed"
        if this_seq == seq_id and not crashed.exists():

            def die_while_committing(store: ArtifactStore, *_: Any) -> None:
                crashed.write_text(str(os.getpid()))
                os.kill(os.getpid(), signal.SIGKILL)

            ArtifactStore._swap_into_place = die_while_committing  # type: ignore[method-assign] -- this process dies
        return inner(*args, **kwargs)

    return task(run_or_crash, name=stage_task.name, cache_policy=stage_task.cache_policy,
                retries=stage_task.retries, retry_delay_seconds=stage_task.retry_delay_seconds,
                retry_jitter_factor=stage_task.retry_jitter_factor, retry_condition_fn=stage_task.retry_condition_fn)
