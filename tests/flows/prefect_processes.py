"""Prefect's own processes for tests: a ``prefect server start`` on a free port with its own home and SQLite
database, the Prefect CLI run against it, and a record of every process they start, so a test can end them all and
check that none is left.

Every process is started in a session of its own (``start_new_session``): ending the server ends its process group,
and what a process leaves running after its parent exits is still found by its session id.
"""

from __future__ import annotations

import contextlib
import os
import signal
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path

from flows.lifetime import ProcessKey, descendants, end_processes, process_table

REPO = Path(__file__).resolve().parents[2]
#: The Prefect CLI of this interpreter.
PREFECT = (sys.executable, "-m", "prefect")
#: Settings that would point a child at another API, profile or Ray cluster than the test's.
FOREIGN_SETTINGS = ("PREFECT_API_URL", "PREFECT_API_KEY", "PREFECT_PROFILE", "PREFECT_PROFILES_PATH", "RAY_ADDRESS")


def free_port() -> int:
    """A TCP port on 127.0.0.1 that nothing listens on right now."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def log_tail(path: Path, lines: int = 60) -> str:
    """The last ``lines`` lines of the log at ``path`` ("" when there is none)."""
    with contextlib.suppress(OSError):
        return "\n".join(path.read_text(errors="replace").splitlines()[-lines:])
    return ""


def _session_of(pid: int) -> int | None:
    """The session id of ``pid`` (``None`` when it has exited)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    return int(stat[stat.rindex(")") + 2:].split()[3])


@dataclass
class ProcessRecord:
    """Every process started for a test: the ones it starts itself (``roots``) and, each time ``scan`` is called,
    what they have started (``descendants``)."""

    roots: list[subprocess.Popen] = field(default_factory=list)
    root_keys: set[ProcessKey] = field(default_factory=set)
    descendants: set[ProcessKey] = field(default_factory=set)

    def scan(self) -> None:
        """Record what the roots have started and runs now (a flow-run process while it runs, say)."""
        table = process_table()
        self.descendants |= descendants([p.pid for p in self.roots], table)
        self.root_keys |= {(p.pid, table[p.pid][1]) for p in self.roots if p.pid in table}

    def running(self) -> set[int]:
        """The recorded processes still running as the same process, and any process left in a root's session."""
        table = process_table()
        sessions = {p.pid for p in self.roots}
        alive = {pid for pid, start in self.root_keys | self.descendants if pid in table and table[pid][1] == start}
        return alive | {pid for pid in table if _session_of(pid) in sessions}

    def end_all(self, grace_s: float = 10.0) -> None:
        """SIGTERM every running recorded process (and what it started), SIGKILL what is left after ``grace_s``."""
        table = process_table()
        end_processes({(pid, table[pid][1]) for pid in self.running() if pid in table}, grace_s)
        for process in self.roots:
            with contextlib.suppress(subprocess.TimeoutExpired):
                process.wait(timeout=grace_s)


@dataclass(frozen=True)
class PrefectServer:
    """A running ``prefect server start``.

    Attributes:
        url: its API, ``http://127.0.0.1:<port>/api``.
        home: its ``PREFECT_HOME`` (the SQLite database and the logs of the processes started against it).
        env: the environment of a Prefect client of this server (CLI, worker), without the test's own settings.
        processes: what was started for it so far.
    """

    url: str
    home: Path
    env: Mapping[str, str]
    processes: ProcessRecord

    def start(self, args: list[str], log_name: str, env: Mapping[str, str] | None = None,
              cwd: Path = REPO) -> subprocess.Popen:
        """Start ``prefect ARGS...`` against this server (``env`` added to its environment), output in
        ``home/<log_name>``; recorded in ``processes``."""
        log = (self.home / log_name).open("w")
        process = subprocess.Popen([*PREFECT, *args], env={**self.env, **(env or {})}, cwd=cwd, stdout=log,
                                   stderr=subprocess.STDOUT, start_new_session=True)
        log.close()
        self.processes.roots.append(process)
        return process

    def cli(self, args: list[str], log_name: str, timeout_s: float, env: Mapping[str, str] | None = None) -> int:
        """Run ``prefect ARGS...`` to its end; its exit code (output in ``home/<log_name>``)."""
        process = self.start(args, log_name, env)
        try:
            return process.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            raise AssertionError(f"prefect {' '.join(args)} did not finish in {timeout_s} s:\n"
                                 f"{log_tail(self.home / log_name)}") from None


def client_env(home: Path, url: str = "") -> dict[str, str]:
    """This process's environment with Prefect pointed at ``home`` (and at the API ``url`` when given), the
    repository first on ``PYTHONPATH``, and nothing pointing at the test's own Prefect API or Ray cluster."""
    env = {k: v for k, v in os.environ.items() if k not in FOREIGN_SETTINGS}
    env |= {
        "PREFECT_HOME": str(home),
        "PREFECT_API_DATABASE_CONNECTION_URL": f"sqlite+aiosqlite:///{home / 'prefect.db'}",
        "PREFECT_SERVER_ANALYTICS_ENABLED": "false",
        "PYTHONPATH": os.pathsep.join(p for p in (str(REPO), os.environ.get("PYTHONPATH", "")) if p),
        "RAY_AUTH_MODE": "disabled",
        "SIMSPLAT_PROGRESS": "0",
    }
    if url:
        env["PREFECT_API_URL"] = url
    return env


def _wait_for_health(url: str, server: subprocess.Popen, log: Path, timeout_s: float) -> None:
    deadline = time.monotonic() + timeout_s
    while True:
        with contextlib.suppress(urllib.error.URLError, OSError):
            with urllib.request.urlopen(f"{url}/health", timeout=5) as response:
                if response.status == 200:
                    return
        if server.poll() is not None:
            raise AssertionError(f"prefect server exited ({server.returncode}) before it answered:\n{log_tail(log)}")
        if time.monotonic() > deadline:
            raise AssertionError(f"prefect server did not answer {url}/health in {timeout_s} s:\n{log_tail(log)}")
        time.sleep(0.5)


@contextlib.contextmanager
def prefect_server(home: Path, timeout_s: float = 600.0) -> Iterator[PrefectServer]:
    """``prefect server start`` on a free port of 127.0.0.1 with ``home`` as its ``PREFECT_HOME`` and a new SQLite
    database there, ready (``/api/health`` answers) when the block starts; at its end every process started against
    it is ended (the server's process group first). The scheduler service is off (runs are created by the test
    only) and block types are not registered (no block is used).

    Args:
        timeout_s: how long the server may take to answer (a new database is migrated first).
    """
    home.mkdir(parents=True, exist_ok=True)
    port = free_port()
    url = f"http://127.0.0.1:{port}/api"
    server_env = client_env(home) | {"PREFECT_SERVER_SERVICES_SCHEDULER_ENABLED": "false",
                                     "PREFECT_API_BLOCKS_REGISTER_ON_START": "false"}
    served = PrefectServer(url, home, client_env(home, url), ProcessRecord())
    server = served.start(["server", "start", "--host", "127.0.0.1", "--port", str(port)], "server.log",
                          env=server_env, cwd=home)
    try:
        _wait_for_health(url, server, home / "server.log", timeout_s)
        served.processes.scan()
        yield served
    finally:
        served.processes.scan()
        with contextlib.suppress(ProcessLookupError):
            os.killpg(server.pid, signal.SIGTERM)
        with contextlib.suppress(subprocess.TimeoutExpired):
            server.wait(timeout=30)
        served.processes.end_all()
