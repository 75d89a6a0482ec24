"""RuleBasedVLMClient: proposals from scene facts (deterministic, diverse, safety-critical, feasible, parsed and
applied by the editor on the editing tests' synthetic scene) and the protocol."""

from __future__ import annotations

import dataclasses
import logging
from collections import Counter

import numpy as np
import pytest

from simsplat_core.editing.apply import Editor
from simsplat_core.editing.draft import EditContext
from simsplat_core.editing.result import EditRefused
from simsplat_core.mining import (
    EDIT_CATEGORIES,
    ProposalRejected,
    ProposalRequest,
    RuleBasedVLMClient,
    SceneSummary,
    VLMClient,
)
from simsplat_core.mining.rule_proposals import KINDS, Proposal, candidates, proposal_rng, propose_edits
from simsplat_core.mining.rule_wording import FORMS, referring_phrase
from simsplat_core.mining.scene_fact_records import AgentFacts, AssetFacts, RoadFacts, SceneFacts
from simsplat_core.mining.scene_facts import summary
from simsplat_core.scenario import vocabulary as voc

VIEW = np.zeros((8, 12, 3), np.uint8)
#: Families of safety-critical edits the issue names, and the proposal kinds that make each.
SAFETY_FAMILIES: dict[str, set[str]] = {
    "jaywalking pedestrian": {"jaywalker", "ped_jaywalk", "runner", "ped_run_across"},
    "aggressive cut-in": {"cut_in", "lane_change"},
    "sudden stop": {"lead_brake", "hard_stop"},
    "obstacle in the lane": {"cones_in_lane", "obstacle_in_lane"},
    "pulling out / reversing": {"reverse", "pull_out"},
}


def _request(facts: SceneFacts, count: int) -> ProposalRequest:
    return ProposalRequest([VIEW], summary(facts), count=count)


@pytest.fixture(scope="module")
def mixed(facts: SceneFacts) -> list[Proposal]:
    """Twelve proposals: six from each of two seeds."""
    return propose_edits(facts, 6, seed=0) + propose_edits(facts, 6, seed=1)


def test_the_client_is_a_vlm_client() -> None:
    client = RuleBasedVLMClient(seed=3)
    assert isinstance(client, VLMClient) and client.name == "rule-based/1" and "seed=3" in repr(client)


def test_proposals_are_deterministic_per_seed_and_vary_across_seeds(facts: SceneFacts) -> None:
    first = RuleBasedVLMClient(seed=0).propose(_request(facts, 6))
    assert first == RuleBasedVLMClient(seed=0).propose(_request(facts, 6))
    assert len(first) == 6 and len(set(first)) == 6
    others = [RuleBasedVLMClient(seed=s).propose(_request(facts, 6)) for s in (1, 2, 3)]
    assert all(o != first for o in others)
    assert len({p for o in others for p in o} - set(first)) >= 12  # mostly new wording and edits
    assert RuleBasedVLMClient(seed=0).propose(_request(facts, 2)) == first[:2]  # fewer asked: the first ones


def test_proposals_cover_every_category_and_the_safety_critical_edits(facts: SceneFacts) -> None:
    client = RuleBasedVLMClient(seed=0)
    six = client.proposals(summary(facts), 6)
    assert {p.category for p in six} == set(EDIT_CATEGORIES)  # one per category when six are asked
    several = [p for seed in range(8) for p in RuleBasedVLMClient(seed=seed).proposals(summary(facts), 8)]
    kinds = {p.kind for p in several}
    for family, members in SAFETY_FAMILIES.items():
        assert kinds & members, f"no {family} among {sorted(kinds)}"
    assert sum(p.safety_critical for p in several) >= len(several) // 2
    # fewer asked: categories still differ
    three = client.proposals(summary(facts), 3)
    assert len({p.category for p in three}) == 3


def test_every_kind_is_feasible_in_the_test_scene_and_its_words_vary(facts: SceneFacts) -> None:
    built = {k.name: found for kinds in candidates(facts, proposal_rng(0, facts.seq_id)).values()
             for k, found in kinds}
    # every kind but two: no standing car has room to pull out, no moving one room to speed up
    assert set(built) == {k.name for k in KINDS} - {"pull_out", "speed_up"}
    assert set(FORMS) == {k.name for k in KINDS}
    wording = [p.prompt for found in built.values() for p in found]
    openings = Counter(text.split()[0].lower() for text in wording)
    assert len(openings) >= 8 and max(openings.values()) < 0.5 * len(wording)


def test_every_proposal_parses_most_apply_and_act_on_the_named_object(ctx: EditContext, facts: SceneFacts,
                                                                      mixed: list[Proposal],
                                                                      caplog: pytest.LogCaptureFixture) -> None:
    client = RuleBasedVLMClient(seed=0)
    editor = Editor(ctx)
    node_of = {a.object_id: a.node_id for a in facts.agents}
    applied, named_right, refused = 0, 0, []
    for proposal in mixed:
        program = client.to_command(proposal.prompt, summary(facts))
        assert program.prompt == proposal.prompt and program.commands
        try:
            edited = editor.edit(proposal.prompt)
        except EditRefused as exc:
            refused.append(f"{proposal.prompt}: {exc}")
            continue
        applied += 1
        grounded = {n for o in edited.outcomes for n in (*o.target_node_ids, *o.anchor_node_ids)}
        named_right += proposal.target_id is None or node_of[proposal.target_id] in grounded
    logging.getLogger(__name__).info("applied %d/%d proposals; refused: %s", applied, len(mixed), refused)
    assert len(mixed) == 12
    assert applied / len(mixed) >= 0.8, refused
    assert named_right == applied


def test_to_command_raises_proposal_rejected_for_a_refused_prompt(facts: SceneFacts) -> None:
    client = RuleBasedVLMClient()
    with pytest.raises(ProposalRejected, match="'make the car fly' cannot be turned into commands") as info:
        client.to_command("make the car fly", summary(facts))
    assert isinstance(info.value, EditRefused) and info.value.reason == "unsupported"
    assert info.value.prompt == "make the car fly"


def test_proposing_needs_structured_facts(facts: SceneFacts) -> None:
    bare = ProposalRequest([VIEW], SceneSummary(facts.seq_id, ("some text",)), count=2)
    with pytest.raises(ValueError, match="structured facts"):
        RuleBasedVLMClient().propose(bare)
    assert len(RuleBasedVLMClient(facts_of=lambda s: facts).propose(bare)) == 2
    empty = SceneFacts("empty", (), RoadFacts())
    with pytest.raises(ValueError, match="no feasible edit"):
        RuleBasedVLMClient().propose(ProposalRequest([VIEW], summary(empty), count=2))


# ---------------------------------------------------------------------------------------------- feasibility
def _agent(object_id: str, kind: str, caption: str, **kw: object) -> AgentFacts:
    base: dict[str, object] = dict(
        object_id=object_id, node_id=1, category=kind, kind=kind, caption=caption, subtype=caption.split()[-1],
        color=caption.split()[1], motion="", sector=voc.IN_FRONT_OF_EGO, context=voc.ON_THE_ROAD, moving=False,
        speed_mps=0.0, ahead_m=20.0, left_m=4.0, heading_deg=0.0, relation=voc.IN_FRONT_OF_EGO, area="other_lane",
        visible_share=0.5)
    base.update(kw)
    return AgentFacts(**base)  # type: ignore[arg-type]


def _scene(*agents: AgentFacts, **road: object) -> SceneFacts:
    base: dict[str, object] = dict(ego_speed_mps=5.0, lane_ahead_m=100.0, plain_road=((0.0, 100.0),),
                                   lanes_our_way=1, sidewalks=True, duration_s=8.0)
    base.update(road)
    assets = (AssetFacts("vehicle", "sedan", "yellow", "a yellow sedan"),
              AssetFacts("pedestrian", "adult", "red", "a pedestrian in a red top"),
              AssetFacts("static", "traffic cone", "orange", "an orange traffic cone"))
    return SceneFacts("hand", agents, RoadFacts(**base), assets)  # type: ignore[arg-type]


def _kinds(facts: SceneFacts) -> dict[str, list[Proposal]]:
    return {k.name: found for kinds in candidates(facts, proposal_rng(0, facts.seq_id)).values() for k, found in kinds}


def test_only_feasible_edits_are_proposed() -> None:
    moving = _agent("car_1", "vehicle", "a red SUV", moving=True, speed_mps=8.0, motion=voc.GOING_STRAIGHT)
    parked = _agent("car_2", "vehicle", "a blue van", motion=voc.PARKED, context=voc.BY_THE_CURB, room_behind_m=2.0,
                    room_ahead_m=3.0)
    kinds = _kinds(_scene(moving, parked))
    assert [p.target_id for p in kinds["hard_stop"]] == ["car_1"]  # only a moving car is made to stop
    assert "reverse" not in kinds and "pull_out" not in kinds  # the parked van has no room either way
    assert "cut_in" not in kinds and "lane_change" not in kinds  # one lane, no neighbour
    assert "turn" not in kinds
    # a lane on the left: cut-ins from it; the moving car may change into it
    wide = _kinds(_scene(dataclasses.replace(moving, lane_change_sides=("left",), turns=("right",)), parked,
                         left_lane=True, lanes_our_way=2))
    assert all("left lane" in p.prompt or "to our left" in p.prompt or "left-hand" in p.prompt
               for p in wide["cut_in"])
    assert "left" in wide["lane_change"][0].prompt and "right" in wide["turn"][0].prompt
    # a cut-in starts where the plain road goes on long enough for the lane change (here 20 m at 5 m/s)
    near_junction = _kinds(_scene(moving, parked, left_lane=True, lanes_our_way=2, plain_road=((0.0, 38.0),)))
    assert near_junction["cut_in"] and all(d <= 18 for d in _asked_distances(near_junction["cut_in"]))
    assert "cut_in" not in _kinds(_scene(moving, parked, left_lane=True, lanes_our_way=2, plain_road=((0.0, 25.0),)))
    # no plain road ahead: nobody jaywalks in front of us, no obstacle goes in the lane
    junction = _kinds(_scene(moving, plain_road=((0.0, 8.0),)))
    assert not {"jaywalker", "runner", "cones_in_lane", "obstacle_in_lane"} & set(junction)
    # a short lane: inserts stay within it
    short = _kinds(_scene(moving, lane_ahead_m=30.0))
    assert short["lead_brake"] and all(15 <= d <= 20 for d in _asked_distances(short["lead_brake"]))
    # no assets: nothing is inserted or swapped
    bare = _kinds(dataclasses.replace(_scene(moving, parked), assets=()))
    assert not {k for k in bare if k in {"cut_in", "lead_brake", "oncoming", "jaywalker", "cones_in_lane", "replace"}}


def _asked_distances(proposals: list[Proposal]) -> list[int]:
    """The metres each prompt asks for ("... 18 m ahead", "18 metres", "18m")."""
    out = []
    for p in proposals:
        numbers = [int(w.rstrip("m")) for w in p.prompt.replace(",", " ").split() if w.rstrip("m").isdigit()]
        out.append(numbers[0])
    return out


def test_lookalikes_are_told_apart_or_left_alone() -> None:
    left = _agent("ped_1", "pedestrian", "a pedestrian in a red top", sector=voc.LEFT_OF_EGO,
                  context=voc.ON_THE_SIDEWALK, area="sidewalk", motion=voc.STANDING)
    right = dataclasses.replace(left, object_id="ped_2", sector=voc.RIGHT_OF_EGO)
    twin = dataclasses.replace(right, object_id="ped_3")  # same caption, sector, context and motion as ped_2
    facts = _scene(left, right)
    rng = np.random.default_rng(0)
    phrases = {referring_phrase(left, facts, rng) for _ in range(20)}
    assert all(p is not None and ("left" in p) for p in phrases) and len(phrases) > 3
    crowded = _scene(left, right, twin)
    assert referring_phrase(right, crowded, rng) is None  # nothing tells ped_2 from ped_3
    targets = {p.target_id for found in _kinds(crowded).values() for p in found}
    assert "ped_2" not in targets and "ped_3" not in targets and "ped_1" in targets
