"""Step progress reported by tasks drives one live bar per unit of work: reports made in this process through a
listener, those of other processes (Ray workers) relayed through a folder."""

from __future__ import annotations

import os
import subprocess
import sys

import flows.progress
from flows.progress import StepBars
from tasks.progress import RELAY_ENV, StepProgress


def test_step_bars_draw_one_bar_per_label_from_task_reports(monkeypatch):
    monkeypatch.setenv("SIMSPLAT_PROGRESS", "1")
    with StepBars() as bars:
        assert flows.progress._shared_bar is bars._bar is not None
        StepProgress("reconstruct a")(5, 10, {"psnr": 20.0})
        StepProgress("reconstruct b")(10, 10, {})
        shown = {t.description: (t.completed, t.total) for t in bars._bar.tasks}
    assert shown == {"reconstruct a psnr 20.00": (5, 10), "reconstruct b": (10, 10)}
    assert flows.progress._shared_bar is None
    StepProgress("after")(1, 1, {})  # no listener, no run context: a no-op


def test_step_bars_do_nothing_without_a_terminal(monkeypatch):
    monkeypatch.setenv("SIMSPLAT_PROGRESS", "0")
    with StepBars() as bars:
        StepProgress("x")(1, 2, {})
    assert bars._bar is None and flows.progress._shared_bar is None


def test_step_reports_are_relayed_through_a_folder_throttled(tmp_path, monkeypatch):
    from tasks.progress import StepReport, read_step_reports

    monkeypatch.setenv(RELAY_ENV, str(tmp_path))
    step = StepProgress("reconstruct a")
    step(3, 10, {"psnr": 21.0})
    step(4, 10, {"psnr": 21.5})  # within the relay interval: not written
    assert read_step_reports(str(tmp_path)) == [StepReport("reconstruct a", 3, 10, {"psnr": 21.0})]
    step(10, 10, {})  # the last step always is
    StepProgress("reconstruct b")(1, 5)
    assert read_step_reports(str(tmp_path)) == [StepReport("reconstruct a", 10, 10, {}),
                                                                StepReport("reconstruct b", 1, 5, {})]


def test_relayed_steps_pass_each_change_once():
    from flows.progress import RelayedSteps

    heard = []
    with RelayedSteps(lambda *report: heard.append(report), interval_s=60.0) as relay:
        StepProgress("x")(1, 2, {})  # this process inherits the folder too
        assert relay.poll() == 1 and relay.poll() == 0
        folder = relay.folder
    assert heard == [("x", 1, 2, {})]
    assert not os.path.exists(folder) and RELAY_ENV not in os.environ


def test_step_bars_draw_the_reports_of_another_process(monkeypatch):
    """What the Ray runner needs: a worker process (inheriting the environment) reports, the driver draws."""
    monkeypatch.setenv("SIMSPLAT_PROGRESS", "1")
    worker = "from tasks.progress import StepProgress; StepProgress('reconstruct w')(7, 20, {'psnr': 18.5})"
    with StepBars(relay=True) as bars:
        subprocess.run([sys.executable, "-c", worker], check=True, env=dict(os.environ), timeout=120)
        bars._relayed.poll()
        shown = {t.description: (t.completed, t.total) for t in bars._bar.tasks}
    assert shown == {"reconstruct w psnr 18.50": (7, 20)}
    assert RELAY_ENV not in os.environ


def test_without_a_terminal_progress_is_plain_lines_every_tenth(monkeypatch, capsys):
    monkeypatch.setenv("SIMSPLAT_PROGRESS", "lines")
    with StepBars() as bars:
        step = StepProgress("reconstruct a")
        for i in range(1, 101):
            step(i, 100, {"psnr": 20.0 + i / 100})
    assert bars._bar is None and not flows.progress._lines_active
    lines = capsys.readouterr().err.splitlines()
    assert lines[0] == "reconstruct a psnr 20.01: 1/100 (1 %)"
    assert [line.split(": ")[1] for line in lines[1:]] == [f"{10 * k}/100 ({10 * k} %)" for k in range(1, 11)]


def test_nested_step_bars_write_each_line_once(monkeypatch, capsys):
    monkeypatch.setenv("SIMSPLAT_PROGRESS", "lines")
    with StepBars(), StepBars(headline=""):
        StepProgress("x")(2, 2, {})
    assert capsys.readouterr().err.splitlines() == ["x: 2/2 (100 %)"]
