"""Step progress reported by tasks in this process drives one live bar per unit of work."""

from __future__ import annotations

import flows.progress
from flows.progress import StepBars
from tasks.progress import StepProgress


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
