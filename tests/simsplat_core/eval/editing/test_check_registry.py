"""Every behaviour of the edit language has a benchmark motion check or a stated reason for none."""

from __future__ import annotations

from simsplat_core.editing.behaviours.registry import BEHAVIOURS, LABEL_CHECKED
from simsplat_core.eval.editing.checks import MOTION_CHECKS, UNCHECKED


def test_every_behaviour_is_checked_or_says_why_not() -> None:
    checked = [name for name, _ in MOTION_CHECKS]
    assert len(set(checked)) == len(checked)
    assert not set(checked) & set(UNCHECKED)
    assert set(checked) | set(UNCHECKED) == {b.name for b in BEHAVIOURS}
    assert {b.name for b in LABEL_CHECKED} <= set(checked)
