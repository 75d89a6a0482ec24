"""The sequences of a mining run take the edit categories in turn (``propose_edits(..., category_offset)``): with K
proposals per sequence, sequence ``i`` starting at ``i * K`` of the run's order, two sequences with K = 3 cover all
six categories, where independent per-sequence orders mostly repeat some and leave others out; and the default
adjustment of a refused delay."""

from __future__ import annotations

import dataclasses

from simsplat_core.editing.commands import EditProgram
from simsplat_core.mining.adjust import adjust_program
from simsplat_core.mining.rule_proposals import EDIT_CATEGORIES, category_order, propose_edits
from simsplat_core.mining.scene_facts import SceneFacts


def test_the_run_order_is_shared_and_rotated() -> None:
    order = category_order(7, 0)
    assert sorted(order) == sorted(EDIT_CATEGORIES) and category_order(7, 0) == order
    assert category_order(7, 3) == order[3:] + order[:3] and category_order(7, 6) == order


def test_two_sequences_with_three_proposals_each_cover_every_category(facts: SceneFacts) -> None:
    # the same scene under two sequence ids stands for two sequences of a run (every category is feasible in it)
    scenes = [dataclasses.replace(facts, seq_id=f"synth-{i:06d}") for i in (101, 102)]
    for seed in range(5):
        turns = [p.category for i, scene in enumerate(scenes) for p in propose_edits(scene, 3, seed, 3 * i)]
        assert sorted(turns) == sorted(EDIT_CATEGORIES), (seed, turns)
    independent = [sorted({p.category for scene in scenes for p in propose_edits(scene, 3, seed)}) for seed in range(5)]
    assert any(len(c) < len(EDIT_CATEGORIES) for c in independent)  # what the turns fix


def test_a_refused_delay_becomes_a_start_time() -> None:
    """store_101: a standing pedestrian asked to sprint across collided; the default "1.5 s later" (a delay of its log
    trajectory) was refused -- it does not move in the log --, and nothing else was tried: the scenario was lost."""
    program = EditProgram.model_validate({"prompt": "have the pedestrian sprint across", "commands": [
        {"op": "modify", "target": {"object_id": "ped_01"},
         "behaviour": {"cross_street": True, "gait": "run", "delay_s": 1.5}}]})
    adjusted = adjust_program(program, ["pedestrian"], (), {"infeasible_motion"})
    assert adjusted is not None and "hold still" in adjusted.describe()
    (behaviour,) = [c.behaviour for c in adjusted.program.commands]
    assert behaviour is not None and behaviour.delay_s is None and behaviour.start_time_s == 1.5
    assert behaviour.cross_street and behaviour.gait == "run"
    undelayed = program.model_copy(update={"commands": [adjusted.program.commands[0]]})
    assert adjust_program(undelayed, ["pedestrian"], (), {"infeasible_motion"}) is None  # nothing left to turn
