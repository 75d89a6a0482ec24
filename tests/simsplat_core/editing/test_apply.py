"""apply_edit on a small synthetic scene: remove / replace / modify / insert by value, refusals, the delta
rebuilding the edited graph, the restricted editors."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch

from simsplat_core.editing import apply as apply_module
from simsplat_core.editing.apply import OMNIRE_LIKE, apply_edit
from simsplat_core.editing.assets.bank import AssetBank
from simsplat_core.editing.assets.procedural import procedural_asset
from simsplat_core.editing.assets.record import Asset
from simsplat_core.editing.commands import Behaviour, EditCommand, EditProgram, SpeedSpec, TargetRef
from simsplat_core.editing.delta import apply_delta
from simsplat_core.editing.draft import Draft, EditContext
from simsplat_core.editing.grounding import Grounder
from simsplat_core.editing.motion import plans as motion_plans
from simsplat_core.editing.motion.joining import JOIN_DECEL_MPS2
from simsplat_core.editing.motion.plans import first_overlap, making_room, plan_inserted, plan_modified
from simsplat_core.editing.motion.requests import FOLLOW_GAP_M, StartState
from simsplat_core.editing.ops import node_factory
from simsplat_core.editing.options import DEFAULT_OPTIONS
from simsplat_core.editing.placement.resolve import PlacedPose, distance_slack
from simsplat_core.editing.result import EditRefused
from simsplat_core.editing.traffic.room import room_reach
from simsplat_core.scenario.geometry import signed_polygon_distance
from simsplat_core.scenario.metrics import collision_steps
from simsplat_core.scene import GaussianSet
from simsplat_core.scene.nodes import OFFSETS

#: The editor without refinement: everyone but the edited agents replays the log.
NO_REFINE = dataclasses.replace(DEFAULT_OPTIONS, refinement="none")
#: The moving vehicle the tests modify, and the van they remove / replace (seed 0 of the world).
VAN = "veh_02"


def _program(*commands: dict, prompt: str = "") -> EditProgram:
    return EditProgram.model_validate({"prompt": prompt, "commands": list(commands)})


def _box_gaussians(size: tuple[float, float, float], rgb: tuple[float, float, float], n: int = 64,
                   seed: int = 0) -> GaussianSet:
    g = torch.Generator().manual_seed(seed)
    means = (torch.rand((n, 3), generator=g) - 0.5) * torch.tensor(size)
    return GaussianSet.create(means, torch.full((n,), 0.15), torch.tensor([rgb] * n), 0.9)


@pytest.fixture(scope="module")
def bank() -> AssetBank:
    car = Asset(asset_id="unit.car", category="vehicle", subtype="sedan", caption="a yellow sedan", color="yellow",
                size=(4.4, 1.9, 1.5), source_seq="unit", source_object="car",
                gaussians=_box_gaussians((4.4, 1.9, 1.5), (0.9, 0.8, 0.1)))
    walker_gs = _box_gaussians((0.5, 0.5, 1.7), (0.8, 0.1, 0.1), seed=1)
    walker_gs.extras[OFFSETS] = torch.zeros((len(walker_gs), 3, 3))
    walker = Asset(asset_id="unit.walker", category="pedestrian", subtype="adult",
                   caption="a pedestrian in a red top and black pants", color="red", size=(0.5, 0.5, 1.7),
                   source_seq="unit", source_object="walker", gaussians=walker_gs,
                   deform_frames=np.array([0, 5, 10]), deform_arc_length=np.array([0.0, 0.7, 1.4], np.float32))
    return AssetBank.from_assets([car, walker, procedural_asset("traffic cone", "orange")])


@pytest.fixture(scope="module")
def ctx(edit_log, edit_graph, edit_language, engine, bank) -> EditContext:
    return EditContext.create(edit_log, edit_graph, edit_language, engine, bank)


def _node(ctx: EditContext, object_id: str) -> int:
    return next(n.node_id for n in ctx.graph.object_nodes if n.object_id == object_id)


def _moving_vehicle(ctx: EditContext) -> str:
    """A vehicle of the log that drives over its whole track (so a stop changes it)."""
    states = ctx.states
    for r, (oid, cat) in enumerate(zip(states.object_ids, states.categories)):
        moving = states.speed[r][states.valid[r]]
        if cat == "vehicle" and oid != "ego" and moving.size >= 30 and moving.min() > 3:
            return oid
    raise AssertionError("the test world has no vehicle moving over 30 frames")


def _stop_with_crash(ctx: EditContext) -> tuple[str, EditProgram, list[str]]:
    """A vehicle whose stop makes a log agent run into it when everyone else replays the log, that stop, and
    the agents that run into it."""
    states = ctx.states
    for oid, cat in zip(states.object_ids, states.categories):
        if cat != "vehicle" or oid == "ego":
            continue
        program = _program({"op": "modify", "target": {"object_id": oid}, "behaviour": {"stop": {}}})
        try:
            replayed = apply_edit(ctx, program, NO_REFINE)
        except EditRefused:
            continue
        hits = collision_steps(replayed.states, [replayed.states.index(oid)]).pairs[0].any(axis=1)
        crashed = [replayed.states.object_ids[j] for j in np.flatnonzero(hits)]
        if crashed:
            return oid, program, crashed
    raise AssertionError("no stop in the test world makes the replaying traffic crash")


def test_remove_is_by_value(ctx):
    edited = apply_edit(ctx, _program({"op": "remove", "target": {"description": "the white van"}}))
    van = _node(ctx, VAN)
    assert edited.delta.removed_node_ids == (van,) and not edited.delta.added and not edited.delta.retracked
    assert van not in {n.node_id for n in edited.graph.nodes}
    assert VAN not in edited.states.object_ids and VAN in ctx.states.object_ids
    assert van in {n.node_id for n in ctx.graph.nodes} and ctx.graph.revision == ""  # the stored graph unchanged
    assert edited.outcomes[0].target_node_ids == (van,) and "white van" in edited.outcomes[0].summary
    assert edited.validation.as_dict()["checked"] == 0
    # unchanged nodes are shared, not copied
    kept = next(n for n in ctx.graph.object_nodes if n.node_id != van)
    assert edited.graph.node(kept.node_id) is kept


def test_remove_a_group(ctx):
    edited = apply_edit(ctx, _program({"op": "remove", "target": {"description": "orange traffic cones",
                                                                   "group": True}}))
    assert sorted(edited.delta.removed_node_ids) == sorted(_node(ctx, o) for o in ("static_00", "static_01"))


def test_not_found_is_refused_with_the_command_index(ctx):
    with pytest.raises(EditRefused) as info:
        apply_edit(ctx, _program({"op": "remove", "target": {"description": "the white van"}},
                                 {"op": "remove", "target": {"description": "the purple bus"}}))
    assert info.value.reason == "not_found" and info.value.command_index == 1
    assert "purple bus" in str(info.value)


def test_a_removed_object_cannot_be_edited_again(ctx):
    with pytest.raises(EditRefused, match="already removed") as info:
        apply_edit(ctx, _program({"op": "remove", "target": {"description": "the white van"}},
                                 {"op": "modify", "target": {"object_id": VAN}, "behaviour": {"stop": {}}}))
    assert info.value.command_index == 1


def test_replace_keeps_the_trajectory_and_fits_the_box_on_the_ground(ctx, bank):
    edited = apply_edit(ctx, _program({"op": "replace", "target": {"description": "the white van"},
                                       "asset": {"description": "a yellow sedan"}}))
    van = _node(ctx, VAN)
    (added,) = edited.delta.added
    assert edited.delta.removed_node_ids == (van,) and added.object_id == VAN and added.asset_id == "unit.car"
    assert added.node_id > max(n.node_id for n in ctx.graph.nodes)
    before, after = ctx.states.index(VAN), edited.states.index(VAN)
    assert edited.states.sources[after] == "edited" and edited.states.node_ids[after] == added.node_id
    valid = ctx.states.valid[before]
    assert np.array_equal(edited.states.valid[after], valid)
    assert np.allclose(edited.states.xy[after][valid], ctx.states.xy[before][valid])
    assert np.allclose(edited.states.size[after], bank.get("unit.car").size)
    old_ground = ctx.states.z[before] - ctx.states.size[before, 2] / 2
    new_ground = edited.states.z[after] - edited.states.size[after, 2] / 2
    assert np.allclose(old_ground[valid], new_ground[valid])
    node = edited.graph.node(added.node_id)
    assert len(node.gaussians) == len(bank.get("unit.car").gaussians) and van not in {n.node_id for n in
                                                                                     edited.graph.nodes}


def test_replace_across_categories_is_refused(ctx):
    with pytest.raises(EditRefused) as info:
        apply_edit(ctx, _program({"op": "replace", "target": {"description": "the white van"},
                                  "asset": {"description": "a pedestrian in a red top", "category": "pedestrian"}}))
    assert info.value.reason == "wrong_category"


def test_modify_stop_retracks_the_node(ctx):
    target = _moving_vehicle(ctx)
    edited = apply_edit(ctx, _program({"op": "modify", "target": {"object_id": target}, "behaviour": {"stop": {}}}),
                        NO_REFINE)
    node_id = _node(ctx, target)
    assert list(edited.delta.retracked) == [node_id] and not edited.delta.added
    assert edited.refinement is None and "refined" not in edited.states.sources
    row = edited.states.index(target)
    assert edited.states.sources[row] == "edited"
    speed = edited.states.speed[row][edited.states.valid[row]]
    assert abs(speed[-1]) < 0.1 < abs(speed[0])  # it comes to rest
    track = edited.delta.retracked[node_id]
    pose, _ = track.sample(float(edited.states.frame_idx[-1]))
    assert np.allclose(pose[:2, 3].numpy(), edited.states.xy[row, -1], atol=1e-3)
    assert [v.object_id for v in edited.validation.agents] == [target]


def test_traffic_reacts_to_a_stop_and_reacting_nodes_are_retracked(ctx):
    """Refinement (default): agents behind the stopping car react, get new tracks in the delta and are validated;
    none of them overlaps the stopped car; the delta still rebuilds the edited graph."""
    target, program, crashed = _stop_with_crash(ctx)
    edited = apply_edit(ctx, program)
    assert edited.refinement is not None and edited.refinement.mode == "full"
    reacted = edited.refinement.refined_ids
    assert set(crashed) <= set(reacted), "the agents that ran into the stopped car did not react"
    for oid in reacted:
        row = edited.states.index(oid)
        assert edited.states.sources[row] == "refined"
        node_id = int(edited.states.node_ids[row])
        if node_id >= 0:
            assert node_id in edited.delta.retracked
    checked = {v.object_id for v in edited.validation.agents}
    assert {target, *reacted} <= checked
    assert not collision_steps(edited.states, [edited.states.index(target)]).pairs.any()  # nobody hits it now
    ego = edited.states.index("ego")
    np.testing.assert_array_equal(edited.states.xy[ego], ctx.states.xy[ctx.states.index("ego")])  # not affected
    assert ctx.bank is not None
    rebuilt = apply_delta(ctx.graph, edited.delta, node_factory(ctx.bank.get, ctx.graph.frame_indices))
    assert rebuilt.revision == edited.graph.revision


def test_modify_that_changes_nothing_is_refused(ctx):
    with pytest.raises(EditRefused, match="would not change") as info:
        apply_edit(ctx, _program({"op": "modify", "target": {"object_id": _moving_vehicle(ctx)}, "behaviour": {}}))
    assert info.value.reason == "infeasible_motion"


def test_static_objects_do_not_move(ctx):
    with pytest.raises(EditRefused) as info:
        apply_edit(ctx, _program({"op": "modify", "target": {"object_id": "static_00"}, "behaviour": {"stop": {}}}))
    assert info.value.reason == "wrong_category"


def test_replace_then_modify_acts_on_the_new_node(ctx):
    target = _moving_vehicle(ctx)
    edited = apply_edit(ctx, _program({"op": "replace", "target": {"object_id": target},
                                       "asset": {"description": "a yellow sedan"}},
                                      {"op": "modify", "target": {"object_id": target}, "behaviour": {"stop": {}}}),
                        NO_REFINE)
    (added,) = edited.delta.added
    assert not edited.delta.retracked and edited.delta.removed_node_ids == (_node(ctx, target),)
    row = edited.states.index(target)
    end = float(edited.states.frame_idx[-1])
    pose, _ = added.track.sample(end)
    assert np.allclose(pose[:2, 3].numpy(), edited.states.xy[row, -1], atol=1e-3)  # the new node stops
    assert abs(edited.states.speed[row][edited.states.valid[row]][-1]) < 0.1


def test_insert_a_row_of_cones_standing_on_the_road(ctx):
    edited = apply_edit(ctx, _program({"op": "insert", "asset": {"description": "orange traffic cones", "count": 3},
                                       "placement": {"relation": "in_lane", "distance_m": 15}}))
    assert [a.object_id for a in edited.delta.added] == ["inserted_00", "inserted_01", "inserted_02"]
    assert edited.outcomes[0].new_object_ids == ("inserted_00", "inserted_01", "inserted_02")
    rows = [edited.states.index(o) for o in edited.outcomes[0].new_object_ids]
    for r in rows:
        assert edited.states.sources[r] == "inserted" and edited.states.valid[r].all()
        assert np.ptp(edited.states.xy[r], axis=0).max() < 1e-9  # standing still
        assert np.allclose(edited.states.z[r], edited.states.size[r, 2] / 2)  # on the ground (z = 0 here)
    starts = np.stack([edited.states.xy[r, 0] for r in rows])
    assert np.all(np.linalg.norm(np.diff(starts, axis=0), axis=1) > 0.5)  # a row, not a pile
    assert ctx.map_ctx.facts(starts, np.zeros(len(starts))).on_drivable.all()  # cones go on the road
    assert {a.node_id for a in edited.delta.added} <= {n.node_id for n in edited.graph.nodes}
    assert [v.object_id for v in edited.validation.agents if v.source == "inserted"] == list(
        edited.outcomes[0].new_object_ids)  # (the traffic reacting to the cones is validated too)


def test_ego_reacts_to_a_cone_on_its_path_unless_told_to_replay(ctx):
    e = ctx.states.index("ego")
    x, y = ctx.states.xy[e, 15]  # where the ego's log takes it at step 15 (world frame = first ego pose)
    program = _program({"op": "insert", "asset": {"description": "an orange traffic cone"},
                        "placement": {"relation": "absolute", "position": [float(x), float(y), 0.0]}})
    ego_fixed = apply_edit(ctx, program, dataclasses.replace(DEFAULT_OPTIONS, ego_reacts=False))
    assert collision_steps(ego_fixed.states, [e]).static.any()  # the ego replays its log through the cone
    assert not ego_fixed.ego_poses(ctx.log.ego_poses)  # and renders come from the log's cameras
    reacting = apply_edit(ctx, program)  # the default: the ego reacts
    r = reacting.states.index("ego")
    assert reacting.states.sources[r] == "refined"
    assert not collision_steps(reacting.states, [r]).static.any()  # it stops short of the cone
    poses = reacting.ego_poses(ctx.log.ego_poses)
    assert poses and all(p.shape == (4, 4) for p in poses.values())
    k = max(poses)
    assert np.allclose(poses[k][:2, 3], reacting.states.xy[r, int(np.searchsorted(reacting.states.frame_idx, k))])


def test_insert_a_vehicle_drives_along_its_lane(ctx):
    edited = apply_edit(ctx, _program({"op": "insert", "asset": {"description": "a yellow sedan"},
                                       "placement": {"relation": "in_lane", "distance_m": 20}}))
    row = edited.states.index("inserted_00")
    valid = edited.states.valid[row]
    assert edited.states.speed[row][valid].mean() > 2.0  # drives by default
    match = ctx.lanes.nearest(edited.states.xy[row][valid], edited.states.heading[row][valid])
    assert np.nanmax(match.distance) < 1.0  # on a lane centre line, oriented along it


def test_inserting_a_car_on_the_sidewalk_is_refused(ctx):
    with pytest.raises(EditRefused) as info:
        apply_edit(ctx, _program({"op": "insert", "asset": {"description": "a yellow sedan"},
                                  "placement": {"relation": "on_sidewalk"}}))
    assert info.value.reason == "infeasible_placement"


def test_the_delta_rebuilds_the_edited_graph(ctx, bank):
    edited = apply_edit(ctx, _program({"op": "replace", "target": {"description": "the white van"},
                                       "asset": {"description": "a yellow sedan"}},
                                      {"op": "modify", "target": {"object_id": _moving_vehicle(ctx)},
                                       "behaviour": {"stop": {}}},
                                      {"op": "insert", "asset": {"description": "orange traffic cones", "count": 2}},
                                      {"op": "remove", "target": {"description": "the stop sign", "group": True}}))
    rebuilt = apply_delta(ctx.graph, edited.delta, node_factory(bank.get, ctx.graph.frame_indices))
    assert rebuilt.revision == edited.graph.revision
    for t in (0.0, 7.5, 20.0, 39.0):
        a, b = edited.graph.at(t), rebuilt.at(t)
        assert a.node_slices == b.node_slices
        assert torch.allclose(a.means, b.means)


def test_omnire_like_takes_ids_only(ctx):
    with pytest.raises(EditRefused, match="object ids") as info:
        apply_edit(ctx, _program({"op": "remove", "target": {"description": "the white van"}}), OMNIRE_LIKE)
    assert info.value.reason == "unsupported"
    edited = apply_edit(ctx, _program({"op": "remove", "target": {"object_id": VAN}}), OMNIRE_LIKE)
    assert edited.delta.removed_node_ids == (_node(ctx, VAN),)


def test_without_a_bank_inserts_are_refused_naming_the_command(edit_log, edit_graph, edit_language, engine):
    bare = EditContext.create(edit_log, edit_graph, edit_language, engine, None)
    with pytest.raises(EditRefused, match="simsplat assets build") as info:
        apply_edit(bare, _program({"op": "insert", "asset": {"description": "a yellow sedan"}}))
    assert info.value.reason == "no_asset"


def test_insert_a_pedestrian_walks_on_the_sidewalk(ctx):
    from simsplat_core.scene.nodes import NonRigidNode

    edited = apply_edit(ctx, _program({"op": "insert", "asset": {"description": "a pedestrian in a red top",
                                                                  "category": "pedestrian"},
                                       "placement": {"relation": "on_sidewalk", "distance_m": 10}}))
    row = edited.states.index("inserted_00")
    valid = edited.states.valid[row]
    assert edited.states.speed[row][valid].max() > 0.8  # walks by default
    first = int(np.argmax(valid))
    facts = ctx.map_ctx.facts(edited.states.xy[row, first:first + 1], edited.states.heading[row, first:first + 1])
    assert facts.on_sidewalk.all()
    (added,) = edited.delta.added
    node = edited.graph.node(added.node_id)
    assert isinstance(node, NonRigidNode) and added.arc_length is not None  # the gait follows the new path


def test_editor_parses_and_applies_a_prompt(ctx):
    from simsplat_core.editing.apply import Editor

    edited = Editor(ctx).edit("remove the white van")
    assert edited.prompt == "remove the white van"
    assert edited.delta.removed_node_ids == (_node(ctx, VAN),)
    with pytest.raises(EditRefused) as info:
        Editor(ctx).edit("paint the sky green")
    assert info.value.reason in ("unsupported", "not_found")


def test_a_speed_up_the_traffic_ahead_takes_away_is_refused_not_silently_dropped(ctx):
    """Every vehicle asked for 12 m/s either gets near it, or is refused naming the traffic only when a free road
    would have let it get there (a plain physical limit, 4 s of log at comfortable acceleration, is no refusal)."""
    from simsplat_core.editing.motion.plans import SPEED_REACHED_SHARE

    outcomes = {"reached": 0, "refused": 0, "limited": 0}
    for oid, category in zip(ctx.states.object_ids, ctx.states.categories, strict=True):
        if category != "vehicle" or oid == "ego":
            continue
        try:
            edited = apply_edit(ctx, EditProgram(commands=[EditCommand(
                op="modify", target=TargetRef(object_id=oid),
                behaviour=Behaviour(speed=SpeedSpec(mode="absolute", value=12.0)))]))
        except EditRefused as refused:
            assert refused.reason == "infeasible_motion", str(refused)
            assert "traffic ahead" in str(refused) and "12.0 m/s" in str(refused)
            outcomes["refused"] += 1
            continue
        top = float(np.abs(edited.states.speed[edited.states.index(oid)]).max())
        outcomes["reached" if top >= SPEED_REACHED_SHARE * 12.0 else "limited"] += 1
    assert outcomes["reached"] > 0 and outcomes["refused"] > 0, outcomes


def _parked_off_lane(ctx: EditContext) -> str:
    """A vehicle of the log standing still over its whole track away from every lane (parked at the kerb)."""
    from simsplat_core.editing.placement.resolve import LANE_SNAP_M

    states = ctx.states
    for r, (oid, cat) in enumerate(zip(states.object_ids, states.categories, strict=True)):
        valid = states.valid[r]
        if cat != "vehicle" or oid == "ego" or not valid[0] or np.abs(states.speed[r][valid]).max() > 0.1:
            continue
        if ctx.lanes.nearest(states.xy[r, :1], max_dist_m=LANE_SNAP_M).lane[0] < 0:
            return oid
    raise AssertionError("the test world has no vehicle parked off the lanes")


def test_a_car_inserted_behind_a_parked_car_parks_in_line_with_it(ctx):
    anchor = _parked_off_lane(ctx)
    edited = apply_edit(ctx, _program({"op": "insert", "asset": {"description": "a yellow sedan"},
                                       "placement": {"relation": "behind", "anchor": {"object_id": anchor}}}))
    st = edited.states
    row, a = st.index("inserted_00"), st.index(anchor)
    assert st.valid[row].all() and np.abs(st.speed[row]).max() == 0.0  # parked: it does not drive off
    assert np.ptp(st.xy[row], axis=0).max() < 1e-9
    heading = st.heading[a, 0]
    forward, left = np.array([np.cos(heading), np.sin(heading)]), np.array([-np.sin(heading), np.cos(heading)])
    rel = st.xy[row, 0] - st.xy[a, 0]
    assert rel @ forward < -(st.size[a, 0] + st.size[row, 0]) / 2  # behind it, clear of it
    assert abs(rel @ left) < 1e-6 and np.cos(st.heading[row, 0] - heading) > 0.999  # in line, facing its way
    assert "parked" in edited.outcomes[0].summary
    # asked to move, it does -- or, when the parked car right in front of it leaves it no room to hold the speed,
    # the insert is refused naming that car (not carried out braking to a halt at once)
    try:
        moving = apply_edit(ctx, _program({"op": "insert", "asset": {"description": "a yellow sedan"},
                                           "placement": {"relation": "behind", "anchor": {"object_id": anchor}},
                                           "behaviour": {"speed": {"mode": "absolute", "value": 5.0}}}))
    except EditRefused as refused:
        assert refused.reason == "infeasible_motion" and anchor in str(refused) and "slows it" in str(refused)
    else:
        assert np.abs(moving.states.speed[moving.states.index("inserted_00")]).min() > 4.0


def test_a_pedestrian_inserted_to_cross_starts_at_the_road_edge(ctx):
    command = {"op": "insert", "asset": {"description": "a pedestrian in a red top", "category": "pedestrian"},
               "placement": {"relation": "behind", "distance_m": 5}}
    standing = apply_edit(ctx, _program(command))
    crossing = apply_edit(ctx, _program({**command, "behaviour": {"cross_street": True, "jaywalk": True}}))
    start = [e.states.xy[e.states.index("inserted_00"), 0] for e in (standing, crossing)]
    inside = [signed_polygon_distance(p[None], ctx.map_ctx.drivable)[0] for p in start]
    assert 0.0 < inside[1] <= 1.0 < inside[0]  # on the road by its edge, not in the ego's lane
    ego = ctx.log.ego_poses[0]
    assert (np.linalg.inv(ego) @ np.r_[start[1], 0.0, 1.0])[0] == pytest.approx(
        (np.linalg.inv(ego) @ np.r_[start[0], 0.0, 1.0])[0], abs=0.5)  # as far behind


def test_accelerate_ends_faster_or_is_refused_naming_the_traffic(ctx):
    """"Speed up" without a speed asks ``ACCELERATE_DELTA_MPS`` more than the start speed: every vehicle either
    ends clearly faster than it started, or is refused naming the traffic ahead (never carried out ending slower,
    as when it braked for traffic its log passed, or took a logged curve slower than the log)."""
    from simsplat_core.editing.behaviours.longitudinal import ACCELERATE_DELTA_MPS

    outcomes = {"faster": 0, "refused": 0}
    for oid, category in zip(ctx.states.object_ids, ctx.states.categories, strict=True):
        row = ctx.states.index(oid)
        if category != "vehicle" or oid == "ego" or not ctx.states.valid[row].any():
            continue
        start = abs(float(ctx.states.speed[row][np.flatnonzero(ctx.states.valid[row])[0]]))
        try:
            edited = apply_edit(ctx, EditProgram(commands=[EditCommand(
                op="modify", target=TargetRef(object_id=oid), behaviour=Behaviour(longitudinal="accelerate"))]))
        except EditRefused as refused:
            assert refused.reason == "infeasible_motion" and "traffic ahead" in str(refused), str(refused)
            outcomes["refused"] += 1
            continue
        end = abs(float(edited.states.speed[edited.states.index(oid)][-1]))
        assert end >= start + 0.5 * ACCELERATE_DELTA_MPS, (oid, start, end)  # clearly faster than it started
        outcomes["faster"] += 1
    assert outcomes["faster"] > 0, outcomes


@pytest.mark.parametrize("speed", [6.0, 9.0, 12.0])
def test_a_car_inserted_at_a_speed_holds_it_or_is_refused_naming_the_car_ahead(ctx, speed):
    """An inserted car asked to drive at a speed holds it from the start (within the tolerance), placed within the
    distance slack of the asked distance where it can, or is refused naming what slows it: never carried out
    while the traffic ahead holds it back."""
    from simsplat_core.editing.motion.plans import SPEED_HELD_SHARE, SPEED_HELD_TOL_MPS

    tol = max(SPEED_HELD_TOL_MPS, SPEED_HELD_SHARE * speed)
    outcomes = {"held": 0, "moved": 0, "refused": 0}
    for distance in (8.0, 12.0, 16.0, 25.0):
        try:
            edited = apply_edit(ctx, _program({"op": "insert", "asset": {"description": "a yellow sedan"},
                                               "placement": {"relation": "in_lane", "distance_m": distance},
                                               "behaviour": {"speed": {"mode": "absolute", "value": speed}}}))
        except EditRefused as refused:
            assert refused.reason == "infeasible_motion" and "slows it to" in str(refused), str(refused)
            outcomes["refused"] += 1
            continue
        row = edited.states.index("inserted_00")
        assert float(np.abs(edited.states.speed[row]).min()) >= speed - tol - 1e-6, (distance, speed)
        ahead = float(np.dot(edited.states.xy[row, 0] - ctx.states.xy[ctx.states.index("ego"), 0],
                             [np.cos(ctx.states.heading[0, 0]), np.sin(ctx.states.heading[0, 0])]))
        assert abs(ahead - distance) <= distance_slack(distance) + 0.5, (ahead, distance)
        outcomes["moved" if "instead of" in edited.outcomes[0].summary else "held"] += 1
    assert outcomes["held"] + outcomes["moved"] > 0, outcomes


@pytest.mark.parametrize(("behaviour", "refusal"), [(Behaviour(delay_s=1.5), "cannot set off 1.5 s later"),
                                                    (Behaviour(start_time_s=1.5), "cannot wait until 1.5 s")])
def test_a_delayed_start_sets_off_later_or_is_refused_saying_why(ctx, behaviour, refusal):
    """A delay (or a start time: "wait 1.5 s before moving") of a vehicle that stands in its log is refused as
    meaningless; every moving one either sets off after the delay, or is refused naming the agent in its way
    (covering under ``DELAY_PROGRESS_SHARE`` of what a free road allows; never carried out standing where it was
    the whole time)."""
    st = ctx.states
    outcomes = {"kept": 0, "refused": 0, "standing": 0}
    for r, (oid, category) in enumerate(zip(st.object_ids, st.categories, strict=True)):
        if category != "vehicle" or oid == "ego" or st.valid[r].sum() < 30:
            continue
        valid = np.flatnonzero(st.valid[r])
        log_moved = float(np.linalg.norm(st.xy[r, valid[-1]] - st.xy[r, valid[0]]))
        try:
            edited = apply_edit(ctx, EditProgram(commands=[EditCommand(
                op="modify", target=TargetRef(object_id=oid), behaviour=behaviour)]))
        except EditRefused as refused:
            assert refused.reason == "infeasible_motion", str(refused)
            if "cannot start at 1.5 s: the edit begins at" in str(refused):
                assert st.times[valid[0]] > 1.5, str(refused)  # a start time before the agent is there
                continue
            if log_moved < 1.0:
                assert "does not move in the log" in str(refused)
                outcomes["standing"] += 1
            else:
                assert refusal in str(refused) and "replaying its log" in str(refused) \
                    or "holds it back" in str(refused), str(refused)
                outcomes["refused"] += 1
            continue
        assert log_moved >= 1.0, oid  # a parked car is never "delayed"
        j = edited.states.index(oid)
        got = float(np.linalg.norm(np.diff(edited.states.xy[j, valid], axis=0), axis=1).sum())
        assert got > 1.0, (oid, got)  # it does set off
        early = valid[st.times[valid] <= 1.5 - 0.2]
        assert np.linalg.norm(edited.states.xy[j, early] - edited.states.xy[j, early[:1]], axis=1).max() < 0.2
        outcomes["kept"] += 1
    assert outcomes["kept"] > 0 and outcomes["standing"] > 0, outcomes


def test_an_asked_faster_speed_is_met_at_the_end_or_refused_naming_the_traffic(ctx):
    """"50 % faster": a carried-out edit ends (mean over the last 0.5 s, not just its last step) within the
    tolerance of the asked speed, unless even a free road could not get there in the time left; otherwise it
    is refused naming the traffic ahead (before, ending at 0.8 of it while still accelerating passed)."""
    from simsplat_core.editing.motion.plans import SPEED_HELD_SHARE, SPEED_HELD_TOL_MPS, end_speed

    st = ctx.states
    outcomes = {"met": 0, "refused": 0, "limited": 0}
    for r, (oid, category) in enumerate(zip(st.object_ids, st.categories, strict=True)):
        if category != "vehicle" or oid == "ego" or st.valid[r].sum() < 30:
            continue
        start = abs(float(st.speed[r][np.flatnonzero(st.valid[r])[0]]))
        if start < 2.0:
            continue
        target = 1.5 * start
        try:
            edited = apply_edit(ctx, EditProgram(commands=[EditCommand(
                op="modify", target=TargetRef(object_id=oid),
                behaviour=Behaviour(speed=SpeedSpec(mode="factor", value=1.5)))]))
        except EditRefused as refused:
            assert refused.reason == "infeasible_motion" and "traffic ahead" in str(refused), str(refused)
            outcomes["refused"] += 1
            continue
        j = edited.states.index(oid)
        end = end_speed(edited.states.speed[j], edited.states.times)
        met = end >= target - max(SPEED_HELD_TOL_MPS, SPEED_HELD_SHARE * target)
        # not met: only a physical limit (a curve ahead, the time left) that a free road has too -- then it still
        # ends no slower than its log does
        assert met or end >= end_speed(st.speed[r], st.times) - 0.1, (oid, start, end)
        outcomes["met" if met else "limited"] += 1
    assert outcomes["met"] > 0, outcomes


def test_an_insert_the_traffic_cannot_take_moves_within_its_slack(ctx, monkeypatch):
    """A cone a few metres in front of the moving ego leaves it no way to stop: the room search moves the cone
    along the lane (within its reach for the asked distance) to where the reacting ego can stop for it, and
    says so; without the search the ego runs into it."""
    program = _program({"op": "insert", "asset": {"description": "an orange traffic cone"},
                        "placement": {"relation": "in_lane", "distance_m": 4}})
    edited = apply_edit(ctx, program)
    e = edited.states.index("ego")
    assert edited.states.sources[e] == "refined"
    assert not collision_steps(edited.states, [e]).static.any()
    assert "so that the traffic can react" in edited.outcomes[0].summary
    cone = edited.states.index("inserted_00")
    ahead = float(np.linalg.norm(edited.states.xy[cone, 0] - ctx.states.xy[e, 0]))
    assert 0.1 < abs(ahead - 4.0) <= room_reach(4.0) + 0.1
    monkeypatch.setattr(apply_module, "ROOM_SHIFTS", ())
    as_asked = apply_edit(ctx, program)
    assert collision_steps(as_asked.states, [as_asked.states.index("ego")]).static.any() or not \
        as_asked.validation.ok


def test_a_pedestrian_on_the_carriageway_makes_no_room_for_a_planned_car(ctx):
    """Under full refinement a crossing pedestrian still on the kerb gives way (the plan may ignore it); one
    already walking on the carriageway cannot clear the lane by stopping, so the plan keeps clear of it."""
    draft = Draft.start(ctx, Grounder(ctx.language, ctx.engine, ctx.graph, DEFAULT_OPTIONS.grounding),
                        DEFAULT_OPTIONS)
    e = ctx.states.index("ego")
    start = StartState(0, ctx.states.xy[e, 0] + np.array([-30.0, 0.0]), float(ctx.states.heading[e, 0]), 6.0)
    walkers = [r for r, c in enumerate(ctx.states.categories) if c == "pedestrian"
               and np.linalg.norm(ctx.states.xy[r, -1] - ctx.states.xy[r, 0]) > 1.0]
    facts = ctx.map_ctx.facts(ctx.states.xy[walkers, 0], ctx.states.heading[walkers, 0])
    row = walkers[int(np.flatnonzero(facts.on_sidewalk | ~facts.on_drivable)[0])]  # on the kerb at the start
    assert ctx.states.object_ids[row] in making_room(draft, start, ())
    xy = ctx.states.xy.copy()
    xy[row] += ctx.states.xy[e, 0] + np.array([10.0, 0.0]) - ctx.states.xy[row, 0]  # on the ego's lane
    draft.states = dataclasses.replace(ctx.states, xy=xy)
    assert ctx.states.object_ids[row] not in making_room(draft, start, ())


def test_a_pedestrian_put_behind_someone_standing_walks_round_or_waits_behind_them(ctx):
    """Inserted right behind a pedestrian who stands through the log, a walker would walk into them: it steps
    round them where the pavement allows, else stops behind them (or, already too close to walk, stands), and
    says which."""
    for anchor in ("ped_01", "ped_05"):
        edited = apply_edit(ctx, _program({"op": "insert", "asset": {"description": "a pedestrian in a red top"},
                                           "placement": {"relation": "behind", "anchor": {"object_id": anchor},
                                                         "distance_m": 1.0}}))
        row = edited.states.index("inserted_00")
        assert not collision_steps(edited.states, [row]).pairs.any()
        summary = edited.outcomes[0].summary
        assert f"and back to pass {anchor}" in summary or "stands in its way" in summary, summary


def test_an_inserted_walker_sidesteps_someone_walking_towards_it(ctx, bank, monkeypatch):
    """Someone walks head-on along the inserted walker's own path: it steps aside to pass them and back onto its
    path, and says so; without the sidestep the two walk into each other."""
    walker = bank.assets[[a.category for a in bank.assets].index("pedestrian")]
    placed = PlacedPose(np.array([2.0, -5.4]), 0.0, None, 0.0, "sidewalk")
    grounder = Grounder(ctx.language, ctx.engine, ctx.graph, DEFAULT_OPTIONS.grounding)
    free = plan_inserted(Draft.start(ctx, grounder, DEFAULT_OPTIONS), None, walker, placed, 0, 0)
    row = next(r for r, c in enumerate(ctx.states.categories) if c == "pedestrian")
    xy, heading, valid = ctx.states.xy.copy(), ctx.states.heading.copy(), ctx.states.valid.copy()
    xy[row] = free.xy[::-1] + np.array([0.0, 0.2])  # back along the walker's path, 0.2 m to its left
    heading[row] = free.heading[::-1] + np.pi
    valid[row] = True
    draft = Draft.start(ctx, grounder, DEFAULT_OPTIONS)
    draft.states = dataclasses.replace(ctx.states, xy=xy, heading=heading, valid=valid)
    passing = plan_inserted(draft, None, walker, placed, 0, 0)
    assert "and back to pass" in passing.description
    assert first_overlap(draft.states, passing, np.asarray(walker.size), ("ego",)) is None
    monkeypatch.setattr(motion_plans, "SIDESTEPS_M", ())
    head_on = plan_inserted(draft, None, walker, placed, 0, 0)
    assert first_overlap(draft.states, head_on, np.asarray(walker.size), ("ego",)) is not None


def test_a_walker_told_to_run_sidesteps_someone_walking_towards_it(ctx, monkeypatch):
    """A pedestrian told to walk faster along its path meets someone coming the other way on it: it steps aside
    to pass (the traffic model keeps an edited walker fixed, so it must keep clear itself)."""
    states = ctx.states
    walker = next(r for r, c in enumerate(states.categories) if c == "pedestrian"
                  and float(np.linalg.norm(states.xy[r, -1] - states.xy[r, 0])) > 3.0)
    other = next(r for r, c in enumerate(states.categories) if c == "pedestrian" and r != walker)
    fast = Behaviour(speed=SpeedSpec(value=2.5))
    grounder = Grounder(ctx.language, ctx.engine, ctx.graph, DEFAULT_OPTIONS.grounding)
    alone = plan_modified(Draft.start(ctx, grounder, DEFAULT_OPTIONS), walker, fast, None, 0, "the walker")
    xy, heading, valid = states.xy.copy(), states.heading.copy(), states.valid.copy()
    xy[other] = alone.xy[::-1] + 0.2 * np.stack([-np.sin(alone.heading[::-1]), np.cos(alone.heading[::-1])], 1)
    heading[other], valid[other] = alone.heading[::-1] + np.pi, True
    valid[[r for r in range(states.num_agents) if r not in (walker, other)]] = False  # nobody else about
    draft = Draft.start(ctx, grounder, DEFAULT_OPTIONS)
    draft.states = dataclasses.replace(states, xy=xy, heading=heading, valid=valid)
    ids = ("ego", states.object_ids[walker])
    passing = plan_modified(draft, walker, fast, None, 0, "the walker")
    assert "to pass" in passing.description and first_overlap(draft.states, passing, states.size[walker], ids) is None
    aside = np.linalg.norm(passing.xy[:, None] - alone.xy[None], axis=2).min(axis=1)  # [T] off its own path
    assert aside.max() > 0.6 and aside[-1] < 0.2
    monkeypatch.setattr(motion_plans, "SIDESTEPS_M", ())
    head_on = plan_modified(draft, walker, fast, None, 0, "the walker")
    assert first_overlap(draft.states, head_on, states.size[walker], ids) is not None


def test_an_inserted_walker_steps_round_a_sign_on_its_pavement(ctx, bank):
    """A sign stands on the inserted walker's pavement, in its way: it steps round it and back onto its path,
    keeping to the pavement, instead of stopping in front of it for good."""
    walker = bank.assets[[a.category for a in bank.assets].index("pedestrian")]
    placed = PlacedPose(np.array([2.0, -5.4]), 0.0, None, 0.0, "sidewalk")
    grounder = Grounder(ctx.language, ctx.engine, ctx.graph, DEFAULT_OPTIONS.grounding)
    row = next(r for r, c in enumerate(ctx.states.categories) if c not in ("vehicle", "pedestrian", "cyclist"))
    valid = ctx.states.valid.copy()
    valid[[r for r, o in enumerate(ctx.states.object_ids) if o != "ego"]] = False  # nobody else about
    draft = Draft.start(ctx, grounder, DEFAULT_OPTIONS)
    draft.states = dataclasses.replace(ctx.states, valid=valid)
    free = plan_inserted(draft, None, walker, placed, 0, 0)
    assert free.description == "default motion"
    xy, heading = ctx.states.xy.copy(), ctx.states.heading.copy()
    xy[row], heading[row], valid[row] = free.xy[15], free.heading[15], True  # on its path, 1.5 s ahead
    draft.states = dataclasses.replace(ctx.states, xy=xy, heading=heading, valid=valid)
    walk = plan_inserted(draft, None, walker, placed, 0, 0)
    assert f"and back to pass {ctx.states.object_ids[row]}" in walk.description, walk.description
    assert first_overlap(draft.states, walk, np.asarray(walker.size), ("ego",)) is None
    assert walk.xy[-1, 0] > free.xy[15, 0] + 1.0  # got past it
    was = ctx.map_ctx.facts(free.xy, free.heading).on_sidewalk
    assert (ctx.map_ctx.facts(walk.xy, walk.heading).on_sidewalk | ~was).all()


def test_a_car_inserted_close_behind_a_standing_car_creeps_up_instead_of_running_into_it(ctx, bank):
    """A car put a few metres behind one that stands through the log starts no faster than it can still stop
    from behind it, and so does not run into it (it used to start at cruising speed)."""
    car = bank.assets[[a.category for a in bank.assets].index("vehicle")]
    states = ctx.states
    standing = next(r for r, c in enumerate(states.categories) if c == "vehicle" and states.valid[r].all()
                    and np.abs(states.speed[r]).max() < 0.1 and ctx.lanes.nearest(
                        states.xy[r, :1], states.heading[r, :1], max_dist_m=1.0).lane[0] >= 0)
    forward = np.array([np.cos(states.heading[standing, 0]), np.sin(states.heading[standing, 0])])
    gap = 5.0
    xy = states.xy[standing, 0] - forward * (gap + states.size[standing, 0] / 2 + car.size[0] / 2)
    placed = PlacedPose(xy, float(states.heading[standing, 0]), None, 0.0, "lane")
    grounder = Grounder(ctx.language, ctx.engine, ctx.graph, DEFAULT_OPTIONS.grounding)
    motion = plan_inserted(Draft.start(ctx, grounder, DEFAULT_OPTIONS), None, car, placed, 0, 0)
    assert 0.0 < motion.speed[0] <= np.sqrt(2.0 * JOIN_DECEL_MPS2 * (gap - FOLLOW_GAP_M)) + 1e-6
    assert first_overlap(states, motion, np.asarray(car.size), ("ego",)) is None


def test_an_agent_standing_in_its_log_that_the_edit_sets_moving_can_set_off_later(ctx):
    """"Cross the street 2 s later" sets off a pedestrian who stands through its log; a delay alone does not (there
    is nothing to start later)."""
    st = ctx.states
    standing = [o for r, (o, c) in enumerate(zip(st.object_ids, st.categories, strict=True))
                if c == "pedestrian" and st.valid[r].sum() >= 30
                and np.linalg.norm(np.ptp(st.xy[r, st.valid[r]], axis=0)) < 0.5]
    assert standing, "the fixture scene has a standing pedestrian"
    oid = standing[0]
    edited = apply_edit(ctx, EditProgram(commands=[EditCommand(
        op="modify", target=TargetRef(object_id=oid), behaviour=Behaviour(cross_street=True, delay_s=2.0))]))
    r = edited.states.index(oid)
    valid = np.flatnonzero(edited.states.valid[r])
    xy, t = edited.states.xy[r, valid], edited.states.times[valid]
    assert np.linalg.norm(xy[t <= t[0] + 1.9] - xy[0], axis=1).max() < 0.2  # waits the 2 s where it stood
    assert np.linalg.norm(xy[-1] - xy[0]) > 1.0  # then sets off across
    with pytest.raises(EditRefused, match="does not move in the log"):
        apply_edit(ctx, EditProgram(commands=[EditCommand(
            op="modify", target=TargetRef(object_id=oid), behaviour=Behaviour(delay_s=2.0))]))
