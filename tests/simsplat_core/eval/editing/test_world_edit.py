"""The world re-renders an edit: removing changes only the object's pixels, inserting makes pixels of a new id."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.eval.editing.observation import AssetLook, ego_contact_frames
from simsplat_core.eval.editing.world_edit import AWAY_M, edit_world, trajectory_of
from simsplat_core.scenario.agents import AgentStates


@pytest.fixture(scope="module")
def scene(truths):
    truth = truths[0]
    return truth, AgentStates.from_log(truth.log, truth.node_of_object)


def _busiest(truth, object_id: str) -> tuple[int, int]:
    """(frame, camera index) where the log shows the most pixels of ``object_id``."""
    inst = truth.facts[object_id].instance_id
    best = max(((img.frame_idx, truth.log.cameras.index(img.camera), int((img.instance == inst).sum()))
                for img in truth.log.images), key=lambda x: x[2])
    return best[0], best[1]


def test_removing_an_agent_changes_only_its_pixels(scene) -> None:
    truth, before = scene
    oid = "veh_04"
    frame, cam = _busiest(truth, oid)
    edited = edit_world(truth.world, before, before.without([oid]), {})
    assert oid not in edited.instance and len(edited.world.agents) == len(truth.world.agents) - 1
    assert len(truth.world.agents) == len({a.object_id for a in truth.world.agents})  # the original is untouched
    original = truth.world.render(frame)[cam]
    after = edited.render(frame)[cam]
    mask = original[5] == truth.facts[oid].instance_id
    changed = np.abs(original[3] - after[3]).max(axis=-1) > 1e-6
    assert mask.sum() > 500
    assert changed[mask].mean() > 0.9  # the object is gone from its pixels
    outside = changed & ~mask
    assert outside.sum() < mask.sum()
    assert original[6][outside].all() and after[6][outside].all()  # outside it only the ground changed: its shadow
    assert not (changed & ~mask & (original[5] != 0)).any()  # no other object's pixels


def test_inserting_a_native_car_makes_pixels_of_its_instance(scene) -> None:
    truth, before = scene
    h = float(truth.ego_heading[0])
    xy = truth.ego_xy[0] + 12.0 * np.array([np.cos(h), np.sin(h)])
    n = before.num_steps
    after = before.with_agent("new_0", "vehicle", "inserted", xy=np.tile(xy, (n, 1)), heading=np.full(n, h),
                              speed=np.zeros(n), valid=np.ones(n, bool), size=(4.6, 1.8, 1.45), node_id=99)
    edited = edit_world(truth.world, before, after, {"new_0": AssetLook("vehicle", "sedan", "yellow",
                                                                        (4.6, 1.8, 1.45))})
    assert "new_0" in edited.native
    inst = edited.instance["new_0"]
    pixels = [int((r[5] == inst).sum()) for r in edited.render(0)]
    assert pixels[truth.log.cameras.index("front")] > 300
    alone = edited.world.silhouette_pixels(0, [inst])  # nothing in front of it: its silhouette is what shows
    assert [int(alone[c][0]) for c in truth.log.cameras] == pixels
    # a second car parked right in front of it (from the ego) hides most of it; its silhouette is unchanged
    nearer = truth.ego_xy[0] + 8.0 * np.array([np.cos(h), np.sin(h)])
    blocked = after.with_agent("new_1", "vehicle", "inserted", xy=np.tile(nearer, (n, 1)), heading=np.full(n, h),
                               speed=np.zeros(n), valid=np.ones(n, bool), size=(4.6, 1.8, 1.45), node_id=98)
    look = AssetLook("vehicle", "sedan", "yellow", (4.6, 1.8, 1.45))
    hidden = edit_world(truth.world, before, blocked, {"new_0": look, "new_1": look})
    front = truth.log.cameras.index("front")
    seen = int((hidden.render(0)[front][5] == hidden.instance["new_0"]).sum())
    whole = int(hidden.world.silhouette_pixels(0, [hidden.instance["new_0"]])["front"][0])
    assert whole == pixels[front] and seen < 0.5 * whole
    # procedural kinds are native (their own meshes); an unknown kind is drawn by a stand-in and reported
    for subtype, native in (("barrel", True), ("mailbox", False)):
        static = after.with_agent("new_0", "static", "inserted", xy=np.tile(xy, (n, 1)), heading=np.full(n, h),
                                  speed=np.zeros(n), valid=np.ones(n, bool), size=(0.6, 0.6, 0.9), node_id=99)
        drawn = edit_world(truth.world, before, static, {"new_0": AssetLook("static", subtype, "orange",
                                                                            (0.6, 0.6, 0.9))})
        assert ("new_0" in drawn.native) == native and bool(drawn.notes) != native
        assert (np.stack([r[5] for r in drawn.render(0)]) == drawn.instance["new_0"]).sum() > 20
    with pytest.raises(ValueError, match="no look"):
        edit_world(truth.world, before, after, {})


def test_moved_agent_follows_its_edited_trajectory_and_absent_steps_hide_it(scene) -> None:
    truth, before = scene
    oid = "veh_04"
    row = before.index(oid)
    valid = before.valid[row].copy()
    valid[:10] = False
    after = before.with_agent(oid, "vehicle", "edited", xy=before.xy[row] + [0.0, 1.0], heading=before.heading[row],
                              speed=before.speed[row], valid=valid, size=before.size[row],
                              node_id=int(before.node_ids[row]))
    edited = edit_world(truth.world, before, after, {})
    moved = next(a for a in edited.world.agents if a.object_id == oid)
    assert np.allclose(moved.traj["xy"][10:], before.xy[row, 10:] + [0.0, 1.0])
    assert np.all(moved.traj["xy"][:10] == AWAY_M)
    frame, cam = 5, truth.log.cameras.index("front")
    assert not (edited.render(frame)[cam][5] == edited.instance[oid]).any()
    traj = trajectory_of(after, row)
    assert traj["s"][-1] == pytest.approx(np.linalg.norm(np.diff(before.xy[row, 10:], axis=0), axis=1).sum())


def test_frames_where_the_logged_ego_touches_an_agent(scene) -> None:
    truth, before = scene
    assert ego_contact_frames(before) == frozenset()  # the log's own traffic keeps clear of the ego
    n = before.num_steps
    h = float(truth.ego_heading[0])
    ahead = truth.ego_xy[0] + 3.0 * np.array([np.cos(h), np.sin(h)])  # a car standing 3 m ahead of the ego's start
    after = before.with_agent("new_0", "vehicle", "inserted", xy=np.tile(ahead, (n, 1)), heading=np.full(n, h),
                              speed=np.zeros(n), valid=np.ones(n, bool), size=(4.6, 1.8, 1.45), node_id=99)
    touching = ego_contact_frames(after)
    assert 0 in touching and len(touching) < n  # the ego drives into it, then on past its place

