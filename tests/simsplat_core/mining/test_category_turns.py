"""The sequences of a mining run take the edit categories in turn (``propose_edits(..., category_offset)``): with K
proposals per sequence, sequence ``i`` starting at ``i * K`` of the run's order, two sequences with K = 3 cover all
six categories, where independent per-sequence orders mostly repeat some and leave others out."""

from __future__ import annotations

import dataclasses

import pytest

from simsplat_core.mining.rule_proposals import EDIT_CATEGORIES, category_order, propose_edits
from simsplat_core.mining.scene_fact_records import SceneFacts


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


def test_selected_categories_keep_the_run_order_and_take_turns(facts: SceneFacts) -> None:
    chosen = ("modify_pedestrian", "add_vehicle", "remove")
    order = category_order(7, 0, chosen)
    assert order == [c for c in category_order(7, 0) if c in chosen]  # the full order, less the others
    assert category_order(7, 2, chosen) == order[2:] + order[:2]
    scenes = [dataclasses.replace(facts, seq_id=f"synth-{i:06d}") for i in (101, 102)]
    for seed in range(3):
        turns = [p.category for i, scene in enumerate(scenes) for p in propose_edits(scene, 3, seed, 3 * i, chosen)]
        assert sorted(turns) == sorted(chosen * 2), (seed, turns)
        unrotated = propose_edits(scenes[0], 4, seed, categories=chosen)
        assert {p.category for p in unrotated} <= set(chosen)
        assert propose_edits(scenes[0], 4, seed, categories=chosen) == unrotated  # deterministic
    assert propose_edits(scenes[0], 6, 1, 0, ()) == propose_edits(scenes[0], 6, 1, 0)  # none given: all six
    with pytest.raises(ValueError, match="unknown edit category \\['add_truck'\\]"):
        propose_edits(scenes[0], 3, 0, categories=("add_truck",))
