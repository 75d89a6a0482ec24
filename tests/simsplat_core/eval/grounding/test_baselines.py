"""Baseline grounders on hand-built and ground-truth-built scenes."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from simsplat_core.eval.grounding.baselines import (
    AppearanceOnlyGrounder,
    EngineGrounder,
    FrameCaptionGrounder,
    frame_captions,
    instantaneous_states,
)
from simsplat_core.eval.grounding.gt_scene import ground_truth_caption, node_ids_of
from simsplat_core.language.appearance.captioner import AppearanceCaption
from simsplat_core.language.scene_language import LanguageScene, NodeLanguage
from simsplat_core.language.text import TextEncoder
from simsplat_core.scenario.map_context import MapContext
from simsplat_core.scenario.trajectory import log_trajectories
from simsplat_core.world import generate_log
from tests.simsplat_core.language import scenes
from tests.simsplat_core.language.language_scene_factory import SMALL_WORLD


def _hand_log():
    still = np.tile([[30.0, 8.0]], (scenes.FRAMES, 1)), np.zeros(scenes.FRAMES)
    ped_walk = np.stack([np.full(scenes.FRAMES, 20.0), np.linspace(-6.0, 6.0, scenes.FRAMES)], axis=1)
    objects = {
        "turner": ("vehicle", *scenes.arc(15.0, 90.0)),
        "cruiser": ("vehicle", *scenes.straight((5.0, -3.5), 0.0, 8.0)),
        "van": ("vehicle", *still),
        "crosser": ("pedestrian", ped_walk, np.full(scenes.FRAMES, np.pi / 2)),
        "waiter": ("pedestrian", np.tile([[25.0, 9.0]], (scenes.FRAMES, 1)), np.zeros(scenes.FRAMES)),
    }
    road = scenes.polygon("drivable_area", "road", -50.0, 150.0, -7.0, 7.0)
    return scenes.scene(objects, map_features=(road,))


def _hand_scene(log, encoder: TextEncoder) -> LanguageScene:
    captions = {
        "turner": AppearanceCaption("a red sedan", "vehicle", "sedan", ("red",)),
        "cruiser": AppearanceCaption("a red sedan", "vehicle", "sedan", ("red",)),
        "van": AppearanceCaption("a blue van", "vehicle", "van", ("blue",)),
        "crosser": AppearanceCaption("a pedestrian in a green top and black trousers", "pedestrian", "adult",
                                     ("green", "black"), "green", "black"),
        "waiter": AppearanceCaption("a pedestrian in a green top and black trousers", "pedestrian", "adult",
                                    ("green", "black"), "green", "black"),
    }
    emb = encoder.encode_passages([c.text for c in captions.values()])
    nodes = tuple(
        NodeLanguage(k + 1, oid, log.object(oid).category, log.object(oid).category, emb[k], cap, None)
        for k, (oid, cap) in enumerate(captions.items())
    )
    return LanguageScene(log.seq_id, "", nodes, np.arange(scenes.FRAMES), (), None, encoder.name)


def test_instantaneous_states_follow_the_track() -> None:
    log = _hand_log()
    trajs = log_trajectories(log, MapContext.from_features(log.map_features), min_frames=1)
    turner = instantaneous_states(trajs["turner"])
    assert "turning left" in turner and "turning right" not in turner
    assert set(instantaneous_states(trajs["cruiser"])) == {"moving"}
    assert set(instantaneous_states(trajs["van"])) == {"stopped"}
    assert "walking across the road" in instantaneous_states(trajs["crosser"])
    assert set(instantaneous_states(trajs["waiter"])) == {"standing"}


def test_frame_captions_add_states_to_the_appearance(encoder: TextEncoder) -> None:
    log = _hand_log()
    scene = _hand_scene(log, encoder)
    caps = frame_captions(scene, log)
    assert "a red sedan turning left" in caps[1]
    assert caps[3] == ["a blue van stopped"]
    with pytest.raises(ValueError, match="does not belong"):
        frame_captions(LanguageScene("other", "", (), np.zeros(0), (), None, encoder.name), log)


def test_appearance_only_picks_by_appearance_and_ignores_motion(encoder: TextEncoder) -> None:
    log = _hand_log()
    scene = _hand_scene(log, encoder)
    grounder = AppearanceOnlyGrounder(encoder)
    assert grounder.ground(scene, "the blue van") == (3,)
    picked = grounder.ground(scene, "the red sedan turning left")
    assert len(picked) == 1 and picked[0] in (1, 2)
    scores = grounder.scores(scene, "the red sedan turning left")
    assert scores[1] == pytest.approx(scores[2])  # identical appearance: motion is invisible to it


def test_frame_captions_tell_look_alikes_apart(encoder: TextEncoder) -> None:
    log = _hand_log()
    scene = _hand_scene(log, encoder)
    grounder = FrameCaptionGrounder(encoder, {log.seq_id: log})
    assert grounder.ground(scene, "the red sedan turning left") == (1,)
    assert grounder.ground(scene, "the pedestrian in green crossing the road") == (4,)
    assert grounder.ground(scene, "the pedestrian in green standing still") == (5,)
    with pytest.raises(KeyError, match="no log"):
        FrameCaptionGrounder(encoder, {}).ground(scene, "anything")


def test_grounders_refuse_other_text_spaces(encoder: TextEncoder) -> None:
    log = _hand_log()
    scene = _hand_scene(log, encoder)
    other = LanguageScene(scene.seq_id, "", scene.nodes, scene.frame_indices, (), None, "clip-text")
    with pytest.raises(ValueError, match="clip-text"):
        AppearanceOnlyGrounder(encoder).ground(other, "the blue van")


def test_appearance_only_on_a_ground_truth_scene(encoder: TextEncoder) -> None:
    log = generate_log(3, SMALL_WORLD)
    captions = {o.object_id: ground_truth_caption(o) for o in log.objects}
    emb = dict(zip(captions, encoder.encode_passages([c.text for c in captions.values()])))
    ids = node_ids_of(log)
    nodes = tuple(
        NodeLanguage(ids[o.object_id], o.object_id, o.category, "", emb[o.object_id], captions[o.object_id], None)
        for o in log.objects
    )
    scene = LanguageScene(log.seq_id, "", nodes, np.arange(log.num_frames), (), None, encoder.name)
    grounder = AppearanceOnlyGrounder(encoder)
    counts: dict[str, int] = {}
    for c in captions.values():
        counts[c.text] = counts.get(c.text, 0) + 1
    unique = [o for o in log.objects if counts[captions[o.object_id].text] == 1 and o.category == "vehicle"]
    assert unique
    hits = 0
    for obj in unique:
        (node,) = grounder.ground(scene, "the " + captions[obj.object_id].text.split(" ", 1)[1])
        hits += scene.node(node).object_id == obj.object_id
    assert hits >= 0.8 * len(unique)


def test_engine_adapter() -> None:
    @dataclass
    class _Grounding:
        node_ids: tuple[int, ...]

    class _Engine:
        def ground(self, scene, text):
            return _Grounding((np.int64(4), 2))

    assert EngineGrounder(_Engine()).ground(None, "x") == (4, 2)  # type: ignore[arg-type]
