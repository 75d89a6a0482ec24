"""The mining loop on the editing tests' small synthetic scene: deterministic per seed with the rule-based client,
accepted scenarios always valid, a collision rejected and retried further away, refusals and VLM failures recorded
as attempts while the loop goes on, seed prompts first, retries bounded; the program adjustments; the edits rows.

The scene is an untrained random cloud: its renders are flat, so the rule-based judge's render and visibility checks
are relaxed here (:data:`RELAXED`); everything else it checks (grounding, the change asked, validation) is not."""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Sequence

import numpy as np
import pytest

from simsplat_core.editing.commands import AssetSpec, EditCommand, EditProgram
from simsplat_core.editing.draft import EditContext
from simsplat_core.editing.options import DEFAULT_OPTIONS
from simsplat_core.language.text import TextEncoder
from simsplat_core.mining import (
    EDIT_CATEGORIES,
    Judgement,
    JudgeRequest,
    MiningConfig,
    MiningResult,
    ParameterChange,
    ProposalRequest,
    RuleBasedVLMClient,
    SceneSummary,
    attempt_rows,
    judge_views,
    mine_sequence,
)
from simsplat_core.mining.adjust import MIN_LANE_GAP_M, adjust_program
from simsplat_core.mining.attempts import EDITS_COLUMNS, TIMED_STAGES, judge_reasons_of
from simsplat_core.mining.judge_input import targets_of
from simsplat_core.mining.rule_judge import JudgeConfig
from simsplat_core.mining.rule_proposals import Proposal
from simsplat_core.vlm.openai_chat import VLMError
from storage.schemas.edits import EDITS_SCHEMA

#: The judge without its render checks (module docstring).
RELAXED = JudgeConfig(blank_std=-1.0, hole_share=1.01, min_visible_pixels=0)
#: Small and quick: tiny judge views, two scenarios wanted.
CONFIG = MiningConfig(scenarios=2, judge_frames=2, judge_width=64, bev_size=96, min_visible_pixels=0)
#: Everyone but the edited agents replays the log (the ego drives through what is put on its path).
REPLAY = dataclasses.replace(DEFAULT_OPTIONS, refinement="none")
CONE_AHEAD = "Put a traffic cone 3 m ahead of the ego."
REMOVE_VAN = "Remove the white van."
SLOWER_SUV = "Make the blue SUV in the oncoming lane go 10 km/h slower."


class ScriptedClient:
    """Proposes fixed prompts, translates and judges with the rule-based client, or fails where told."""

    name = "scripted"

    def __init__(self, prompts: Sequence[str], inner: RuleBasedVLMClient, *, fail_at: str = "",
                 verdict: Judgement | None = None) -> None:
        self.prompts = list(prompts)
        self.inner = inner
        self.fail_at = fail_at
        self.verdict = verdict

    def _maybe_fail(self, stage: str) -> None:
        if self.fail_at == stage:
            raise VLMError(f"http://127.0.0.1:9/v1/chat/completions: no valid {stage} answer after 3 tries")

    def propose(self, request: ProposalRequest) -> list[str]:
        self._maybe_fail("propose")
        return self.prompts[:request.count]

    def to_command(self, prompt: str, summary: SceneSummary) -> EditProgram:
        self._maybe_fail("command")
        return self.inner.to_command(prompt, summary)

    def judge(self, request: JudgeRequest) -> Judgement:
        self._maybe_fail("judge")
        return self.verdict if self.verdict is not None else self.inner.judge(request)


@pytest.fixture(scope="module")
def rule_client(encoder: TextEncoder) -> RuleBasedVLMClient:
    return RuleBasedVLMClient(seed=0, encoder=encoder, judge_config=RELAXED)


@pytest.fixture(scope="module")
def mined(ctx: EditContext, rule_client: RuleBasedVLMClient) -> MiningResult:
    return mine_sequence(ctx, rule_client, CONFIG)


@pytest.fixture(scope="module")
def collided(ctx: EditContext, rule_client: RuleBasedVLMClient) -> MiningResult:
    config = dataclasses.replace(CONFIG, scenarios=1, options=REPLAY)
    return mine_sequence(ctx, ScriptedClient([CONE_AHEAD], rule_client), config)


def _program(record_json: str) -> EditProgram:
    return EditProgram.model_validate(json.loads(record_json))


# ---------------------------------------------------------------------------------------------- the loop
def test_the_rule_based_loop_is_deterministic_and_accepts_valid_scenarios(ctx: EditContext, mined: MiningResult,
                                                                          encoder: TextEncoder) -> None:
    nodes, agents = [n.node_id for n in ctx.graph.nodes], ctx.states.object_ids
    progress: list[tuple[int, int]] = []
    again = mine_sequence(ctx, RuleBasedVLMClient(seed=0, encoder=encoder, judge_config=RELAXED), CONFIG,
                          progress=lambda done, wanted: progress.append((done, wanted)))
    assert again == mined and again.records == mined.records  # timings and edited scenes are not compared
    assert 1 <= len(mined.accepted) <= CONFIG.scenarios and mined.client == "rule-based/1"
    assert len(progress) == len(again.records) and progress[-1] == (len(again.accepted), CONFIG.scenarios)
    for record in mined.records:
        assert record.category in EDIT_CATEGORIES and record.attempt >= 1 and set(record.seconds) == set(TIMED_STAGES)
        assert record.export == (record.status == "accepted")
        assert (record.edited is not None) == record.export
    for record in mined.accepted:
        assert record.edited is not None and record.edited.validation.ok and not record.failure_reason
        assert record.follows_prompt and record.plausibility is not None and record.plausibility >= 3
        assert record.edited.prompt == record.prompt and _program(record.program_json).commands
    assert [n.node_id for n in ctx.graph.nodes] == nodes and ctx.states.object_ids == agents  # stored scene as it was
    assert set(mined.seconds) == set(TIMED_STAGES) and mined.prompts[0] == mined.records[0].prompt


def test_a_collision_is_rejected_and_retried_with_the_object_further_away(collided: MiningResult) -> None:
    first, *retries = collided.records
    assert first.status == "rejected" and first.attempt == 1
    assert "validation:" in first.failure_reason and "collides" in first.failure_reason
    assert "'ego'" in first.failure_reason
    assert retries and retries[0].attempt == 2 and retries[0].scenario == first.scenario
    assert retries[0].edit_id == first.edit_id and "offset" in retries[0].adjustment
    before = _program(first.program_json).commands[0].placement
    after = _program(retries[0].program_json).commands[0].placement
    assert before is not None and after is not None and after.distance_m is not None
    assert before.distance_m is not None and after.distance_m > before.distance_m
    for record in collided.records:
        if record.status == "accepted":
            assert record.edited is not None and record.edited.validation.ok
        else:
            assert record.edited is None


def test_a_collision_is_rejected_whatever_the_judge_says(ctx: EditContext, rule_client: RuleBasedVLMClient) -> None:
    delighted = Judgement(True, 4, ("looks great",))  # no suggestions: the default change for a collision applies
    client = ScriptedClient([CONE_AHEAD], rule_client, verdict=delighted)
    result = mine_sequence(ctx, client, dataclasses.replace(CONFIG, scenarios=1, max_attempts=2, options=REPLAY))
    first = result.records[0]
    assert first.status == "rejected" and first.follows_prompt and first.plausibility == 4
    assert first.failure_reason.startswith("rejected: validation: ") and "collides" in first.failure_reason
    assert len(result.records) == 2 and result.records[1].adjustment == "command 1: offset 5 m further"
    assert all(r.edited is not None and r.edited.validation.ok for r in result.accepted)


def test_the_judge_sees_small_telling_frames_and_the_bev(ctx: EditContext, mined: MiningResult) -> None:
    edited = mined.accepted[0].edited
    assert edited is not None
    shown = judge_views(edited, ctx.log, frames=2, max_width=48, bev_size=80)
    assert 1 <= len(shown.renders) == len(shown.frames) == len(shown.cameras) <= 2
    assert all(r.dtype == np.uint8 and r.shape[1] <= 48 and r.shape[2] == 3 for r in shown.renders)
    assert shown.bev.shape == (80, 80, 3) and list(shown.frames) == sorted(shown.frames)
    present = {o for ids in targets_of(edited) for o in ids if o in edited.states.object_ids}
    assert set(shown.visible_pixels) == present


def test_a_refused_proposal_is_a_refused_row_and_the_loop_goes_on(ctx: EditContext,
                                                                  rule_client: RuleBasedVLMClient) -> None:
    client = ScriptedClient(["Paint the sky purple.", REMOVE_VAN], rule_client)
    result = mine_sequence(ctx, client, dataclasses.replace(CONFIG, scenarios=1))
    refused, removed = result.records
    assert refused.status == "refused" and refused.failure_reason.startswith("unsupported: ")
    assert refused.program_json == "" and refused.judgement is None and refused.attempt == 1
    assert removed.prompt == REMOVE_VAN and removed.status == "accepted" and removed.category == "remove"
    assert removed.scenario == refused.scenario + 1


def test_proposals_of_categories_not_selected_are_refused_unexecuted(ctx: EditContext,
                                                                    rule_client: RuleBasedVLMClient) -> None:
    # the cone's category comes from its command program (the scripted client does not say it), the seed's from
    # its proposer; only the removal is among the selected categories
    config = dataclasses.replace(CONFIG, scenarios=1, categories=("remove",))
    seeds = [Proposal(SLOWER_SUV, "modify_vehicle", "slow_down", False)]
    result = mine_sequence(ctx, ScriptedClient([CONE_AHEAD, REMOVE_VAN], rule_client), config, seed_prompts=seeds)
    slower, cone, removed = result.records
    for record, category in ((slower, "modify_vehicle"), (cone, "add_static")):
        assert record.status == "refused" and record.category == category and record.edited is None
        assert record.failure_reason == f"category_not_selected: {category} is not among ['remove']"
    assert slower.program_json == "" and cone.program_json != ""
    assert removed.prompt == REMOVE_VAN and removed.status == "accepted"
    with pytest.raises(ValueError, match="MiningConfig.categories: unknown edit category \\['add_truck'\\]"):
        MiningConfig(categories=("add_truck",))


@pytest.mark.parametrize("stage", ["command", "judge"])
def test_a_failing_vlm_is_a_failed_attempt_and_nothing_is_accepted(ctx: EditContext, rule_client: RuleBasedVLMClient,
                                                                   stage: str) -> None:
    client = ScriptedClient([REMOVE_VAN, CONE_AHEAD], rule_client, fail_at=stage)
    result = mine_sequence(ctx, client, CONFIG)
    assert [r.status for r in result.records] == ["failed", "failed"]  # one per proposal: the loop went on
    assert not result.accepted
    for record in result.records:
        assert record.failure_reason.startswith(f"vlm_error: {stage}: VLMError: ")
        assert "127.0.0.1" in record.failure_reason
        assert record.judgement is None and record.edited is None
        assert (record.program_json != "") == (stage == "judge")


def test_seed_prompts_come_first_and_a_failed_proposal_call_is_recorded(ctx: EditContext,
                                                                         rule_client: RuleBasedVLMClient) -> None:
    seeds = [Proposal(REMOVE_VAN, "remove", "remove", False), "  remove the WHITE van. "]  # the second: a repeat
    client = ScriptedClient([CONE_AHEAD], rule_client, fail_at="propose")
    result = mine_sequence(ctx, client, CONFIG, seed_prompts=seeds)
    seeded, failed = result.records
    assert seeded.source == "seed" and seeded.prompt == REMOVE_VAN and seeded.status == "accepted"
    assert seeded.category == "remove" and result.prompts == (REMOVE_VAN,)
    assert failed.status == "failed" and failed.failure_reason.startswith("vlm_error: propose: VLMError: ")
    assert failed.prompt == "" and failed.source == "client"


def test_words_that_do_not_ground_are_retried_naming_the_object_the_proposer_meant(
        ctx: EditContext, rule_client: RuleBasedVLMClient) -> None:
    from simsplat_core.editing.apply import apply_edit
    from simsplat_core.editing.parse.prompt import parse_prompt

    (van,) = apply_edit(ctx, parse_prompt(REMOVE_VAN)).outcomes[0].changed_object_ids
    wrong = "Remove the purple van."  # no purple van here: the words do not ground
    meant = Proposal(wrong, "remove", "remove", False, target_id=van)
    result = mine_sequence(ctx, ScriptedClient([], rule_client), dataclasses.replace(CONFIG, scenarios=1),
                           seed_prompts=[meant])
    refused, retried = result.records
    assert refused.status == "refused" and refused.failure_reason.startswith("not_found: ")
    assert retried.attempt == 2 and retried.status == "accepted" and f"-> object {van}" in retried.adjustment
    assert _program(retried.program_json).commands[0].target.object_id == van
    unsaid = mine_sequence(ctx, ScriptedClient([], rule_client), dataclasses.replace(CONFIG, scenarios=1),
                           seed_prompts=[wrong])  # a proposer that does not say which object: not retried
    assert [(r.attempt, r.status) for r in unsaid.records] == [(1, "refused")]


def test_the_rule_based_client_follows_the_seed_prompts(ctx: EditContext, rule_client: RuleBasedVLMClient,
                                                        mined: MiningResult) -> None:
    result = mine_sequence(ctx, rule_client, dataclasses.replace(CONFIG, scenarios=1), seed_prompts=[SLOWER_SUV])
    assert result.records[0].source == "seed" and result.records[0].prompt == SLOWER_SUV
    assert result.records[0].category == "modify_vehicle"
    assert all(r.source == "client" for r in result.records[1:])


def test_max_attempts_bounds_the_retries(ctx: EditContext, rule_client: RuleBasedVLMClient) -> None:
    never = Judgement(False, 1, ("never good enough",), (ParameterChange("start_time", "2 s later", "try later"),))
    client = ScriptedClient([SLOWER_SUV], rule_client, verdict=never)
    result = mine_sequence(ctx, client, dataclasses.replace(CONFIG, scenarios=1, max_attempts=2))
    assert [(r.attempt, r.status) for r in result.records] == [(1, "rejected"), (2, "rejected")]
    assert "never good enough" in result.records[0].failure_reason
    delays = [c.behaviour.delay_s for r in result.records for c in _program(r.program_json).commands if c.behaviour]
    assert delays == [None, 2.0] and result.records[1].adjustment == "command 1: start_time 2 s later"


def test_attempt_rows_map_onto_the_edits_table(mined: MiningResult, collided: MiningResult) -> None:
    assert EDITS_COLUMNS == tuple(EDITS_SCHEMA.names)
    for result in (mined, collided):
        rows = attempt_rows(result, "mine-test")
        assert len(rows) == len(result.records)
        numbered: dict[str, int] = {}
        for row in rows:
            assert set(EDITS_COLUMNS) <= set(row) and row["run_id"] == "mine-test"
            assert row["status"] in ("succeeded", "refused", "failed")
            assert (row["status"] == "succeeded") == (row["failure_reason"] == "") == row["export"]
            assert row["attempt"] == numbered.get(row["edit_id"], 0) + 1  # as the table numbers attempts
            numbered[row["edit_id"]] = row["attempt"]
            assert row["category"] in EDIT_CATEGORIES and row["client"] == result.client
            if row["mining_status"] == "rejected":
                assert row["status"] == "failed" and row["failure_reason"].startswith("rejected: ")
        for record, row in zip(result.records, rows):  # the judge's reasons, kept for every judged attempt
            expected = () if record.judgement is None else record.judgement.reasons
            assert judge_reasons_of(row["judge_reasons"]) == expected
            assert (row["judge_reasons"] is None) == (record.judgement is None)


# ---------------------------------------------------------------------------------------------- adjustments
def _insert(**placement: object) -> EditProgram:
    return EditProgram.model_validate({"prompt": "p", "commands": [
        {"op": "insert", "asset": {"description": "a traffic cone", "category": "static"},
         "placement": {"relation": "in_lane", "lane": "same", **placement}}]})


def _modify(**behaviour: object) -> EditProgram:
    return EditProgram.model_validate({"prompt": "p", "commands": [
        {"op": "modify", "target": {"object_id": "veh_01"}, "behaviour": behaviour}]})


def test_default_adjustments_by_failure_class() -> None:
    static = adjust_program(_insert(distance_m=3.0), ["static"], (), {"collision"})
    assert static is not None and static.program.commands[0].placement.distance_m == 8.0
    moving = adjust_program(_modify(stop={}), ["vehicle"], (), {"collision"})
    assert moving is not None and moving.program.commands[0].behaviour.delay_s == 1.5
    closer = adjust_program(_insert(distance_m=12.0), ["static"], (), {"not_visible"})
    assert closer is not None and closer.program.commands[0].placement.distance_m == MIN_LANE_GAP_M
    assert adjust_program(_modify(stop={}), ["vehicle"], (), {"not_visible"}) is None  # no placement to move
    assert adjust_program(_modify(stop={}), ["vehicle"], (ParameterChange("other", "anything"),), ()) is None


def test_suggested_changes_are_applied_once_per_parameter() -> None:
    suggestions = (ParameterChange("speed", "7.5 m/s"), ParameterChange("speed", "faster"),
                   ParameterChange("start_time", "1 s earlier"))
    adjusted = adjust_program(_modify(delay_s=3.0), ["vehicle"], suggestions)
    assert adjusted is not None
    behaviour = adjusted.program.commands[0].behaviour
    assert behaviour is not None and behaviour.speed is not None and behaviour.speed.target_mps(0.0) == 7.5
    assert behaviour.delay_s == 2.0 and len(adjusted.changes) == 2
    slower = adjust_program(_modify(speed={"mode": "absolute", "value": 10.0}), ["vehicle"],
                            (ParameterChange("speed", "a bit slower"),))
    assert slower is not None and slower.program.commands[0].behaviour.speed.value == 7.0
    assert adjust_program(_insert(distance_m=20.0), ["static"], (ParameterChange("speed", "5 m/s"),)) is None


def test_anchor_and_asset_changes() -> None:
    anchored = _insert(distance_m=10.0, anchor={"description": "the white van"})
    dropped = adjust_program(anchored, ["static"], (ParameterChange("anchor", "the ego lane"),))
    assert dropped is not None and dropped.program.commands[0].placement.anchor is None

    def other(spec: AssetSpec) -> str | None:
        return "unit.barrier" if spec.category == "static" else None

    swapped = adjust_program(_insert(), ["static"], (ParameterChange("asset", "a larger object"),),
                             alternative_asset=other)
    assert swapped is not None and swapped.program.commands[0].asset.asset_id == "unit.barrier"
    assert adjust_program(_insert(), ["static"], (ParameterChange("asset", "another"),)) is None  # no bank choice
    unchanged = EditCommand.model_validate({"op": "remove", "target": {"object_id": "veh_01"}})
    assert adjust_program(EditProgram(prompt="p", commands=[unchanged]), ["vehicle"],
                          (ParameterChange("offset", "5 m further"),), {"collision"}) is None
