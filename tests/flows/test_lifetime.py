"""A process killed with SIGKILL leaves none of its children behind (``flows.lifetime``)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from flows.lifetime import descendants, process_table, supported

pytestmark = pytest.mark.skipif(not supported(), reason="the watchdog reads /proc (Linux)")

REPO = Path(__file__).resolve().parents[2]

# A driver with a plain child and a daemonised grandchild (its parent exits after the watchdog recorded it).
DUMMY_DRIVER = """
import json, subprocess, sys, time
from flows.lifetime import children_die_with_this_process

with children_die_with_this_process(poll_s=0.05, grace_s=1.0) as watchdog:
    child = subprocess.Popen(["sleep", "300"])
    parent = subprocess.Popen(["sh", "-c", "sleep 300 & echo $!; read line"],
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    daemon = int(parent.stdout.readline())
    watchdog.record_now()
    parent.stdin.close()
    parent.wait()  # the grandchild now belongs to init
    pids = {"child": child.pid, "daemon": daemon, "watchdog": watchdog.process.pid}
    with open(sys.argv[1] + ".tmp", "w") as f:
        json.dump(pids, f)
    import os
    os.replace(sys.argv[1] + ".tmp", sys.argv[1])
    if sys.argv[2] == "stay":
        time.sleep(300)
"""

# The helpers of a real run: the temporary Prefect API server and a local Ray cluster with one worker.
RUN_DRIVER = """
import os, sys, time
import ray
from flows.lifetime import children_die_with_this_process
from flows.runtime import RunnerKind, make_task_runner, prefect_api

def worker_pid():
    return os.getpid()

with children_die_with_this_process() as watchdog, prefect_api(), make_task_runner(RunnerKind.ray, 1):
    ray.get(ray.remote(worker_pid).remote())
    watchdog.record_now()
    with open(sys.argv[1], "w") as f:
        f.write("ready")
    time.sleep(600)
"""


def _start(tmp_path: Path, script: str, *args: str) -> tuple[subprocess.Popen, Path]:
    """Run ``script`` in a fresh interpreter; returns it and the path of the file it writes when ready."""
    (tmp_path / "driver.py").write_text(textwrap.dedent(script))
    ready = tmp_path / "ready"
    env = {k: v for k, v in os.environ.items() if k not in ("PREFECT_API_URL", "RAY_ADDRESS")}
    env["PYTHONPATH"] = os.pathsep.join([str(REPO), env.get("PYTHONPATH", "")])
    log = (tmp_path / "driver.log").open("w")
    driver = subprocess.Popen([sys.executable, str(tmp_path / "driver.py"), str(ready), *args],
                              stdout=log, stderr=subprocess.STDOUT, env=env, cwd=tmp_path)
    return driver, ready


def _wait_until_ready(driver: subprocess.Popen, ready: Path, timeout_s: float) -> None:
    deadline = time.monotonic() + timeout_s
    while not ready.exists():
        log = (ready.parent / "driver.log").read_text()
        assert driver.poll() is None, f"the driver exited ({driver.returncode}) before it was ready:\n{log}"
        assert time.monotonic() < deadline, f"the driver was not ready within {timeout_s} s:\n{log}"
        time.sleep(0.2)


def _running(pids: set[int], timeout_s: float) -> set[int]:
    """Those of ``pids`` still running once they have all ended or ``timeout_s`` has passed."""
    deadline = time.monotonic() + timeout_s
    while (left := pids & process_table().keys()) and time.monotonic() < deadline:
        time.sleep(0.2)
    return left


def _name(pid: int) -> str:
    """The command name of ``pid`` ("" when it has exited)."""
    try:
        return Path(f"/proc/{pid}/comm").read_text().strip()
    except OSError:
        return ""


def _kill(driver: subprocess.Popen) -> None:
    driver.send_signal(signal.SIGKILL)
    driver.wait()


def _end(pids: set[int]) -> None:
    """Clean up after a failed test: nothing started here may outlive it."""
    for pid in pids & process_table().keys():
        os.kill(pid, signal.SIGKILL)


def test_the_watchdog_ends_a_killed_drivers_children_even_daemonised(tmp_path):
    driver, ready = _start(tmp_path, DUMMY_DRIVER, "stay")
    try:
        _wait_until_ready(driver, ready, timeout_s=60)
        pids = set(json.loads(ready.read_text()).values())
        assert pids <= process_table().keys()
    finally:
        _kill(driver)
    survivors = _running(pids, timeout_s=30)
    _end(survivors)
    assert not survivors


def test_leaving_the_block_ends_the_watchdog_and_spares_the_children(tmp_path):
    driver, ready = _start(tmp_path, DUMMY_DRIVER, "leave")
    assert driver.wait(timeout=60) == 0, (tmp_path / "driver.log").read_text()
    pids = json.loads(ready.read_text())
    children = {pids["child"], pids["daemon"]}
    try:
        assert pids["watchdog"] not in process_table()
        assert children <= process_table().keys()
    finally:
        _end(children)


@pytest.mark.orchestration
def test_a_killed_run_leaves_no_prefect_server_or_ray_process_behind(tmp_path):
    driver, ready = _start(tmp_path, RUN_DRIVER)
    try:
        _wait_until_ready(driver, ready, timeout_s=240)
        pids = {pid for pid, _ in descendants([driver.pid], process_table())}
        names = {_name(pid) for pid in pids}
        assert {"raylet", "gcs_server"} <= names, names
    finally:
        _kill(driver)
    survivors = _running(pids, timeout_s=60)
    _end(survivors)
    assert not survivors
