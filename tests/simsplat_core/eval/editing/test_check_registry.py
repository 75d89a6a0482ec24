"""Every behaviour of the edit language has a benchmark motion check or a stated reason for none, and every prompt kind
a behaviour declares has a drafter (static: no scene)."""

from __future__ import annotations

from simsplat_core.editing.behaviours.registry import BEHAVIOURS, LABEL_CHECKED, PROMPT_FORMS
from simsplat_core.eval.editing.checks import MOTION_CHECKS, UNCHECKED
from simsplat_core.eval.editing.plans import (
    AGENT_DRAFTERS,
    INFEASIBLE_PEDESTRIAN_DRAFTERS,
    INFEASIBLE_VEHICLE_DRAFTERS,
    PEDESTRIAN_DRAFTERS,
    VEHICLE_DRAFTERS,
)
from simsplat_core.eval.editing.wording import FORMS


def test_every_behaviour_is_checked_or_says_why_not() -> None:
    checked = [name for name, _ in MOTION_CHECKS]
    assert len(set(checked)) == len(checked)
    assert not set(checked) & set(UNCHECKED)
    assert set(checked) | set(UNCHECKED) == {b.name for b in BEHAVIOURS}
    assert {b.name for b in LABEL_CHECKED} <= set(checked)


def test_every_declared_prompt_kind_has_one_drafter_with_sentence_forms() -> None:
    tables = (VEHICLE_DRAFTERS, PEDESTRIAN_DRAFTERS, INFEASIBLE_VEHICLE_DRAFTERS, INFEASIBLE_PEDESTRIAN_DRAFTERS)
    kinds = [kind for table in tables for kind, _ in table]
    assert len(set(kinds)) == len(kinds) and set(kinds) == set(AGENT_DRAFTERS)
    assert set(PROMPT_FORMS) <= set(AGENT_DRAFTERS), sorted(set(PROMPT_FORMS) - set(AGENT_DRAFTERS))
    assert set(AGENT_DRAFTERS) <= set(FORMS)  # the kinds no behaviour declares (replacing) are worded by the benchmark
