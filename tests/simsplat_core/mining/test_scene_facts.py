"""Scene facts of the editing tests' synthetic scene (seed 0: the ego drives east in the right of two lanes towards
an intersection) and their text summary."""

from __future__ import annotations

import dataclasses
import math

import pytest

from simsplat_core.mining import SceneSummary
from simsplat_core.mining.scene_fact_records import AREAS, SceneFacts
from simsplat_core.mining.scene_facts import summary
from simsplat_core.scenario import vocabulary as voc


def test_the_road_ahead_of_the_ego(facts: SceneFacts) -> None:
    road = facts.road
    assert road.left_lane and not road.right_lane
    assert (road.lanes_our_way, road.lanes_oncoming) == (2, 2)
    assert road.intersection_ahead_m is not None and road.intersection_ahead_m < 10
    assert road.crosswalk_ahead_m is not None and road.crosswalk_ahead_m < 10
    assert road.sidewalks and 90 < road.lane_ahead_m <= 120 and road.ego_speed_mps == pytest.approx(6.2, abs=0.1)
    # past the intersection the road is plain: no crosswalk, no junction
    assert any(a <= 30 <= b for a, b in road.plain_road)
    assert road.plain_road_within(15, 40) and all(25 <= a <= b <= 40 for a, b in road.plain_road_within(15, 40))


def test_agents_carry_captions_labels_and_positions(facts: SceneFacts) -> None:
    assert {a.kind for a in facts.agents} == {"vehicle", "pedestrian", "static"}
    assert all(a.area in AREAS for a in facts.agents)
    van = facts.agent("veh_02")
    assert (van.caption, van.subtype, van.color, van.kind) == ("a white van", "van", "white", "vehicle")
    assert van.ahead_m > 0 and van.left_m > 0 and van.relation in voc.LOCATION_SECTOR.names
    oncoming = facts.agent("veh_05")  # a blue SUV driving west in the inner oncoming lane
    assert oncoming.oncoming and oncoming.area == "oncoming_lane" and oncoming.moving
    assert oncoming.lane_change_sides == ("right",) and oncoming.context == voc.IN_THE_ONCOMING_LANE
    assert math.isfinite(oncoming.room_ahead_m)  # the red sedan ahead of it
    parked = facts.agent("veh_07")
    assert not parked.moving and parked.motion == voc.PARKED and not parked.turns
    walker = facts.agent("ped_01")  # standing on the sidewalk to the ego's right
    assert walker.area == "sidewalk" and walker.relation == voc.RIGHT_OF_EGO and not walker.moving
    cone = facts.agent("static_00")
    assert cone.kind == "static" and cone.motion == "" and cone.speed_mps == 0.0
    assert {(a.category, a.subtype) for a in facts.assets} == {("vehicle", "sedan"), ("pedestrian", "adult"),
                                                              ("static", "traffic cone")}
    with pytest.raises(KeyError, match="no agent 'nobody'"):
        facts.agent("nobody")


def test_the_summary_is_text_plus_the_facts(facts: SceneFacts) -> None:
    s = summary(facts)
    assert s.facts is facts and s.seq_id == facts.seq_id
    text = s.text()
    assert "veh_02: a white van" in text and "crosswalk" in text and "assets that can be inserted" in text
    assert len(s.lines) == len(facts.agents) + 4
    assert "SceneFacts" not in repr(s)
    # the structured facts take no part in equality (the text is what a VLM reads)
    assert s == SceneSummary(s.seq_id, s.lines)
    bare = summary(dataclasses.replace(facts, assets=()))
    assert bare.lines[-1].endswith("none (no asset bank)")
