"""The four edit ops on a working copy of a scene (``editing.draft.Draft``), used by ``editing.apply``.

Each op grounds what it needs, changes the draft and returns a :class:`~simsplat_core.editing.result.CommandOutcome`,
or raises :class:`~simsplat_core.editing.result.EditRefused`.

Heights: a box centre sits half the box height above the ground (an inserted object stands on its anchor's
ground, ``editing.placement.resolve``; a replacement on the replaced object's).
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Callable

import numpy as np
import torch

from simsplat_core.editing.assets.nodes import asset_node
from simsplat_core.editing.assets.record import Asset
from simsplat_core.editing.commands import Behaviour, EditCommand, Placement
from simsplat_core.editing.draft import Draft
from simsplat_core.editing.motion.plans import (
    Motion,
    anchor_pose,
    asked_cruise_speed,
    blocker_ahead,
    changed_motion,
    describe_behaviour,
    no_room_note,
    plan_inserted,
    plan_modified,
    resolve,
    speed_shortfall,
)
from simsplat_core.editing.placement.resolve import (
    NUDGE_M,
    NUDGE_STEP_M,
    AnchorPose,
    PlacedPose,
    distance_slack,
    place_clear_row,
    shift_row,
)
from simsplat_core.editing.result import AddedNode, CommandOutcome, EditRefused
from simsplat_core.editing.traffic.room import movable, room_reach
from simsplat_core.scenario.agents import EGO_ID, AgentStates
from simsplat_core.scenario.trajectory import agent_kind
from simsplat_core.scene.nodes import ObjectNode
from simsplat_core.scene.pose_track import PoseTrack
from simsplat_core.scene.transforms import poses_from_boxes

logger = logging.getLogger(__name__)

#: Why an inserted row stands off its asked spot when ``Draft.room_shift`` moved it (``editing.apply``'s room search).
ROOM_NOTE = "(within the asked distance's slack) so that the traffic can react without a crash"
#: Placements that name the kind of area the object stands on, which the room search must keep.
ASKED_AREAS: dict[str, str] = {"on_crosswalk": "crosswalk", "on_sidewalk": "sidewalk", "on_road": "road"}
#: Default gap between the objects of a row, by asset category (metres between box edges).
ROW_GAP_M = {"static": 1.5, "vehicle": 3.0, "pedestrian": 0.8}


def asset_category(category: str) -> str:
    """The asset category (``vehicle`` / ``pedestrian`` / ``static``) of a log object category."""
    kind = agent_kind(category)
    return kind if kind is not None else "static"


def track_from_states(states: AgentStates, row: int, z: np.ndarray | None = None) -> PoseTrack:
    """The box pose track of agent ``row`` on the states' frames (``z [T]`` overrides the box-centre heights);
    present where the agent is valid."""
    zz = states.z[row] if z is None else np.broadcast_to(np.asarray(z, np.float64), states.z[row].shape)
    center = np.concatenate([states.xy[row], zz[:, None]], axis=1)
    poses = torch.as_tensor(poses_from_boxes(center, states.heading[row]), dtype=torch.float32)
    return PoseTrack(states.frame_idx.astype(np.float64), poses, torch.as_tensor(states.valid[row]))


def node_factory(asset_of: Callable[[str], Asset], graph_frames: np.ndarray) -> Callable[[AddedNode], ObjectNode]:
    """``AddedNode -> ObjectNode``: the asset ``asset_of(added.asset_id)`` (the assets an edit retrieved, or
    ``AssetBank.get`` when rebuilding a stored edit) on the added node's track (``editing.assets.nodes.asset_node``)."""

    def build(added: AddedNode) -> ObjectNode:
        return asset_node(asset_of(added.asset_id), node_id=added.node_id, object_id=added.object_id,
                          track=added.track, arc_length=added.arc_length, graph_frames=graph_frames)

    return build


# ---------------------------------------------------------------------------------------------- ops
def remove(draft: Draft, command: EditCommand, index: int) -> CommandOutcome:
    """Drop every node the target grounds to, and its agent."""
    assert command.target is not None
    found = draft.grounder.ground(command.target, removed=draft.gone, command_index=index)
    for node_id, object_id in zip(found.node_ids, found.object_ids):
        draft.drop_stored(node_id)
        draft.gone.add(node_id)
        if object_id in draft.states.object_ids:
            draft.states = draft.states.without([object_id])
    summary = "removed " + "; ".join(draft.describe(n) for n in found.node_ids)
    return CommandOutcome(command, target_node_ids=found.node_ids, changed_object_ids=found.object_ids,
                          summary=summary)


def replace(draft: Draft, command: EditCommand, index: int) -> CommandOutcome:
    """Each target keeps its trajectory and gets the asset's appearance and box size, kept on the ground."""
    assert command.target is not None and command.asset is not None
    found = draft.grounder.ground(command.target, removed=draft.gone, command_index=index)
    lines, changed = [], []
    for node_id, object_id in zip(found.node_ids, found.object_ids):
        row = draft.row_of(object_id)
        kind = asset_category(draft.states.categories[row])
        spec = command.asset if command.asset.category is not None else command.asset.model_copy(
            update={"category": kind})
        asset = draft.retrieve(spec, index)
        if asset.category != kind:
            raise EditRefused(f"cannot replace {draft.describe(node_id)} with {asset.caption!r}: replace keeps the "
                              f"trajectory, so the new object must be a {kind} too", reason="wrong_category",
                              command_index=index)
        old_h, new_h = float(draft.states.size[row, 2]), float(asset.size[2])
        z = draft.states.z[row] - old_h / 2.0 + new_h / 2.0  # same ground, the asset's own height
        track = track_from_states(draft.states, row, z)
        new_id = draft.take_node_id()
        draft.drop_stored(node_id)
        draft.replaced[node_id] = new_id
        draft.added.append(AddedNode(node_id=new_id, object_id=object_id, asset_id=asset.asset_id,
                                     category=asset.category, track=track, arc_length=None))
        draft.states = draft.states.with_agent(
            object_id, draft.states.categories[row], "edited", xy=draft.states.xy[row],
            heading=draft.states.heading[row], speed=draft.states.speed[row], valid=draft.states.valid[row],
            size=np.asarray(asset.size, np.float64), z=z, node_id=new_id)
        lines.append(f"replaced {draft.describe(node_id)} with {asset.caption} (asset {asset.asset_id}, node {new_id})")
        changed.append(object_id)
    return CommandOutcome(command, target_node_ids=found.node_ids, changed_object_ids=tuple(changed),
                          summary="; ".join(lines))


#: Where an insert without a placement goes: ahead of the ego, where its front cameras see it.
DEFAULT_AHEAD_M = 12.0


def _default_placement(category: str) -> Placement:
    """Pedestrians on the sidewalk, everything else in the ego lane, :data:`DEFAULT_AHEAD_M` ahead."""
    if category == "pedestrian":
        return Placement(relation="on_sidewalk", distance_m=DEFAULT_AHEAD_M)
    return Placement(relation="in_lane", lane="same", distance_m=DEFAULT_AHEAD_M)


def _where(placement: Placement, anchor: str) -> str:
    """The placement in words ("in the same lane 12 m ahead of the ego", "left of veh_02 (node 16): ...")."""
    gap = f"{placement.distance_m:g} m " if placement.distance_m is not None else ""
    rel = placement.relation
    if rel == "absolute":
        return f"at {tuple(round(v, 2) for v in placement.position or ())} in the ego frame"
    if rel == "in_lane":
        return f"in the {placement.lane or 'same'} lane {gap}ahead of {anchor}"
    if rel.startswith("on_"):
        return f"{rel.replace('_', ' the ', 1)} {gap}{'ahead of' if gap else 'near'} {anchor}"
    return f"{gap}{rel.replace('_', ' ')} {anchor}"


def insert(draft: Draft, command: EditCommand, index: int) -> CommandOutcome:
    """Add the asset (a row of ``count``) at the placement, moving as the behaviour says (module docstring)."""
    assert command.asset is not None
    if command.asset.category is not None:
        draft.options.check_insert_category(command.asset.category, index)
    asset = draft.retrieve(command.asset, index)
    draft.options.check_insert_category(asset.category, index)
    placement = command.placement or _default_placement(asset.category)
    anchor_ids: tuple[int, ...] = ()
    anchor = None
    step = min(int(np.searchsorted(draft.states.frame_idx, placement.frame or 0)), draft.states.num_steps - 1)
    if placement.anchor is not None and not placement.anchor.is_ego:
        found = draft.grounder.ground(placement.anchor, removed=draft.gone, command_index=index, role="anchor")
        anchor_ids = found.node_ids[:1]
        anchor = anchor_pose(draft, found.object_ids[0], draft.describe(anchor_ids[0]), step, index)
    gap = command.asset.spacing_m if command.asset.spacing_m is not None else ROW_GAP_M[asset.category]
    first = resolve(draft, placement, asset, anchor, step, index, command.behaviour)
    target = asked_cruise_speed(command.behaviour, asset.category)
    if target is not None:
        first = _spot_holding_speed(draft, command, placement, asset, anchor, step, index, first, target)
    new_ids, lines = [], []
    reach = NUDGE_M if placement.distance_m is None else distance_slack(placement.distance_m)
    try:
        row = place_clear_row(first, count=command.asset.count, spacing_m=gap, size=asset.size,
                              lanes=draft.ctx.lanes, map_ctx=draft.ctx.map_ctx, occupied=draft.states,
                              frame=int(draft.states.frame_idx[step]), reach=reach, category=asset.category)
        if draft.room_shift and movable(command):
            row = shift_row(row, draft.room_shift * room_reach(placement.distance_m), spacing_m=gap,
                            size=asset.size, lanes=draft.ctx.lanes,
                            map_ctx=draft.ctx.map_ctx, occupied=draft.states,
                            frame=int(draft.states.frame_idx[step]), why=ROOM_NOTE,
                            keep_area=ASKED_AREAS.get(placement.relation))
    except EditRefused as exc:
        raise EditRefused(str(exc), reason=exc.reason, command_index=index) from exc
    for placed in row:
        motion = plan_inserted(draft, command.behaviour, asset, placed, step, index)
        if target is not None:
            _check_speed_held(draft, command, asset, motion, target, step, index, "")
        object_id = draft.new_object_id()
        node_id = draft.take_node_id()
        z = np.full(draft.states.num_steps, placed.z)
        draft.added.append(AddedNode(node_id=node_id, object_id=object_id, asset_id=asset.asset_id,
                                     category=asset.category, track=motion.track(draft.states.frame_idx, z),
                                     arc_length=motion.arc_length))
        draft.states = draft.states.with_agent(object_id, asset.category, "inserted", xy=motion.xy,
                                               heading=motion.heading, speed=motion.speed, valid=motion.valid,
                                               size=np.asarray(asset.size, np.float64), z=z, node_id=node_id)
        new_ids.append(object_id)
        lines.append(f"{object_id} (node {node_id}, {placed.area}{', ' + placed.note if placed.note else ''}, "
                     f"{motion.description})")
    where = _where(placement, draft.describe(anchor_ids[0]) if anchor_ids else "the ego")
    summary = f"inserted {asset.caption} (asset {asset.asset_id}) {where} as {'; '.join(lines)}"
    return CommandOutcome(command, anchor_node_ids=anchor_ids, new_object_ids=tuple(new_ids),
                          changed_object_ids=tuple(new_ids), summary=summary)


def _spot_holding_speed(draft: Draft, command: EditCommand, placement: Placement, asset: Asset,
                        anchor: AnchorPose | None, step: int, index: int, first: PlacedPose,
                        target: float) -> PlacedPose:
    """``first`` when an inserted vehicle asked to drive at ``target`` m/s can hold that speed there behind the
    traffic ahead (which replays its log); else the spot nearest the asked distance (within
    ``placement.distance_slack``, not nudged) where it can; else ``EditRefused`` naming the vehicle ahead."""
    motion = plan_inserted(draft, command.behaviour, asset, first, step, index)
    if speed_shortfall(motion, target, step)[1] < 0:
        return first
    asked = placement.distance_m
    slack = distance_slack(asked) if asked is not None else 0.0
    if asked is not None:
        offsets = np.arange(NUDGE_STEP_M, slack + NUDGE_STEP_M / 2.0, NUDGE_STEP_M)
        for delta in sorted([*offsets.tolist(), *(-offsets).tolist()], key=lambda d: (abs(d), d)):
            distance = asked + delta
            if distance <= 0.0:
                continue
            try:
                placed = resolve(draft, placement.model_copy(update={"distance_m": distance}), asset, anchor, step,
                                 index, command.behaviour)
                if placed.note:  # nudged to clear something: no longer at ``distance``
                    continue
                moved = plan_inserted(draft, command.behaviour, asset, placed, step, index)
            except EditRefused:
                continue
            if speed_shortfall(moved, target, step)[1] < 0:
                note = (f"placed {distance:g} m instead of {asked:g} m, where it can hold {target:.1f} m/s behind "
                        "the traffic ahead")
                return dataclasses.replace(placed, note=f"{placed.note}; {note}" if placed.note else note)
    within = f" (nor anywhere within {slack:g} m of the asked {asked:g} m)" if asked is not None else ""
    refusal = _speed_refusal(draft, command, asset, motion, target, step, index, within)
    return first if refusal is None else _raise(refusal)


def _raise(err: EditRefused) -> PlacedPose:
    raise err


def _check_speed_held(draft: Draft, command: EditCommand, asset: Asset, motion: Motion, target: float, step: int,
                      index: int, within: str) -> None:
    refusal = _speed_refusal(draft, command, asset, motion, target, step, index, within)
    if refusal is not None:
        raise refusal


def _speed_refusal(draft: Draft, command: EditCommand, asset: Asset, motion: Motion, target: float, step: int,
                   index: int, within: str) -> EditRefused | None:
    """The refusal of an inserted vehicle asked to drive at ``target`` m/s whose plan cannot hold it, naming the
    vehicle ahead that holds it back (``editing.motion.plans.no_room_note``); ``None``: held."""
    short, at = speed_shortfall(motion, target, step)
    if at < 0:
        return None
    row = blocker_ahead(draft.states, motion, at)
    if row is None:
        who = "the traffic ahead"
    elif draft.states.object_ids[row] == EGO_ID:
        who = "the ego vehicle ahead"
    else:
        try:
            who = draft.describe(int(draft.states.node_ids[row])) + " ahead of it"
        except KeyError:
            who = f"{draft.states.categories[row]} {draft.states.object_ids[row]!r} ahead of it"
    return EditRefused(f"cannot insert {asset.caption} driving at {target:.1f} m/s "
                       f"({describe_behaviour(command.behaviour)}){within}: {who} slows it to {target - short:.1f} "
                       f"m/s (from {draft.states.times[at]:.1f} s on; {no_room_note(draft)})",
                       reason="infeasible_motion", command_index=index)


def modify(draft: Draft, command: EditCommand, index: int) -> CommandOutcome:
    """Re-plan each target's trajectory from its log trajectory by the behaviour (and/or move it)."""
    assert command.target is not None
    found = draft.grounder.ground(command.target, removed=draft.gone, command_index=index)
    lines, changed = [], []
    behaviour = command.behaviour or Behaviour()
    for node_id, object_id in zip(found.node_ids, found.object_ids):
        row = draft.row_of(object_id)
        category = draft.states.categories[row]
        if agent_kind(category) is None:
            raise EditRefused(f"{draft.describe(node_id)} is a {category}, which does not move; motion edits "
                              "apply to vehicles and pedestrians", reason="wrong_category", command_index=index)
        if behaviour.is_empty and command.placement is None:
            raise EditRefused(f"the edit would not change how {draft.describe(node_id)} moves: give a speed, stop, "
                              "turn, lane change, delay, ...", reason="infeasible_motion", command_index=index)
        motion = plan_modified(draft, row, behaviour, command.placement, index, draft.describe(node_id))
        if not changed_motion(draft.states, row, motion):
            raise EditRefused(f"the edit would not change how {draft.describe(node_id)} moves",
                              reason="infeasible_motion", command_index=index)
        z = draft.states.z[row]
        draft.set_track(node_id, motion.track(draft.states.frame_idx, z))
        draft.states = draft.states.with_agent(object_id, category, "edited", xy=motion.xy, heading=motion.heading,
                                               speed=motion.speed, valid=motion.valid, size=draft.states.size[row],
                                               z=z, node_id=int(draft.states.node_ids[row]))
        lines.append(f"{draft.describe(node_id)}: {motion.description}")
        changed.append(object_id)
    return CommandOutcome(command, target_node_ids=found.node_ids, changed_object_ids=tuple(changed),
                          summary="modified " + "; ".join(lines))


OPS: dict[str, Callable[[Draft, EditCommand, int], CommandOutcome]] = {
    "insert": insert, "remove": remove, "replace": replace, "modify": modify}


def apply_command(draft: Draft, command: EditCommand, index: int) -> CommandOutcome:
    """Apply one command to ``draft`` (raises ``EditRefused`` with ``command_index = index``)."""
    return OPS[command.op](draft, command, index)
