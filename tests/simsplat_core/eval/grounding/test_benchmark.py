"""Grounding benchmark generation: determinism, uniqueness of single-target queries, groups, no-match queries."""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest

from simsplat_core.eval.grounding.benchmark import (
    BenchmarkConfig,
    Description,
    ObjectFacts,
    build_benchmark,
    candidate_descriptions,
    generate_queries,
    matching,
    object_facts,
    unambiguous_targets,
)
from simsplat_core.eval.grounding.paraphrases import MOTION_TERMS, SINGLE_STYLES
from simsplat_core.scenario import vocabulary as voc
from simsplat_core.types import SceneLog
from simsplat_core.world import generate_log
from tests.simsplat_core.language.language_scene_factory import SMALL_WORLD

SEEDS = (3, 11)


@pytest.fixture(scope="module")
def logs() -> list[SceneLog]:
    return [generate_log(seed, SMALL_WORLD) for seed in SEEDS]


@pytest.fixture(scope="module")
def facts(logs: list[SceneLog]) -> dict[str, dict[str, ObjectFacts]]:
    return {log.seq_id: object_facts(log) for log in logs}


@pytest.fixture(scope="module")
def bench(logs: list[SceneLog]):
    return build_benchmark(logs, BenchmarkConfig(seed=0))


def test_facts_come_from_ground_truth(logs: list[SceneLog], facts) -> None:
    log = logs[0]
    for obj in log.objects:
        f = facts[log.seq_id][obj.object_id]
        assert f.instance_id == obj.instance_id
        if obj.category == "vehicle":
            assert (f.subtype, f.color) == (obj.attributes["subtype"], obj.attributes["color"])
            assert f.motion is not None and f.sector is not None
        if obj.category == "pedestrian":
            assert (f.upper, f.lower) == (obj.attributes["upper_color"], obj.attributes["lower_color"])
        pixels = sum(int(np.count_nonzero(img.instance == obj.instance_id)) for img in log.images)
        assert f.pixels == pixels


def test_generation_is_deterministic(logs: list[SceneLog], bench) -> None:
    again = build_benchmark(logs, BenchmarkConfig(seed=0))
    assert again.queries == bench.queries
    other = build_benchmark(logs, BenchmarkConfig(seed=1))
    assert [q.text for q in other.queries] != [q.text for q in bench.queries]


def test_every_kind_and_category_is_present(bench) -> None:
    counts = bench.counts()
    assert counts["single"] >= 10 and counts["group"] >= 2 and counts["none"] >= 2
    assert counts["vehicle"] > 0 and counts["pedestrian"] > 0
    assert len({q.query_id for q in bench.queries}) == len(bench.queries)


def test_single_queries_identify_their_target_uniquely(bench, facts) -> None:
    config = bench.config
    singles = [q for q in bench.queries if q.kind == "single"]
    for q in singles:
        objs = list(facts[q.seq_id].values())
        assert len(q.target_ids) == 1
        assert [m.object_id for m in matching(q.description, objs)] == list(q.target_ids), q.text
        assert [m.object_id for m in matching(q.description, objs, lenient=True)] == list(q.target_ids), q.text
        target = facts[q.seq_id][q.target_ids[0]]
        assert target.visible_frames >= config.min_visible_frames
        assert q.category == target.category


def test_group_and_none_queries(bench, facts) -> None:
    for q in bench.queries:
        objs = list(facts[q.seq_id].values())
        matched = sorted(m.object_id for m in matching(q.description, objs))
        assert matched == sorted(m.object_id for m in matching(q.description, objs, lenient=True)), q.text
        if q.kind == "group":
            assert len(q.target_ids) >= 2 and matched == list(q.target_ids), q.text
            assert all(facts[q.seq_id][t].visible_frames >= bench.config.min_visible_frames for t in q.target_ids)
        elif q.kind == "none":
            assert q.target_ids == () and matched == [], q.text
            assert q.perturbed in q.description.slots


def test_texts_put_the_constraints_into_words(bench) -> None:
    for q in bench.queries:
        d = q.description
        text = q.text.lower()
        for color in (d.color, d.upper, d.lower):
            if color is not None:
                words = ("gray", "grey") if color == "gray" else (color,)
                assert any(re.search(rf"\b{w}\b", text) for w in words), (color, q.text)
        if d.category == "pedestrian":
            assert re.search(r"pedestrian|person|people|walker|passer|individual|someone", text), q.text
        if d.motion in (voc.TURNING_LEFT, voc.CROSSING_LEFT_TO_RIGHT):
            assert "left" in text, q.text


def test_paraphrases_of_one_target_differ(bench) -> None:
    by_target: dict[tuple[str, str], list] = {}
    for q in bench.queries:
        if q.kind == "single":
            by_target.setdefault((q.seq_id, q.target_ids[0]), []).append(q)
    assert by_target
    for qs in by_target.values():
        assert len({q.text for q in qs}) == len(qs)
        assert len({q.style for q in qs}) == len(qs)
        assert len({q.description for q in qs}) == len(qs)
        assert len({q.family for q in qs}) >= min(len(qs), 2)
    styles = {q.style for q in bench.queries if q.kind == "single"}
    assert len(styles) >= len(SINGLE_STYLES) - 2


def test_candidates_cover_appearance_motion_location() -> None:
    f = ObjectFacts("v", "vehicle", 1, "SUV", "red", None, None, voc.TURNING_LEFT, voc.LEFT_OF_EGO,
                    voc.AT_THE_INTERSECTION, 10, 500)
    cands = candidate_descriptions(f)
    assert all(c.matches(f) for c in cands)
    fams = {c.family for c in cands}
    assert {"app", "app+mot", "app+loc", "app+mot+loc", "mot", "loc", "mot+loc", "category"} <= fams
    # broader motion terms are offered and cover the exact class
    assert any(c.motion == "turning_any" for c in cands)
    assert voc.TURNING_LEFT in MOTION_TERMS["turning_any"][1]
    twin = dataclasses.replace(f, object_id="w", motion=voc.GOING_STRAIGHT)
    unique = [c for c in cands if [m.object_id for m in matching(c, [f, twin])] == ["v"]]
    assert unique and all(c.motion in (voc.TURNING_LEFT, "turning_any") for c in unique)


def test_plausible_readings_widen_matching() -> None:
    stopping = ObjectFacts(
        "s",
        "vehicle",
        1,
        "sedan",
        "red",
        None,
        None,
        voc.STOPPING,
        voc.IN_FRONT_OF_EGO,
        voc.AT_THE_INTERSECTION,
        motions=frozenset({voc.STOPPING, voc.SLOWING_DOWN, voc.GOING_STRAIGHT}),
        sectors=frozenset({voc.IN_FRONT_OF_EGO, voc.LEFT_OF_EGO}),
        contexts=frozenset({voc.AT_THE_INTERSECTION, voc.IN_THE_ONCOMING_LANE}),
    )
    straight = Description("vehicle", color="red", motion=voc.GOING_STRAIGHT)
    assert not straight.matches(stopping) and straight.matches(stopping, lenient=True)
    left = Description("vehicle", sector=voc.LEFT_OF_EGO)
    assert not left.matches(stopping) and left.matches(stopping, lenient=True)
    assert not Description("vehicle", context=voc.BY_THE_CURB).matches(stopping, lenient=True)
    # a description that fits one object by its labels but another one by a plausible reading is not unique
    other = dataclasses.replace(
        stopping, object_id="t", motion=voc.GOING_STRAIGHT, motions=frozenset({voc.GOING_STRAIGHT})
    )
    assert unambiguous_targets(straight, [stopping, other]) is None
    assert [
        f.object_id for f in unambiguous_targets(Description("vehicle", motion=voc.STOPPING), [stopping, other])
    ] == ["s"]


def test_readings_of_a_real_log_contain_the_labels(logs: list[SceneLog], facts) -> None:
    for f in facts[logs[0].seq_id].values():
        if f.motion is None:
            continue
        assert f.motion in f.motions and f.sector in f.sectors and f.context in f.contexts
        if f.motion == voc.STOPPING:
            assert {voc.SLOWING_DOWN, voc.GOING_STRAIGHT} <= f.motions


def test_generic_nouns_match_every_vehicle() -> None:
    bus = ObjectFacts("b", "vehicle", 1, "bus", "red", None, None, voc.PARKED, voc.LEFT_OF_EGO, voc.BY_THE_CURB)
    assert Description("vehicle", color="red").matches(bus)
    assert not Description("vehicle", subtype="sedan", color="red").matches(bus)
    assert not Description("pedestrian").matches(bus)


def test_config_is_validated() -> None:
    with pytest.raises(ValueError, match="family_weights"):
        BenchmarkConfig(family_weights=(1.0,))
    with pytest.raises(ValueError, match="group_max"):
        BenchmarkConfig(group_max=1)


def test_generate_queries_reuses_given_facts(logs: list[SceneLog], facts) -> None:
    log = logs[1]
    assert generate_queries(log, BenchmarkConfig(), facts[log.seq_id]) == generate_queries(log, BenchmarkConfig())
