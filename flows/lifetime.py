"""Tie the lifetime of a run's child processes to the run: nothing outlives a driver killed with SIGKILL.

A run starts long-lived helpers: the temporary Prefect API server (``flows.runtime.prefect_api``) and a local Ray
cluster (gcs_server, raylet, the dashboard and runtime-env agents, workers). When the driver exits normally they are
stopped in order; when it is killed outright (SIGKILL, the OOM killer) they are reparented to init and live on.

``children_die_with_this_process()`` starts a small watchdog process for the duration of a block. The watchdog
records, every ``poll_s`` seconds, every descendant of the driver (by ``/proc``, so helpers that are later
reparented stay known, and only this driver's processes are ever touched: other Ray clusters on the machine are
not). When the driver dies (its stdin pipe closes, or it is reparented) it terminates the recorded processes that
are still the same processes (pid and start time), plus their own descendants: SIGTERM, then SIGKILL after
``grace_s``. Leaving the block tells the watchdog to exit without touching anything.
A process that is started and reparented within one poll (a double fork) escapes unless the driver calls
``Watchdog.record_now()`` in between; Ray's processes stay under the driver or the raylet while they run.

Linux only (``/proc``); elsewhere the block runs without a watchdog.

Run as ``python -m flows.lifetime PID POLL_S GRACE_S`` it is the watchdog itself (started by the context manager).
"""

from __future__ import annotations

import contextlib
import logging
import os
import select
import signal
import subprocess
import sys
import time
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path

logger = logging.getLogger(__name__)

PROC = Path("/proc")
# One-byte messages: driver -> watchdog on its stdin, watchdog -> driver on its stdout.
STOP = b"q"  # the block ended normally: exit without touching anything
SCAN = b"s"  # record the descendants now and answer ACK
ACK = b"k"
DIED = b""  # what reading the stdin of a watchdog whose driver died gives

ProcessKey = tuple[int, int]  # (pid, start time in clock ticks since boot): a pid reused later is another process


def supported() -> bool:
    """Whether this platform has what the watchdog reads (Linux ``/proc``)."""
    return sys.platform.startswith("linux") and (PROC / "self" / "stat").exists()


@dataclass(frozen=True)
class Watchdog:
    """The driver's end of a running watchdog process (see the module docstring)."""

    process: subprocess.Popen

    def record_now(self, timeout_s: float = 30.0) -> None:
        """Block until the watchdog has recorded every descendant started so far (e.g. right after starting one
        that will soon daemonise)."""
        self._send(SCAN)
        self._await_ack(timeout_s)

    def stop(self, timeout_s: float = 10.0) -> None:
        """End the watchdog without it touching any process; kill it if it does not exit within ``timeout_s``."""
        try:
            self._send(STOP)
            assert self.process.stdin is not None
            self.process.stdin.close()
            self.process.wait(timeout=timeout_s)
        except (OSError, subprocess.TimeoutExpired):  # pragma: no cover - it died or hangs: do not leave it behind
            self.process.kill()
            self.process.wait()

    def _send(self, message: bytes) -> None:
        assert self.process.stdin is not None
        self.process.stdin.write(message)
        self.process.stdin.flush()

    def _await_ack(self, timeout_s: float) -> None:
        assert self.process.stdout is not None
        fd = self.process.stdout.fileno()
        readable, _, _ = select.select([fd], [], [], timeout_s)
        if not readable or os.read(fd, 1) != ACK:
            raise RuntimeError(f"the child-process watchdog (pid {self.process.pid}) did not answer in {timeout_s} s")


@contextlib.contextmanager
def children_die_with_this_process(poll_s: float = 0.5, grace_s: float = 3.0) -> Iterator[Watchdog | None]:
    """Within the block, every process this one starts (and what those start) is ended if this process dies.

    Yields the running ``Watchdog`` once it has made its first scan, or None where the platform has no ``/proc``.

    Args:
        poll_s: seconds between two scans of this process's descendants.
        grace_s: seconds between SIGTERM and SIGKILL when cleaning up after this process's death.
    """
    if not supported():
        logger.debug("no /proc: child processes are not tied to this process's lifetime")
        yield None
        return
    watchdog = Watchdog(subprocess.Popen(
        [sys.executable, "-m", __name__, str(os.getpid()), str(poll_s), str(grace_s)],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE,
        start_new_session=True,  # out of reach of signals sent to the driver's process group
    ))
    try:
        watchdog._await_ack(timeout_s=60.0)
        yield watchdog
    finally:
        watchdog.stop()


def process_table() -> dict[int, tuple[int, int]]:
    """Every running process (zombies left out) as ``{pid: (parent pid, start time)}``, read from
    ``/proc/<pid>/stat``; start times are in clock ticks since boot."""
    table: dict[int, tuple[int, int]] = {}
    for entry in PROC.iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:  # exited while scanning
            continue
        fields = stat[stat.rindex(")") + 2:].split()  # after "pid (comm) ", whose comm may hold spaces
        if fields[0] == "Z":  # exited, waiting to be reaped
            continue
        table[int(entry.name)] = (int(fields[1]), int(fields[19]))
    return table


def descendants(roots: Iterable[int], table: dict[int, tuple[int, int]]) -> set[ProcessKey]:
    """The processes of ``table`` below any of ``roots`` (not the roots themselves), as (pid, start time)."""
    children: dict[int, list[int]] = {}
    for pid, (ppid, _) in table.items():
        children.setdefault(ppid, []).append(pid)
    found: set[ProcessKey] = set()
    stack = list(roots)
    while stack:
        for child in children.get(stack.pop(), ()):
            key = (child, table[child][1])
            if key not in found:
                found.add(key)
                stack.append(child)
    return found


def _alive(keys: Iterable[ProcessKey], table: dict[int, tuple[int, int]]) -> set[ProcessKey]:
    """Those of ``keys`` that still run as the same process (pid present with the recorded start time)."""
    return {(pid, start) for pid, start in keys if pid in table and table[pid][1] == start}


def _signal_all(keys: Iterable[ProcessKey], signum: signal.Signals) -> None:
    for pid, _ in keys:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.kill(pid, signum)


def end_processes(recorded: set[ProcessKey], grace_s: float) -> None:
    """SIGTERM the still-running ``recorded`` processes and their descendants; SIGKILL what remains after
    ``grace_s`` seconds."""
    table = process_table()
    targets = _alive(recorded, table)
    targets |= descendants([pid for pid, _ in targets], table)
    if not targets:
        return
    _signal_all(targets, signal.SIGTERM)
    deadline = time.monotonic() + grace_s
    while targets and time.monotonic() < deadline:
        time.sleep(0.1)
        targets = _alive(targets, process_table())
    _signal_all(targets, signal.SIGKILL)


def _next_message(parent: int, stdin_fd: int, poll_s: float) -> bytes | None:
    """Wait up to ``poll_s`` for news of ``parent``: a message byte, ``DIED``, or None when there is none yet."""
    if os.getppid() != parent:  # reparented: the driver is gone
        return DIED
    readable, _, _ = select.select([stdin_fd], [], [], poll_s)
    if not readable:
        return None
    return os.read(stdin_fd, 1) or DIED  # EOF: the driver died without saying goodbye


def watch(parent: int, poll_s: float, grace_s: float) -> None:
    """The watchdog's loop: record ``parent``'s descendants until it ends the block (return) or dies (clean up).

    Answers ``ACK`` on stdout after its first scan and after each ``SCAN`` request.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # a Ctrl-C meant for the driver must not take the watchdog first
    me = os.getpid()
    recorded: set[ProcessKey] = set()
    stdin_fd, stdout_fd = sys.stdin.fileno(), sys.stdout.fileno()
    message: bytes | None = SCAN
    while message != STOP:
        recorded |= {key for key in descendants([parent], process_table()) if key[0] != me}
        if message == SCAN:
            with contextlib.suppress(OSError):
                os.write(stdout_fd, ACK)
        elif message == DIED:
            end_processes(recorded, grace_s)
            return
        message = _next_message(parent, stdin_fd, poll_s)


if __name__ == "__main__":
    watch(int(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3]))
