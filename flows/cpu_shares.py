"""Give each concurrently running compute-heavy task its share of the CPUs.

A flow that maps ``n`` heavy tasks asks :func:`task_cpu_share` how many cores each gets (the cores of
the Ray cluster or of this machine for the thread-pool runner, divided by how many of those tasks run
at once), passes that count to the task (which calls ``set_compute_threads``) and submits inside
:func:`reserving_cpus` so Ray also reserves that many CPUs per task and never packs more tasks than
cores. See ``simsplat_core.compute_threads`` for why oversubscription is so costly.
"""

from __future__ import annotations

import contextlib
import logging
import os
from collections.abc import Iterator

logger = logging.getLogger(__name__)


def _current_task_runner():
    from prefect.context import FlowRunContext

    ctx = FlowRunContext.get()
    return None if ctx is None else ctx.task_runner


def _is_ray(runner) -> bool:
    return type(runner).__name__ == "RayTaskRunner"


def _runner_cpus(runner) -> tuple[int, int]:
    """``(cores, max concurrent tasks)`` available to the flow's task runner."""
    cores = os.cpu_count() or 1
    if runner is None:
        return cores, 1
    if _is_ray(runner):
        import ray

        if ray.is_initialized():
            cores = max(1, int(ray.cluster_resources().get("CPU", cores)))
        return cores, cores
    slots = getattr(runner, "_max_workers", None)
    return cores, max(1, min(int(slots), cores)) if slots else cores


def task_cpu_share(num_tasks: int) -> int:
    """Cores per task when ``num_tasks`` heavy tasks are mapped on the current flow's task runner."""
    cores, slots = _runner_cpus(_current_task_runner())
    concurrent = max(1, min(num_tasks, slots))
    share = max(1, cores // concurrent)
    logger.info("%d task(s) on %d core(s): %d concurrently, %d thread(s) each", num_tasks, cores, concurrent, share)
    return share


@contextlib.contextmanager
def reserving_cpus(cpus: int) -> Iterator[None]:
    """Tasks submitted in the block reserve ``cpus`` Ray CPUs each (no-op for other task runners)."""
    if not _is_ray(_current_task_runner()):
        yield
        return
    from prefect_ray.context import remote_options

    with remote_options(num_cpus=cpus):
        yield
