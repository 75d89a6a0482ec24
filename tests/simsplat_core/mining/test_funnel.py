"""The mining funnel read from edits-table rows: the stage each kind of attempt reaches, the failure classes of
each reason grammar (validation text as ``AgentValidation.failures`` writes it), and per-category counts."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest

from simsplat_core.eval.mining_funnel import FUNNEL_STAGES, failure_classes, funnel_rows, stage_reached
from simsplat_core.mining.loop import rejection_reason
from simsplat_core.mining.vlm_protocol import Judgement
from simsplat_core.scenario.metrics import AgentValidation, ValidationReport


def _row(scenario: int, status: str, reason: str = "", *, program: str = "{}", category: str = "remove",
         judged: bool = False, seq: str = "s") -> dict[str, Any]:
    return {"seq_id": seq, "edit_id": f"e{scenario}", "scenario": scenario, "mining_status": status,
            "failure_reason": reason, "command_json": program, "category": category,
            "follows_prompt": True if judged else None, "plausibility": 4 if judged else None}


@dataclass(frozen=True)
class _Edited:
    """What ``rejection_reason`` reads of an edited scene: its validation."""

    validation: ValidationReport


def _rejection(agent: AgentValidation, verdict: Judgement) -> str:
    edited = _Edited(ValidationReport(agents=(agent,), frame_idx=np.arange(10)))
    return rejection_reason(edited, verdict, min_plausibility=3)  # type: ignore[arg-type]


COLLIDES = AgentValidation("car_1", "vehicle", "edited", collision_vehicle=True, collision_step=3,
                           collision_with="car_2")
GOOD = Judgement(True, 4, ("looks right",))
POOR = Judgement(False, 2, ("the car is not there",))


@pytest.mark.parametrize(("row", "stage"), [
    (_row(0, "failed", "vlm_error: propose: VLMError: timeout", program=""), "proposed"),
    (_row(0, "failed", "vlm_error: command: VLMError: bad JSON", program=""), "proposed"),
    (_row(0, "refused", "unsupported: flying cars", program=""), "proposed"),
    (_row(0, "refused", "not_found: command 1: no red bus"), "proposed"),
    (_row(0, "refused", "no_asset: command 1: no tram in the bank"), "grounded"),
    (_row(0, "failed", "vlm_error: judge: VLMError: timeout"), "edited"),
    (_row(0, "rejected", _rejection(COLLIDES, GOOD), judged=True), "edited"),
    (_row(0, "rejected", _rejection(AgentValidation("car_1", "vehicle", "edited"), POOR), judged=True), "judged"),
    (_row(0, "failed", "error: OSError: disk full", judged=True), "judged"),
    (_row(0, "accepted", judged=True), "accepted"),
])
def test_each_attempt_stops_at_its_stage(row: dict[str, Any], stage: str) -> None:
    assert stage_reached(row) == stage


def test_failure_classes_follow_the_reason_grammar() -> None:
    assert failure_classes("") == ()
    assert failure_classes("no_asset: command 1: no tram") == ("no_asset",)
    assert failure_classes("vlm_error: judge: VLMError: timeout") == ("vlm_error: judge",)
    assert failure_classes(_rejection(COLLIDES, GOOD)) == ("rejected: collision",)
    offroad = AgentValidation("car_1", "vehicle", "edited", offroad=True, offroad_step=4, kinematic=True,
                              kinematic_step=2, kinematic_detail="acceleration 12 m/s^2 > 10")
    assert failure_classes(_rejection(offroad, POOR)) == (
        "rejected: offroad", "rejected: kinematic", "rejected: does not follow the prompt", "rejected: implausible")
    ok = AgentValidation("car_1", "vehicle", "edited")
    assert failure_classes(_rejection(ok, Judgement(True, 2, ("odd",)))) == ("rejected: implausible",)


def test_funnel_counts_proposals_by_their_furthest_attempt() -> None:
    rows = [
        _row(0, "rejected", _rejection(COLLIDES, GOOD), judged=True), _row(0, "accepted", judged=True),
        _row(1, "refused", "no_asset: command 1: none", category="add_vehicle"),
        _row(2, "refused", "not_found: command 1: none"),
        _row(3, "failed", "vlm_error: propose: VLMError: x", program="", category=""),
    ]
    funnel = {r.category: r for r in funnel_rows(rows)}
    assert list(funnel) == ["add_vehicle", "remove", "unknown", "total"]
    assert funnel["remove"].proposals == (2, 1, 1, 1, 1, 1)
    assert funnel["remove"].attempts == (3, 2, 2, 1, 1, 1)
    assert funnel["add_vehicle"].proposals == (1, 1, 0, 0, 0, 0)
    assert funnel["unknown"].proposals == (1, 0, 0, 0, 0, 0)
    total = funnel["total"]
    assert total.proposals[0] == 4 and total.proposals[FUNNEL_STAGES.index("accepted")] == 1
    assert total.attempts[0] == len(rows)
    assert all(a >= b for a, b in zip(total.proposals, total.proposals[1:]))  # a funnel only narrows


def test_rows_without_mining_columns_are_refused() -> None:
    with pytest.raises(ValueError, match="no mining columns"):
        funnel_rows([{"seq_id": "s", "edit_id": "e9", "scenario": None, "mining_status": None}])
