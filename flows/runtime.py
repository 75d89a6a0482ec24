"""Orchestration runtime: one Prefect API for the whole run, and the task runner choice.

Prefect's ephemeral mode starts a temporary API server in *every* process that runs a task; with
Ray that is one server per worker (8-15 s each). ``prefect_api()`` starts a single local server
up front (unless ``PREFECT_API_URL`` already points at one, e.g. a ``prefect server start`` or Prefect
Cloud) and exports its URL so Ray workers, which inherit the driver's environment, report to it.
"""

from __future__ import annotations

import contextlib
import logging
import os
from collections.abc import Iterator
from enum import StrEnum

logger = logging.getLogger(__name__)


class RunnerKind(StrEnum):
    """Where mapped tasks run."""

    ray = "ray"  # a local (or addressed) Ray cluster: one worker process per CPU
    threads = "threads"  # a thread pool in this process (no start-up cost; good for small jobs)


@contextlib.contextmanager
def prefect_api(timeout_s: float = 90.0) -> Iterator[str]:
    """Make sure a Prefect API is reachable for the duration of the block; yields its URL.

    If ``PREFECT_API_URL`` is set it is used as is. Otherwise a local server is started in a
    subprocess and stopped (after flushing logs) when the block exits.
    """
    existing = os.environ.get("PREFECT_API_URL")
    if existing:
        yield existing
        return
    os.environ.setdefault("PREFECT_SERVER_ANALYTICS_ENABLED", "false")
    from prefect.server.api.server import SubprocessASGIServer
    from prefect.settings import PREFECT_API_URL, PREFECT_LOGGING_TO_API_ENABLED, temporary_settings

    server = SubprocessASGIServer()
    server.start(timeout=int(timeout_s))
    logger.info("Prefect API for this run: %s", server.api_url)
    os.environ["PREFECT_API_URL"] = server.api_url
    try:
        with temporary_settings({PREFECT_API_URL: server.api_url}):
            yield server.api_url
            _flush_prefect_logs()
    finally:
        # Whatever is logged from here on (Ray shutdown, the server's own goodbye) must not be queued
        # for an API that is about to disappear.
        with temporary_settings({PREFECT_LOGGING_TO_API_ENABLED: False}):
            shutdown_ray()
            os.environ.pop("PREFECT_API_URL", None)
            server.stop()


def _flush_prefect_logs(timeout_s: float = 10.0) -> None:
    """Send every queued log record to the API while it is still up (blocks up to ``timeout_s``)."""
    try:
        from prefect.logging.handlers import APILogWorker

        APILogWorker.drain_all(timeout=timeout_s)
    except Exception:  # pragma: no cover - best effort at shutdown
        logger.debug("could not flush Prefect logs", exc_info=True)


def make_task_runner(kind: RunnerKind, num_cpus: int | None = None):
    """Build the Prefect task runner for ``kind``.

    Args:
        kind: ``RunnerKind.ray`` connects to ``RAY_ADDRESS`` when set, else starts a local Ray with
            ``num_cpus`` CPUs (default: all); ``RunnerKind.threads`` uses ``num_cpus`` threads.
    """
    if kind == RunnerKind.threads:
        from prefect.task_runners import ThreadPoolTaskRunner

        return ThreadPoolTaskRunner(max_workers=num_cpus or os.cpu_count() or 1)
    from prefect_ray import RayTaskRunner

    os.environ.setdefault("RAY_AUTH_MODE", "disabled")
    from tasks.progress import RELAY_ENV

    address = os.environ.get("RAY_ADDRESS")
    if address:  # a running cluster's workers do not inherit this process's environment: hand them the relay
        relay = os.environ.get(RELAY_ENV)
        return RayTaskRunner(address=address,
                             init_kwargs={"runtime_env": {"env_vars": {RELAY_ENV: relay}}} if relay else None)
    init_kwargs = {"num_cpus": num_cpus or os.cpu_count() or 1, "include_dashboard": False, "log_to_driver": True,
                   "runtime_env": {"env_vars": local_worker_env()}}
    return RayTaskRunner(init_kwargs=init_kwargs)


# Ray starts its workers at niceness 15 so that they yield to its own daemons on a shared node. On a local run the
# workers are the job: at niceness 15 any nice-0 process on the machine (the Prefect API server answering the
# workers' state and log updates, the driver polling, whatever else runs there) takes the cores first, and a
# reconstruction slows down several-fold on a loaded machine (bench/bench_ray_niceness.py). Ray adds the setting to the
# niceness the workers inherit from the driver, so 0 gives them the driver's: a run started with `nice` stays niced.
def local_worker_env() -> dict[str, str]:
    """Environment of the workers of a local Ray instance this process starts: they run at the driver's priority."""
    return {"RAY_worker_niceness": "0"}


@contextlib.contextmanager
def flow_resubmits_crashed_tasks() -> Iterator[None]:
    """Ray does not re-run a task submitted in the block when its worker dies (its default: up to 3 times, at once
    and unrecorded): the flow resubmits it with the stages' back-off and records the retry
    (``tasks.retry_policy``, ``tasks.run_record.StageRecorder``). Only an option for the Ray task runner."""
    from prefect_ray.context import remote_options

    with remote_options(max_retries=0):
        yield


def shutdown_ray() -> None:
    """Stop the local Ray instance if this process started one."""
    try:
        import ray

        if ray.is_initialized():
            ray.shutdown()
    except ImportError:  # pragma: no cover
        pass
