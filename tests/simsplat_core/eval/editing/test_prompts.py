"""Prompt set generation: counts, wording variety, ground-truth intents, id-based forms, determinism."""

from __future__ import annotations

import dataclasses
from collections import Counter

import numpy as np

from simsplat_core.eval.editing.intents import EGO
from simsplat_core.eval.editing.plans import _clear_run, _delay_clear
from simsplat_core.eval.editing.prompts import CATEGORIES, INFEASIBLE, PromptConfig, build_prompt_set, quotas
from simsplat_core.eval.editing.references import ABSENT_COLORS
from simsplat_core.eval.editing.truth import world_of_log
from simsplat_core.scenario.path import Path
from simsplat_core.world.road import target_lane


def test_counts_per_category_and_scene(prompts) -> None:
    counts = Counter(p.category for p in prompts)
    assert {c: counts[c] for c in CATEGORIES} == dict.fromkeys(CATEGORIES, 30)
    assert counts[INFEASIBLE] == 20
    for category in (*CATEGORIES, INFEASIBLE):
        per_scene = Counter(p.seq_id for p in prompts if p.category == category)
        assert sorted(per_scene.values()) == sorted(quotas(counts[category], 2))
    assert len({p.prompt_id for p in prompts}) == len(prompts)


def test_wording_varies_within_each_category(prompts) -> None:
    for category in (*CATEGORIES, INFEASIBLE):
        mine = [p for p in prompts if p.category == category]
        assert len({p.kind for p in mine}) >= 3, category
        assert len({(p.kind, p.form) for p in mine}) >= 8, category
        assert len({p.text for p in mine}) >= 0.7 * len(mine), category
        assert len({p.text.split()[0].lower() for p in mine}) >= 3, category


def test_modify_speeds_use_several_units_and_relative_forms(prompts) -> None:
    speeds = [p.intent.motion.speed for p in prompts if p.category.startswith("modify") and p.intent.motion
              and p.intent.motion.speed is not None]
    assert {s.unit for s in speeds} >= {"km/h", "m/s"}
    assert {s.mode for s in speeds} >= {"absolute", "factor"}


def test_intents_name_ground_truth_objects(prompts, truths) -> None:
    by_seq = {t.seq_id: t for t in truths}
    for p in prompts:
        truth = by_seq[p.seq_id]
        ids = {a.object_id for a in truth.world.agents}
        intent = p.intent
        assert set(intent.targets) <= ids, p.text
        if p.category == INFEASIBLE:
            assert intent.expected_refusals, p.text
            continue
        assert not intent.expected_refusals
        if intent.op in ("remove", "modify", "replace"):
            assert intent.targets and all(truth.well_visible(t) for t in intent.targets if not intent.group), p.text
        if intent.op == "modify":
            assert intent.motion is not None and intent.motion.behaviour() != intent.motion.behaviour().__class__()
        if intent.op in ("insert", "replace"):
            assert intent.asset is not None and intent.asset.category in ("vehicle", "pedestrian", "static")
        if intent.op == "insert":
            assert intent.placement is not None
            assert intent.placement.anchor == EGO or intent.placement.anchor in ids
        category_of = {"add_vehicle": "vehicle", "add_static": "static", "add_pedestrian": "pedestrian"}
        if p.category in category_of:
            assert intent.asset is not None and intent.asset.category == category_of[p.category]
        if p.category == "modify_pedestrian":
            assert all(truth.agent(t).category == "pedestrian" for t in intent.targets)


def test_structured_form_names_the_targets_nodes(prompts, truths) -> None:
    by_seq = {t.seq_id: t for t in truths}
    for p in prompts:
        if p.category == INFEASIBLE and not p.intent.structured:
            assert p.structured is None
            continue
        assert p.structured is not None, p.text
        nodes = by_seq[p.seq_id].node_of_object
        targets = [c.target.node_id for c in p.structured.commands if c.target is not None]
        assert targets == [nodes[t] for t in p.intent.targets]
        for c in p.structured.commands:
            assert c.target is None or c.target.description is None  # ids, never words
            if c.placement is not None and c.placement.anchor is not None:
                assert c.placement.anchor.node_id == nodes[p.intent.placement.anchor]


def test_relative_speeds_are_resolved_against_the_log(prompts, truths) -> None:
    by_seq = {t.seq_id: t for t in truths}
    seen = 0
    for p in prompts:
        m = p.intent.motion
        if p.intent.op != "modify" or m is None or m.speed is None or m.speed.mode != "factor":
            continue
        v0 = float(by_seq[p.seq_id].agent(p.intent.targets[0]).traj["speed"][0])
        assert np.isclose(m.speed_mps, v0 * m.speed.value)
        seen += 1
    assert seen > 0


def test_turns_go_to_vehicles_approaching_the_junction_in_a_turning_lane(prompts, truths) -> None:
    by_seq = {t.seq_id: t for t in truths}
    turns = [p for p in prompts if p.kind == "vehicle_turn"]
    assert turns
    for p in turns:
        truth = by_seq[p.seq_id]
        agent = truth.agent(p.intent.targets[0])
        pos = truth.road_position(agent.traj["xy"][0], float(agent.traj["heading"][0]))
        assert pos.inbound and pos.lane is not None
        assert target_lane(truth.layout, pos.arm, pos.lane, p.intent.motion.turn) is not None
    for p in prompts:
        if p.kind == "turn_no_intersection":
            truth = by_seq[p.seq_id]
            agent = truth.agent(p.intent.targets[0])
            assert truth.road_position(agent.traj["xy"][0], float(agent.traj["heading"][0])).inbound is False


def test_absent_objects_are_absent(prompts, truths) -> None:
    absent = [p for p in prompts if p.kind.startswith("absent_")]
    assert absent
    for p in absent:
        assert any(c in p.text for c in ABSENT_COLORS)
        truth = next(t for t in truths if t.seq_id == p.seq_id)
        colours = {v for a in truth.world.agents for v in a.appearance.values()}
        assert not colours & set(ABSENT_COLORS)


def test_generation_is_deterministic_and_seeded(truths, prompts) -> None:
    again = build_prompt_set(truths, PromptConfig(per_category=30, infeasible=20))
    assert [p.text for p in again] == [p.text for p in prompts]
    other = build_prompt_set(truths, PromptConfig(per_category=30, infeasible=20, seed=1))
    assert [p.text for p in other] != [p.text for p in prompts]


def test_world_is_rebuilt_from_the_log_and_mismatch_is_named(truths) -> None:
    import dataclasses

    import pytest

    log = truths[0].log
    assert [a.object_id for a in world_of_log(log).agents] == [a.object_id for a in truths[0].world.agents]
    with pytest.raises(ValueError, match="generated by"):
        world_of_log(dataclasses.replace(log, metadata={**log.metadata, "generator": "other/0"}))


def test_inserts_ask_for_what_the_bank_holds(truths) -> None:
    from simsplat_core.eval.editing.observation import AssetLook
    from simsplat_core.eval.editing.plans import AssetPools

    bank = [AssetLook("vehicle", "van", "blue", (5.2, 2.0, 2.1)),
            AssetLook("pedestrian", "adult", "yellow", (0.6, 0.6, 1.7), lower="gray"),
            AssetLook("static", "traffic cone", "orange", (0.42, 0.42, 0.72))]
    pools = AssetPools.from_bank(bank)
    prompts = build_prompt_set(truths, PromptConfig(per_category=6, infeasible=0), pools)
    vehicles = [p.intent.asset for p in prompts if p.category == "add_vehicle"]
    assert vehicles and all(a.subtype in ("van", None) for a in vehicles)
    people = [p.intent.asset for p in prompts if p.category == "add_pedestrian"]
    assert people and all(a.upper == "yellow" and a.lower in ("gray", None) for a in people)


def test_a_run_behind_a_leader_within_the_editors_following_gap_is_not_clear(truths) -> None:
    """A car 2 m behind a vehicle driving straight, at its speed, never overlaps it, yet cannot hold that speed
    behind it in an editor that keeps its following gap: with ``keep_gap`` the run is not clear."""
    truth = truths[0]
    leader = next(a for a in truth.world.agents if a.category == "vehicle" and float(a.traj["speed"].min()) > 3.0
                  and float(np.ptp(np.unwrap(a.traj["heading"]))) < 0.05)
    xy, h, v = leader.traj["xy"], float(leader.traj["heading"][0]), float(np.mean(leader.traj["speed"]))
    fwd = np.array([np.cos(h), np.sin(h)])
    line = Path.from_points(np.stack([xy[0] - 30.0 * fwd, xy[-1]]))
    s_behind = line.project(xy[0]) - float(leader.size[0]) - 2.0  # its front 2 m from the leader's rear
    assert _clear_run(truth, line, s_behind, v, v, tuple(leader.size), skip="ego", margin=0.0)
    assert not _clear_run(truth, line, s_behind, v, v, tuple(leader.size), skip="ego", margin=0.0, keep_gap=True)


def test_a_delay_a_close_follower_replaying_its_log_would_run_into_is_not_asked(truths) -> None:
    """A car followed closely along its own path (its follower replays the log: the benchmark's ego does) may not
    be asked to set off 2 s late: the follower would run into it and the editor rightly refuses."""
    truth = truths[0]
    lead = next(a for a in truth.world.agents if a.category == "vehicle" and float(a.traj["speed"].min()) > 3.0)
    t = truth.world.times
    lag = (float(lead.size[0]) + 2.0) / float(np.mean(lead.traj["speed"]))  # 2 m behind its rear bumper
    s_follow = np.interp(t - lag, t, lead.traj["s"], left=float(lead.traj["s"][0]) - lag * lead.traj["speed"][0])
    follower = dataclasses.replace(lead, object_id="follower", traj={
        **lead.traj, "xy": lead.motion.path.position(s_follow), "heading": lead.motion.path.heading(s_follow)})
    crowded = dataclasses.replace(truth, world=dataclasses.replace(truth.world, agents=[*truth.world.agents,
                                                                                         follower]))
    assert not _delay_clear(crowded, lead, 2.0)
    # set off on time, the follower 2 m behind is in nobody's way: only the delay makes the run unclear
    assert _delay_clear(crowded, lead, 0.0) == _delay_clear(truth, lead, 0.0)
