"""How many CPU threads the numeric libraries use in this process.

torch (intra-op OpenMP pool) and numba (its own OpenMP-backed ``prange`` pool) each default to one
thread per core of the machine. Two tasks running side by side — two Ray workers, or two threads of a
thread-pool runner — would then run 2 x 2 x cores spinning threads on ``cores`` cores, and OpenMP's
busy-waiting makes that several times slower than running them one after the other (measured on the
2-core machine: 0.36 s per reconstruction step alone, several seconds per step oversubscribed).
Whoever schedules tasks decides each one's share and calls :func:`set_compute_threads`; an algorithm
that wants a thread count of its own for one call uses :func:`compute_threads_limited`, which restores
the previous counts on exit, so no call leaves the process setting changed.
"""

from __future__ import annotations

import contextlib
import logging
from collections.abc import Iterator
from dataclasses import dataclass

import torch

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class ComputeThreads:
    """Thread counts of the numeric libraries: ``torch`` intra-op and ``numba`` parallel loops."""

    torch: int
    numba: int


def compute_threads() -> ComputeThreads:
    """The current thread counts."""
    import numba  # noqa: PLC0415  # slow (JIT runtime): imported on use

    return ComputeThreads(torch=torch.get_num_threads(), numba=numba.get_num_threads())


def set_compute_threads(count: int) -> ComputeThreads:
    """Use ``count`` threads in torch and numba (numba is capped at its launch-time maximum,
    ``NUMBA_NUM_THREADS``); returns the previous counts.

    The setting is process-wide: callers running several tasks in one process must give them all the
    same share.

    Raises:
        ValueError: ``count`` is not a positive int.
    """
    import numba  # noqa: PLC0415  # slow (JIT runtime): imported on use

    if not isinstance(count, int) or count < 1:
        raise ValueError(f"set_compute_threads: count must be a positive int, got {count!r}")
    previous = compute_threads()
    torch.set_num_threads(count)
    # numba.config sets its options at import time: its stubs do not declare them
    numba.set_num_threads(min(count, numba.config.NUMBA_NUM_THREADS))  # type: ignore[attr-defined]
    logger.debug("compute threads: torch %d -> %d, numba %d -> %d", previous.torch, count, previous.numba,
                 numba.get_num_threads())
    return previous


@contextlib.contextmanager
def compute_threads_limited(count: int | None) -> Iterator[ComputeThreads]:
    """Run the body with ``count`` torch/numba threads and restore the previous counts afterwards
    (also when the body raises). ``None`` leaves the setting as it is.

    Yields the counts in force inside the body. numba's count is per calling thread; torch's is
    process-wide, so two threads of one process must not use different counts at the same time.

    Raises:
        ValueError: ``count`` is neither ``None`` nor a positive int.
    """
    if count is None:
        yield compute_threads()
        return
    previous = set_compute_threads(count)
    try:
        yield compute_threads()
    finally:
        import numba  # noqa: PLC0415  # slow (JIT runtime): imported on use

        torch.set_num_threads(previous.torch)
        numba.set_num_threads(previous.numba)
