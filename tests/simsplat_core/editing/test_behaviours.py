"""The behaviour registry: every behaviour's parser rule runs, once, in the declared order; label checks accept
exactly the motion classes their behaviour declares."""

from __future__ import annotations

import pytest

from simsplat_core.editing.behaviours.cross_street import CROSS_STREET
from simsplat_core.editing.behaviours.declaration import BehaviourDecl, Intent, LabelCheck
from simsplat_core.editing.behaviours.registry import (
    BEHAVIOURS,
    CLASS_INTENT,
    INTENT_FIELDS,
    LABEL_CHECKED,
    PARSE_ORDER,
    SPEED_ORDER,
)
from simsplat_core.editing.behaviours.turn import TURN
from simsplat_core.editing.parse.behaviour import parse_predicate
from simsplat_core.scenario import vocabulary as voc


def test_every_parse_rule_runs_once_and_jaywalking_is_read_by_the_crossing_rule() -> None:
    with_rule = [b.name for b in BEHAVIOURS if b.parse_rule is not None]
    assert sorted(b.name for b in PARSE_ORDER) == sorted(with_rule)
    assert [b.name for b in BEHAVIOURS if b.parse_rule is None] == ["jaywalk"]
    assert parse_predicate("jaywalk across the road", "pedestrian").fields == {"cross_street": True, "jaywalk": True}


def test_the_turn_rule_runs_before_the_speed_rule() -> None:
    order = [b.name for b in PARSE_ORDER]
    assert order.index("turn") < order.index("speed")
    parsed = parse_predicate("do not turn", "vehicle")
    assert parsed.fields == {"turn": "straight"} and parsed.refusal is None


@pytest.mark.parametrize("decl", LABEL_CHECKED, ids=lambda d: d.name)
def test_a_label_check_accepts_its_own_classes_and_rejects_the_others(decl: BehaviourDecl) -> None:
    check = decl.label_check
    assert check is not None
    for intent in decl.intents:
        fields = INTENT_FIELDS.get(intent.name)
        if fields is None or check.field not in fields:
            continue
        asked = fields[check.field]
        own = [c for c, i in decl.motion_classes.items() if i == intent.name]
        others = [c for c in CLASS_INTENT if c not in own]
        assert own and all(check.shows(asked, c) for c in own), (intent.name, own)
        if asked != "straight":  # going straight: any class but a turn (below)
            assert not any(check.shows(asked, c) for c in others), intent.name
        assert check.missing(asked)


def test_going_straight_is_any_class_but_a_turn() -> None:
    check = TURN.label_check
    assert check is not None
    assert check.shows("straight", voc.GOING_STRAIGHT) and check.shows("straight", voc.STOPPED)
    assert not check.shows("straight", voc.TURNING_LEFT) and check.missing("straight") == "asked to go straight"
    assert check.missing("left") == f"asked {voc.TURNING_LEFT}"
    cross = CROSS_STREET.label_check
    assert cross is not None and not cross.shows(True, voc.WALKING_ALONG)


def test_a_label_check_must_read_one_of_its_behaviours_fields() -> None:
    with pytest.raises(ValueError, match="label check reads 'turn'"):
        BehaviourDecl("u_turn", fields=("u_turn",), intents=(Intent("u_turn", fields={"u_turn": True}),),
                      label_check=LabelCheck("turn", lambda asked, motion: True, lambda asked: ""))


def test_speed_order_lists_every_speed_rule_once() -> None:
    with_rule = [b.name for b in BEHAVIOURS if b.speed_rule is not None]
    assert sorted(b.name for b in SPEED_ORDER) == sorted(with_rule)
    assert all(b.speed_rule is not None for b in SPEED_ORDER)
