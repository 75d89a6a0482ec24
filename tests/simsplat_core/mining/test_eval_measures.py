"""The mining measures (``simsplat_core.eval.mining``): proposals from edits-table rows, the Table 5 analogue and its
by-category table, the stages table, and the independent re-check of a stored scenario's trajectories; the editor's
timed stages (``EditedScene.seconds``, ``StageClock``)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pyarrow as pa
import pytest

from simsplat_core.editing.apply import Editor
from simsplat_core.editing.draft import EditContext
from simsplat_core.editing.result import EDIT_STAGES
from simsplat_core.eval.mining import (
    MINING_STAGES,
    UNKNOWN_CATEGORY,
    collides_or_offroad,
    mining_by_category_table,
    mining_stages_table,
    mining_table,
    proposal_outcomes,
    states_from_trajectories,
    stored_failure,
)
from simsplat_core.mining.rule_proposals import EDIT_CATEGORIES
from simsplat_core.scenario.agents import EGO_ID
from simsplat_core.stage_clock import StageClock
from storage.edits import trajectories_table


def _row(seq: str, scenario: int, status: str, category: str = "remove", plausibility: int | None = None,
         edit_id: str = "") -> dict:
    return {"seq_id": seq, "edit_id": edit_id or f"{seq}-{scenario}", "scenario": scenario, "category": category,
            "mining_status": status, "plausibility": plausibility}


ROWS = [
    _row("s0", 0, "rejected", "add_vehicle", 2), _row("s0", 0, "accepted", "add_vehicle", 4),  # accepted at 2
    _row("s0", 1, "refused", ""),  # refused before any program: category unknown
    _row("s0", 2, "accepted", "remove", 3),  # accepted at 1
    _row("s1", 0, "rejected", "modify_pedestrian", 2), _row("s1", 0, "rejected", "modify_pedestrian", 2),
    _row("s1", 0, "rejected", "modify_pedestrian", 1),  # three attempts, not accepted
    _row("s1", 1, "accepted", "remove", 4, edit_id="s1-1"),  # accepted at 1, fails on re-check
]


def test_table5_measures_from_the_edits_rows() -> None:
    outcomes = proposal_outcomes("rule", ROWS)
    assert [(o.seq_id, o.scenario, o.attempts, o.accepted) for o in outcomes] == [
        ("s0", 0, 2, True), ("s0", 1, 1, False), ("s0", 2, 1, True), ("s1", 0, 3, False), ("s1", 1, 1, True)]
    assert outcomes[1].category == UNKNOWN_CATEGORY and outcomes[0].plausibility == 4
    failures = {("rule", "s0", "s0-0"): False, ("rule", "s0", "s0-2"): False, ("rule", "s1", "s1-1"): True}
    table = mining_table(outcomes, failures, {"rule": "", "openai": "not run: no VLM endpoint configured"})
    rule, openai = table.to_pylist()
    assert (rule["prompts"], rule["accepted"], rule["accepted_with_failure"], rule["sequences"]) == (5, 3, 1, 2)
    assert rule["completion"] == pytest.approx(3 / 5) and rule["attempts_mean"] == pytest.approx(4 / 3)
    assert rule["plausibility_mean"] == pytest.approx(11 / 3) and rule["ran"] and rule["note"] == ""
    assert not openai["ran"] and openai["prompts"] == 0 and math.isnan(openai["completion"])
    assert openai["note"].startswith("not run")
    with pytest.raises(KeyError, match="s1-1"):  # every accepted scenario must have been re-checked
        mining_table(outcomes, {k: v for k, v in failures.items() if k[2] != "s1-1"}, {"rule": ""})
    with pytest.raises(ValueError, match="no mining columns"):
        proposal_outcomes("rule", [{"seq_id": "s0", "edit_id": "e", "scenario": None, "mining_status": ""}])


def test_acceptance_by_category_lists_every_category_and_a_total() -> None:
    rows = mining_by_category_table(proposal_outcomes("rule", ROWS), ["rule", "openai"]).to_pylist()
    by = {r["category"]: r for r in rows if r["client"] == "rule"}
    assert list(by) == [*EDIT_CATEGORIES, UNKNOWN_CATEGORY, "total"]
    assert (by["remove"]["prompts"], by["remove"]["accepted"], by["remove"]["completion"]) == (2, 2, 1.0)
    assert by["modify_pedestrian"]["completion"] == 0.0 and math.isnan(by["modify_pedestrian"]["attempts_mean"])
    assert by["add_static"]["prompts"] == 0 and math.isnan(by["add_static"]["completion"])
    assert (by["total"]["prompts"], by["total"]["accepted"]) == (5, 3)
    assert [r["category"] for r in rows if r["client"] == "openai"] == ["total"]  # proposed nothing


def test_stages_table_shares_and_throughput() -> None:
    seconds = {stage: 1.0 for stage in MINING_STAGES} | {"render": 26.0}
    rows = mining_stages_table({"rule": seconds}, {"rule": 3}, cores=2).to_pylist()
    assert [r["stage"] for r in rows] == [*MINING_STAGES, "total"]
    total, expected = rows[-1], len(MINING_STAGES) - 1 + 26.0
    assert total["seconds"] == pytest.approx(expected) and sum(r["share"] for r in rows[:-1]) == pytest.approx(1.0)
    assert total["accepted_per_hour_per_core"] == pytest.approx(3 / (expected / 3600 * 2))
    assert rows[MINING_STAGES.index("render")]["seconds_per_accepted"] == pytest.approx(26.0 / 3)
    with pytest.raises(ValueError, match="cores"):
        mining_stages_table({"rule": seconds}, {"rule": 3}, cores=0)


def test_the_recheck_reads_the_stored_trajectories(ctx: EditContext) -> None:
    log = ctx.states
    table = trajectories_table("e0", log)
    back = states_from_trajectories(table, log)
    assert back.object_ids == log.object_ids and np.array_equal(back.valid, log.valid)
    assert np.allclose(back.xy[back.valid], log.xy[log.valid], atol=1e-4)
    assert np.allclose(back.size, log.size)
    assert not collides_or_offroad(stored_failure(table, log, {}, ctx.map_ctx))  # the log itself: no failure

    # a stored scenario where a vehicle drives into the ego: the re-check sees the collision
    car = next(k for k, c in enumerate(log.categories) if c == "vehicle" and log.object_ids[k] != EGO_ID)
    ego = log.index(EGO_ID)
    xy = log.xy.copy()
    both = log.valid[car] & log.valid[ego]
    xy[car, both] = log.xy[ego, both] + np.array([0.5, 0.0])
    crashed = dataclasses.replace(log, xy=xy, sources=tuple("edited" if k == car else s
                                                            for k, s in enumerate(log.sources)))
    failure = stored_failure(trajectories_table("e1", crashed), log, {}, ctx.map_ctx)
    assert collides_or_offroad(failure) and log.object_ids[car] in failure.failed_agents

    # an inserted agent's box comes from the sizes given (its asset's), else the agent is named
    alone = trajectories_table("e2", crashed.take([car]))
    renamed = alone.set_column(alone.schema.get_field_index("object_id"), "object_id",
                               pa.array(["new_car"] * alone.num_rows, pa.string()))
    with pytest.raises(ValueError, match="new_car"):
        states_from_trajectories(renamed, log)
    sized = states_from_trajectories(renamed, log, {"new_car": (4.0, 2.0, 1.5)})
    assert np.allclose(sized.size[0], (4.0, 2.0, 1.5))


def test_stage_clock_counts_nested_stages_once(monkeypatch: pytest.MonkeyPatch) -> None:
    ticks = iter([0.0, 2.0, 5.0, 6.0, 10.0, 10.5])  # outer 0..6 with inner 2..5; outer again 10..10.5
    monkeypatch.setattr("simsplat_core.stage_clock.time.perf_counter", lambda: next(ticks))
    clock = StageClock()
    with clock.stage("outer"):
        with clock.stage("inner"):
            pass
    with clock.stage("outer"):
        pass
    assert clock.seconds == {"inner": 3.0, "outer": 3.5}


def test_an_edit_reports_the_seconds_of_its_stages(ctx: EditContext) -> None:
    edited = Editor(ctx).edit("Remove the white van.")
    assert set(edited.seconds) == set(EDIT_STAGES) and all(v >= 0.0 for v in edited.seconds.values())
    assert edited.seconds["ground"] > 0.0 and edited.seconds["validate"] > 0.0
