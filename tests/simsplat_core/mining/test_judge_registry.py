"""Every behaviour of the edit language has a change check of the rule judge or a stated reason for none, every
behaviour checked on the auto-labeller's class has a suggestion for when it does not show, and every proposal kind a
behaviour declares has a proposal planner."""

from __future__ import annotations

from simsplat_core.editing.behaviours.registry import BEHAVIOURS, LABEL_CHECKED, PROPOSAL_FORMS
from simsplat_core.mining.rule_judge import CHANGE_CHECKS, LABEL_SUGGESTIONS, UNCHECKED
from simsplat_core.mining.rule_proposals import KINDS


def test_every_behaviour_is_checked_or_says_why_not() -> None:
    checked = [name for name, _ in CHANGE_CHECKS if name != "labels"]
    assert len(set(checked)) == len(checked)
    assert not set(checked) & set(UNCHECKED)
    assert set(checked) | set(UNCHECKED) == {b.name for b in BEHAVIOURS}


def test_every_label_checked_behaviour_has_a_suggestion() -> None:
    assert set(LABEL_SUGGESTIONS) == {b.name for b in LABEL_CHECKED}


def test_every_declared_proposal_kind_has_a_planner() -> None:
    """A behaviour's ``proposal_forms`` kind is proposed by the ``KINDS`` entry of that name (static: no scene)."""
    names = [k.name for k in KINDS]
    assert len(set(names)) == len(names)
    assert set(PROPOSAL_FORMS) <= set(names), sorted(set(PROPOSAL_FORMS) - set(names))
