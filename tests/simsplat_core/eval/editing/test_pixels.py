"""Pixel checks on hand-made views: drawn where the world shows it, captioned as asked, removed in pixels."""

from __future__ import annotations

import dataclasses

import numpy as np

from simsplat_core.eval.editing.checks import Verdict
from simsplat_core.eval.editing.intents import AssetIntent, EditIntent, PlacementIntent
from simsplat_core.eval.editing.observation import AssetLook, EditObservation, PixelEvidence, ViewSet
from simsplat_core.eval.editing.pixels import check_pixels, check_removed, check_visible
from simsplat_core.eval.editing.world_edit import edit_world
from simsplat_core.scenario.agents import AgentStates

H, W = 20, 30


def _views(rgb: np.ndarray, ids: np.ndarray) -> ViewSet:
    return ViewSet((0,), ("front",), rgb[None, None].astype(np.float32), ids[None, None].astype(np.int32))


def _box(value: int, background: int) -> np.ndarray:
    ids = np.full((H, W), background, np.int32)
    ids[5:15, 10:20] = value
    return ids


def test_visible_needs_the_node_where_the_world_shows_the_object() -> None:
    grey = np.full((H, W, 3), 0.5)
    world = _views(grey, _box(7, 0))
    drawn = PixelEvidence(_views(grey, _box(42, -1)), world, world, {"new_0": 7}, {})
    v = Verdict()
    assert check_visible(drawn, "new_0", 42, v)
    assert v.result().passed
    elsewhere = np.full((H, W), -1, np.int32)
    elsewhere[0:4, 0:4] = 42
    v = Verdict()
    check_visible(PixelEvidence(_views(grey, elsewhere), world, world, {"new_0": 7}, {}), "new_0", 42, v)
    assert not v.result().passed and "drawn in 0%" in v.result().reason
    v = Verdict()  # the world does not show it (hidden / out of view): nothing to check in pixels
    hidden = PixelEvidence(_views(grey, _box(42, -1)), _views(grey, np.zeros((H, W))), world, {"new_0": 7}, {})
    assert not check_visible(hidden, "new_0", 42, v)
    assert v.result().passed and "not mostly in sight" in v.result().reason


def test_a_far_object_drawn_a_pixel_off_the_worlds_mesh_is_drawn_where_it_should_be() -> None:
    """A far car 10 x 4 pixels large that the reconstruction draws two pixels thin and one pixel low is drawn
    where it should be; the same drawn four pixels below it is not."""
    grey = np.full((H, W, 3), 0.5)
    truth = np.zeros((H, W), np.int32)
    truth[8:12, 10:20] = 7
    world = _views(grey, truth)
    for top, drawn_there in ((11, True), (15, False)):
        ours = np.full((H, W), -1, np.int32)
        ours[top:top + 2, 10:20] = 42
        v = Verdict()
        check_visible(PixelEvidence(_views(grey, ours), world, world, {"new_0": 7}, {}), "new_0", 42, v)
        assert v.result().passed == drawn_there, top


def test_no_view_is_judged_at_a_frame_where_the_logged_ego_drives_into_an_agent() -> None:
    grey = np.full((H, W, 3), 0.5)
    world = _views(grey, _box(7, 0))
    undrawn = PixelEvidence(_views(grey, np.full((H, W), -1)), world, world, {"new_0": 7}, {})
    v = Verdict()
    assert check_visible(undrawn, "new_0", 42, v) and not v.result().passed
    v = Verdict()  # frame 0: the ego's cameras sit inside another car, nothing there is judged
    assert not check_visible(dataclasses.replace(undrawn, ego_contact=frozenset({0})), "new_0", 42, v)
    assert v.result().passed


def test_a_sliver_of_an_object_mostly_hidden_behind_another_is_not_a_view_to_check() -> None:
    grey = np.full((H, W, 3), 0.5)
    world = _views(grey, _box(7, 0))  # 100 pixels of the object in sight
    undrawn = PixelEvidence(_views(grey, np.full((H, W), -1)), world, world, {"new_0": 7}, {},
                            world_silhouette={"new_0": np.array([[150]])})
    v = Verdict()  # two thirds of it in sight: checked, and not drawn
    assert check_visible(undrawn, "new_0", 42, v) and not v.result().passed
    v = Verdict()  # a third of it in sight, the rest behind a nearer object: not checked in pixels
    mostly_hidden = dataclasses.replace(undrawn, world_silhouette={"new_0": np.array([[300]])})
    assert not check_visible(mostly_hidden, "new_0", 42, v)
    assert v.result().passed and "not mostly in sight" in v.result().reason


def test_removed_region_must_look_like_the_scene_without_it() -> None:
    with_it, without = np.zeros((H, W, 3)), np.ones((H, W, 3))
    with_it[5:15, 10:20] = [0.8, 0.1, 0.1]
    original = _views(with_it, _box(3, 0))
    world_without = _views(without, np.zeros((H, W)))
    good = PixelEvidence(_views(without, np.full((H, W), -1)), world_without, original, {}, {"veh_00": 3})
    v = Verdict()
    check_removed(good, "veh_00", 12, v)
    assert v.result().passed
    ghost = PixelEvidence(_views(with_it, np.full((H, W), -1)), world_without, original, {}, {"veh_00": 3})
    v = Verdict()
    check_removed(ghost, "veh_00", 12, v)
    assert not v.result().passed and "looks like the scene with it" in v.result().reason
    still = PixelEvidence(_views(without, _box(12, -1)), world_without, original, {}, {"veh_00": 3})
    v = Verdict()
    check_removed(still, "veh_00", 12, v)
    assert "still rendered" in v.result().reason


def test_a_removal_is_judged_on_the_background_it_uncovers_not_on_an_agent_it_hid_all_along() -> None:
    """A silver car is removed; behind it the world shows a black car (instance 9) that the log never saw
    and, on a third of the pixels, the grey road. A reconstruction draws the never-seen car as a smear."""
    road, silver, black, smear = 0.45, 0.7, 0.05, 0.55
    with_it = np.full((H, W, 3), road)
    with_it[5:15, 10:20] = silver
    original = _views(with_it, _box(3, 0))
    without = np.full((H, W, 3), road)
    without[5:15, 10:17] = black
    ids_without = np.zeros((H, W), np.int32)
    ids_without[5:15, 10:17] = 9
    world_without = _views(without, ids_without)
    ours = np.full((H, W, 3), road)
    ours[5:15, 10:17] = smear
    v = Verdict()
    check_removed(PixelEvidence(_views(ours, np.full((H, W), -1)), world_without, original, {}, {"veh_00": 3}),
                  "veh_00", 12, v)
    assert v.result().passed, v.result().reason
    ghost = ours.copy()
    ghost[5:15, 17:20] = silver  # the removed car still shows over the road behind it
    v = Verdict()
    check_removed(PixelEvidence(_views(ghost, np.full((H, W), -1)), world_without, original, {}, {"veh_00": 3}),
                  "veh_00", 12, v)
    assert not v.result().passed and "looks like the scene with it" in v.result().reason


def test_a_removal_weighs_its_views_by_their_pixels() -> None:
    """Gone from a large near view, a car still seems there in two tiny far ones (noise): it is removed. The
    other way round it is not."""
    with_it, without = np.zeros((H, W, 3)), np.ones((H, W, 3))
    with_it[2:18, 2:28] = [0.8, 0.1, 0.1]  # near: 416 pixels
    with_it_far = np.zeros((H, W, 3))
    with_it_far[5:11, 10:17] = [0.8, 0.1, 0.1]  # far: 42 pixels
    ids_near, ids_far = np.zeros((H, W), np.int32), np.zeros((H, W), np.int32)
    ids_near[2:18, 2:28] = 3
    ids_far[5:11, 10:17] = 3

    def stack(*views: tuple[np.ndarray, np.ndarray]) -> ViewSet:
        """Views of frames 0, 1, ... (one camera) from ``(rgb, ids)`` pairs."""
        rgb = np.stack([v[0] for v in views])[:, None].astype(np.float32)
        ids = np.stack([v[1] for v in views])[:, None].astype(np.int32)
        return ViewSet(tuple(range(len(views))), ("front",), rgb, ids)

    original = stack((with_it, ids_near), (with_it_far, ids_far), (with_it_far, ids_far))
    world_without = stack(*[(without, np.zeros((H, W)))] * 3)
    none = np.full((H, W), -1)
    for ours, passed in (((without, with_it_far, with_it_far), True), ((with_it, without, without), False)):
        v = Verdict()
        check_removed(PixelEvidence(stack(*[(im, none) for im in ours]), world_without, original, {}, {"veh_00": 3}),
                      "veh_00", 12, v)
        assert v.result().passed == passed, v.result().reason


def test_caption_of_the_rendered_object_checks_colour_and_type(truths) -> None:
    """A perfect editor: the 'Gaussian' render is the world's own render of the edit (node id = instance id)."""
    truth = truths[0]
    before = AgentStates.from_log(truth.log, truth.node_of_object)
    h = float(truth.ego_heading[0])
    xy = truth.ego_xy[0] + 12.0 * np.array([np.cos(h), np.sin(h)])
    n = before.num_steps
    size = (4.85, 1.95, 1.78)
    after = before.with_agent("new_0", "vehicle", "inserted", xy=np.tile(xy, (n, 1)), heading=np.full(n, h),
                              speed=np.zeros(n), valid=np.ones(n, bool), size=size, node_id=500)
    world = edit_world(truth.world, before, after, {"new_0": AssetLook("vehicle", "SUV", "yellow", size)})
    renders = world.render(0)
    rgb = np.stack([r[3] for r in renders])[None]
    inst = np.stack([r[5] for r in renders])[None]
    cams = tuple(r[0] for r in renders)
    views = ViewSet((0,), cams, rgb.astype(np.float32), inst.astype(np.int32))
    node_ids = np.where(inst == world.instance["new_0"], 500, -1).astype(np.int32)
    evidence = PixelEvidence(ViewSet((0,), cams, rgb.astype(np.float32), node_ids), views, views,
                             dict(world.instance), {})
    obs = EditObservation(None, "", before, after)

    def intent(color: str, subtype: str) -> EditIntent:
        return EditIntent("insert", asset=AssetIntent("vehicle", subtype, color),
                          placement=PlacementIntent("in_lane", "ego", 12.0, "same"))

    ok = check_pixels(intent("yellow", "SUV"), obs, evidence)
    assert ok.passed, ok.reason
    assert "colour yellow, asked blue" in check_pixels(intent("blue", "SUV"), obs, evidence).reason
    assert "a SUV, asked a van" in check_pixels(intent("yellow", "van"), obs, evidence).reason
    # a colour the captioner names otherwise is accepted when the asked look renders the same way, not otherwise
    from simsplat_core.language.appearance.captioner import AppearanceCaption

    blue_reads_yellow = dataclasses.replace(evidence, reference_captions={
        "new_0": AppearanceCaption("a yellow SUV", "vehicle", "SUV", ("yellow",))})
    assert check_pixels(intent("blue", "SUV"), obs, blue_reads_yellow).passed
    blue_reads_blue = dataclasses.replace(evidence, reference_captions={
        "new_0": AppearanceCaption("a blue SUV", "vehicle", "SUV", ("blue",))})
    assert not check_pixels(intent("blue", "SUV"), obs, blue_reads_blue).passed
