"""Grounding of edit targets: descriptions, groups, ids, removed nodes, not-found messages, editor modes."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.editing.commands import EditCommand, Placement, TargetRef
from simsplat_core.editing.grounding import Grounder
from simsplat_core.editing.options import CHATSIM_LIKE, OMNIRE_LIKE, EditorOptions
from simsplat_core.editing.result import EditRefused


@pytest.fixture(scope="module")
def grounder(edit_language, engine, edit_graph) -> Grounder:
    return Grounder(edit_language, engine, edit_graph)


def _node(graph, object_id: str) -> int:
    return next(n.node_id for n in graph.object_nodes if n.object_id == object_id)


def test_description_grounds_to_the_described_object(grounder, edit_graph):
    found = grounder.ground(TargetRef(description="the white van"))
    assert found.object_ids == ("veh_02",)
    assert found.node_ids == (_node(edit_graph, "veh_02"),)


def test_group_grounds_every_match_and_skips_removed_nodes(grounder, edit_graph):
    cones = grounder.ground(TargetRef(description="orange traffic cone", group=True))
    assert sorted(cones.object_ids) == ["static_00", "static_01"]
    first = _node(edit_graph, "static_00")
    rest = grounder.ground(TargetRef(description="orange traffic cone", group=True), removed={first})
    assert rest.object_ids == ("static_01",)


def test_not_found_names_what_the_scene_has(grounder):
    with pytest.raises(EditRefused) as info:
        grounder.ground(TargetRef(description="the purple bus"), command_index=2)
    assert info.value.reason == "not_found" and info.value.command_index == 2
    assert "purple bus" in str(info.value)
    assert "closest:" in str(info.value) or "this scene has" in str(info.value)


def test_removed_target_is_not_found_again(grounder, edit_graph):
    van = _node(edit_graph, "veh_02")
    with pytest.raises(EditRefused, match="already removed"):
        grounder.ground(TargetRef(description="the white van"), removed={van})
    with pytest.raises(EditRefused, match="already removed"):
        grounder.ground(TargetRef(node_id=van), removed={van})


def test_ids_resolve_in_every_mode_and_descriptions_not_in_ids_mode(edit_language, engine, edit_graph):
    ids_only = Grounder(edit_language, engine, edit_graph, mode="ids")
    van = _node(edit_graph, "veh_02")
    assert ids_only.ground(TargetRef(object_id="veh_02")).node_ids == (van,)
    assert ids_only.ground(TargetRef(node_id=van)).object_ids == ("veh_02",)
    with pytest.raises(EditRefused, match="object ids, not descriptions") as info:
        ids_only.ground(TargetRef(description="the white van"))
    assert info.value.reason == "unsupported"
    with pytest.raises(EditRefused, match="no node 999") as missing:
        ids_only.ground(TargetRef(node_id=999))
    assert missing.value.reason == "not_found"


def test_attribute_mode_ignores_motion_words(edit_language, engine, edit_graph):
    """ChatSim-like grounding matches colour and type; the full engine also scores the motion part."""
    attributes = Grounder(edit_language, engine, edit_graph, mode="attributes")
    assert attributes.engine.config.use_motion is False and attributes.engine.config.use_location is False
    assert attributes.ground(TargetRef(description="the white van")).object_ids == ("veh_02",)


def test_editor_options_refuse_what_the_baselines_cannot_do():
    remove = EditCommand(op="remove", target=TargetRef(description="the white van"))
    modify = EditCommand(op="modify", target=TargetRef(description="the white van"),
                         behaviour={"speed": {"value": 5}})
    crosswalk = EditCommand(op="insert", asset={"description": "a cone"},
                            placement=Placement(relation="on_crosswalk"))
    walker = EditCommand(op="insert", asset={"description": "a pedestrian", "category": "pedestrian"})
    CHATSIM_LIKE.check(remove, 0)
    with pytest.raises(EditRefused, match="does not modify") as info:
        CHATSIM_LIKE.check(modify, 1)
    assert info.value.reason == "unsupported" and info.value.command_index == 1
    with pytest.raises(EditRefused, match="on_crosswalk"):
        CHATSIM_LIKE.check(crosswalk, 0)
    OMNIRE_LIKE.check(modify, 0)
    with pytest.raises(EditRefused, match="cannot insert pedestrians"):
        OMNIRE_LIKE.check(walker, 0)
    EditorOptions().check(walker, 0)
    with pytest.raises(ValueError, match="unknown"):
        EditorOptions(ops=frozenset({"teleport"}))


def test_a_named_colour_the_match_does_not_have_is_refused_not_substituted(grounder):
    """The search may rank the nearest colour first; an edit must not act on it ("the purple van" is no blue van)."""
    assert grounder.ground(TargetRef(description="the van")).object_ids == ("veh_02",)  # the van is white
    for wrong in ("the purple van", "the red van", "the black van"):
        with pytest.raises(EditRefused) as info:
            grounder.ground(TargetRef(description=wrong))
        assert info.value.reason == "not_found" and wrong.split()[1] in str(info.value)


def test_colours_agree_with_captions_by_name_and_by_clothing():
    from simsplat_core.editing.grounding import colors_agree
    from simsplat_core.language.appearance.captioner import AppearanceCaption
    from simsplat_core.language.grounding.parse import parse_query

    car = AppearanceCaption("a blue SUV", "vehicle", "SUV", ("blue",))
    person = AppearanceCaption("a pedestrian in a red top and black trousers", "pedestrian", "adult",
                               ("red", "black"), upper_color="red", lower_color="black")
    assert colors_agree(parse_query("the blue SUV"), car)
    assert not colors_agree(parse_query("the purple SUV"), car)
    assert colors_agree(parse_query("the SUV"), car) and colors_agree(parse_query("the purple SUV"), None)
    assert colors_agree(parse_query("the person in a red top and black trousers"), person)
    assert not colors_agree(parse_query("the person in a green top"), person)
    assert not colors_agree(parse_query("the person in a red top and blue trousers"), person)


def test_the_lead_vehicle_is_found_by_geometry_or_refused(edit_language, engine, edit_graph, edit_log):
    from simsplat_core.motion.motion_map import motion_map_of
    from simsplat_core.scenario.agents import AgentStates
    from simsplat_core.scenario.lead import lead_vehicle

    states, lanes = AgentStates.from_log(edit_log), motion_map_of(edit_log).lanes
    assert lead_vehicle(states, lanes) is None  # this world's ego has no moving vehicle ahead in its lane
    with_geometry = Grounder(edit_language, engine, edit_graph, states=states, lanes=lanes)
    with pytest.raises(EditRefused, match="no lead vehicle in this scene") as refused:
        with_geometry.ground(TargetRef(description="the lead vehicle"), command_index=0)
    assert refused.value.reason == "not_found"
    car = states.index("veh_02")
    ahead = states.with_agent("lead", "vehicle", "log", xy=states.xy[0] + 12.0 * np.stack(
        [np.cos(states.heading[0]), np.sin(states.heading[0])], axis=1), heading=states.heading[0],
        speed=states.speed[0], valid=states.valid[0], size=states.size[car])
    assert lead_vehicle(ahead, lanes) == ahead.index("lead")
