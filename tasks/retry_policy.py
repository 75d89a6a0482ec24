"""The pipeline stages' retry policy, declared once: how often and after how long a failed stage runs again.

Two kinds of failure are retried, each at most ``STAGE_RETRIES.retries`` times with growing delays
(``STAGE_RETRIES.delays()``, each varied by up to ``jitter`` so that stages failing together do not retry together):

* **a crashed worker** (the Ray worker process running the task was killed: the OOM killer, a lost node, SIGKILL).
  Prefect's own retries run inside the task engine in that process and die with it, so the flow resubmits the task
  (``tasks.run_record.StageRecorder``); Ray's own task retries are turned off for these tasks (``flows.runtime``) so
  that the flow's back-off and record apply;
* **a transient exception raised by the task** (``is_transient``: a connection or timeout error, an I/O error of the
  store that is not about space, permissions or a missing path), through Prefect's ``retries`` with
  ``retry_condition_fn``.

Everything else fails at once: a missing input, a bad configuration, a schema mismatch or a corrupt artifact (all
``ValueError``s), a full or read-only store, and bugs would fail the same way again. A retry is safe because every
stage skips work it already stored (content keys, completion markers) and commits its outputs atomically: it
recomputes at most the one stage of the one sequence that failed.

    @task(name="reconstruct-scene", cache_policy=NO_CACHE, **STAGE_RETRIES.task_options())
"""

from __future__ import annotations

import errno
import random
from dataclasses import dataclass
from typing import Any

from storage.errors import StoreNotWritableError

#: ``errno`` values of ``OSError``s that another attempt cannot get past: the store is full, read-only or forbidden,
#: or a path is missing or of the wrong kind.
PERMANENT_ERRNOS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EACCES, errno.EPERM, errno.ENOENT,
                              errno.ENOTDIR, errno.EISDIR, errno.ENAMETOOLONG})


def is_transient(exc: BaseException) -> bool:
    """Whether another attempt may succeed where ``exc`` failed: connection and timeout errors, and ``OSError``s
    whose ``errno`` is not one of ``PERMANENT_ERRNOS``. ``ValueError``s (a missing input, a bad configuration, a
    schema mismatch, a corrupt artifact), the store's ``StoreNotWritableError`` (its own wording of a full,
    read-only or forbidden store, which carries no ``errno``) and every other exception are not."""
    if isinstance(exc, ValueError | StoreNotWritableError):
        return False
    if isinstance(exc, ConnectionError | TimeoutError):
        return True
    return isinstance(exc, OSError) and exc.errno not in PERMANENT_ERRNOS


def retry_when_transient(task: Any, task_run: Any, state: Any) -> bool:
    """Prefect ``retry_condition_fn``: retry the failed ``state`` only when its exception ``is_transient``."""
    exc = state.result(raise_on_failure=False)
    return isinstance(exc, BaseException) and is_transient(exc)


@dataclass(frozen=True)
class RetryPolicy:
    """How often and after how long a failed stage is retried.

    Attributes:
        retries: attempts after the first, for each kind of failure (a crashed worker; a transient exception).
        first_delay_s: seconds before the first retry, s.
        backoff: factor by which each further delay grows.
        jitter: each delay is drawn from ``[d * (1 - jitter), d * (1 + jitter)]``.
    """

    retries: int = 2
    first_delay_s: float = 5.0
    backoff: float = 4.0
    jitter: float = 0.2

    def __post_init__(self) -> None:
        if self.retries < 0 or self.first_delay_s < 0 or self.backoff < 1 or not 0 <= self.jitter < 1:
            raise ValueError(f"retry policy needs retries >= 0, first_delay_s >= 0, backoff >= 1 and 0 <= jitter < 1,"
                             f" got {self}")

    def delays(self) -> list[float]:
        """The nominal delay before each retry, s (``[5.0, 20.0]`` by default)."""
        return [self.first_delay_s * self.backoff**i for i in range(self.retries)]

    def delay(self, retry: int, rng: random.Random | None = None) -> float:
        """The delay before retry ``retry`` (1-based), jittered, s."""
        nominal = self.delays()[retry - 1]
        return nominal * (rng or random).uniform(1 - self.jitter, 1 + self.jitter)

    def task_options(self) -> dict[str, Any]:
        """Keyword arguments of ``@task`` for retrying transient exceptions inside a task run."""
        return {"retries": self.retries, "retry_delay_seconds": self.delays(), "retry_jitter_factor": self.jitter,
                "retry_condition_fn": retry_when_transient}


#: The policy of every pipeline stage (ingest, reconstruct, align, asset bank, mine, evaluate, export).
STAGE_RETRIES = RetryPolicy()
