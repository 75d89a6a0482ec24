"""QueryEngine: look-alikes told apart by motion, location or colour; groups; no-match answers; ablations."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from simsplat_core.eval.grounding.gt_scene import language_scene_from_log, node_ids_of
from simsplat_core.language.alignment.motion_training import MotionAligner, MotionAlignerConfig
from simsplat_core.language.codebooks import MotionCodebooks
from simsplat_core.language.grounding.config import QueryConfig
from simsplat_core.language.grounding.engine import QueryEngine
from simsplat_core.language.scene_language import LanguageScene
from simsplat_core.language.text import TextEncoder
from simsplat_core.scenario import vocabulary as voc
from simsplat_core.world import generate_log
from tests.simsplat_core.language.grounding.look_alikes import ID, SPECS, ids
from tests.simsplat_core.language.language_scene_factory import (
    SMALL_WORLD,
    ObjectSpec,
    hand_built_scene,
    motion_label,
    vehicle_caption,
)


@pytest.fixture(scope="module")
def codebooks(encoder: TextEncoder) -> MotionCodebooks:
    return MotionCodebooks.build(encoder)


@pytest.fixture(scope="module")
def scene(encoder: TextEncoder, codebooks: MotionCodebooks) -> LanguageScene:
    return hand_built_scene(SPECS, encoder, codebooks)


@pytest.fixture(scope="module")
def engine(encoder: TextEncoder, codebooks: MotionCodebooks) -> QueryEngine:
    return QueryEngine(encoder, QueryConfig(), codebooks=codebooks)


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        # motion-only look-alikes
        ("the red sedan turning left at the intersection", "A"),
        ("the red sedan that is going straight", "B"),
        ("Where is the red car driving straight ahead?", "B"),
        # location-only look-alikes (both turn left)
        ("the red sedan turning left on my left", "C"),
        ("the red car making a left turn in the junction", "A"),
        # colour-only look-alikes
        ("the blue sedan turning left", "D"),
        ("the blue car", "D"),
        # pedestrians: motion, garments in order, crossing direction
        ("the pedestrian in a white top and gray pants crossing the street", "P1"),
        ("the person in a white shirt and grey trousers who is standing still", "P2"),
        ("find me the pedestrian in a red shirt and blue pants", "P4"),
        ("the person wearing a blue jacket and red pants", "P3"),
        ("someone crossing from left to right", "P1"),
        # location alone, static objects
        ("the white SUV on my right", "E"),
        ("the white SUV parked behind us", "F"),
        ("the orange traffic cone", "cone"),
        ("the stopped van", "G"),
    ],
)
def test_single_queries_pick_the_right_node(engine: QueryEngine, scene: LanguageScene, text: str,
                                            expected: str) -> None:
    g = engine.ground(scene, text)
    assert g.node_ids == ids(expected), (g.message, g.ranking[:3])
    assert not g.group
    assert expected in g.message


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("every parked SUV", {"E", "F"}),
        ("all the white SUVs", {"E", "F"}),
        ("all red sedans", {"A", "B", "C"}),
        ("all cars turning left", {"A", "C", "D"}),
        ("the pedestrians walking along the sidewalk", {"P3", "P4"}),
        ("all crossing pedestrians", {"P1"}),
        ("Which vehicles are stationary?", {"E", "F", "G"}),
    ],
)
def test_group_queries_return_every_member(engine: QueryEngine, scene: LanguageScene, text: str,
                                           expected: set[str]) -> None:
    g = engine.ground(scene, text)
    assert g.group
    assert set(g.node_ids) == set(ids(*expected)), (g.message, g.ranking[:5])
    assert list(g.matches) == sorted(g.matches, key=lambda m: -m.score)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("the purple bus", "no purple bus in this scene"),
        ("the pedestrian crossing from right to left", "no pedestrian in this scene is crossing from right to left"),
        ("the red sedan that is reversing", "no red sedan in this scene is reversing"),
        ("the blue sedan going straight", "no blue sedan in this scene is going straight"),
        ("the person in a gray shirt and white pants", "no person in a gray top and white trousers in this scene"),
        ("the bicycle", "no bicycle in this scene"),
        ("the giraffe", "no giraffe in this scene"),
        ("all reversing trucks", "no truck in this scene"),
    ],
)
def test_queries_that_match_nothing_say_so(engine: QueryEngine, scene: LanguageScene, text: str, message: str) -> None:
    g = engine.ground(scene, text)
    assert g.matches == () and g.node_ids == ()
    assert g.message.startswith(message), g.message
    assert not g.masks(scene).any()


def test_crossing_pedestrian_absent(engine: QueryEngine, encoder: TextEncoder, codebooks: MotionCodebooks) -> None:
    no_crossing = hand_built_scene([s for s in SPECS if s.object_id != "P1"], encoder, codebooks)
    g = engine.ground(no_crossing, "the crossing pedestrian")
    assert g.matches == ()
    assert g.message == "no pedestrian in this scene is crossing"
    assert engine.ground(no_crossing, "all crossing pedestrians").message == "no pedestrian in this scene is crossing"


def test_named_category_is_a_hard_filter(engine: QueryEngine, scene: LanguageScene) -> None:
    g = engine.ground(scene, "the pedestrian turning left at the intersection")
    assert {m.node_id for m in g.ranking} == set(ids("P1", "P2", "P3", "P4"))
    assert g.matches == ()


def test_contradicted_colour_sinks_the_score(engine: QueryEngine, scene: LanguageScene) -> None:
    ranking = {m.node_id: m for m in engine.ground(scene, "the blue sedan turning left at the intersection").ranking}
    assert ranking[ID["D"]].score > 0.5
    assert ranking[ID["A"]].score < 0.1 * ranking[ID["D"]].score
    assert ranking[ID["A"]].motion == pytest.approx(ranking[ID["D"]].motion)


def test_ranking_scores_every_compatible_node(engine: QueryEngine, scene: LanguageScene) -> None:
    g = engine.ground(scene, "the red sedan turning left at the intersection")
    vehicles = [s.object_id for s in SPECS if s.category == "vehicle"]
    assert {m.object_id for m in g.ranking} == set(vehicles)
    assert g.ranking[0].node_id == ID["A"]
    for m in g.ranking:
        assert 0.0 <= m.score <= 1.0
        assert all(0.0 <= v <= 1.0 for v in (m.appearance, m.motion, m.location))
    candidates = [m for m in g.ranking if m.candidate]
    assert [m.score for m in candidates] == sorted((m.score for m in candidates), reverse=True)
    assert not next(m for m in g.ranking if m.object_id == "D").candidate  # narrowed out by colour


# ---------------------------------------------------------------------------------------------- ablations
def test_without_motion_motion_look_alikes_tie(engine: QueryEngine, scene: LanguageScene) -> None:
    app = engine.with_config(QueryConfig(use_motion=False, use_location=False))
    g = app.ground(scene, "the red sedan turning left")
    scores = {m.node_id: m for m in g.ranking}
    assert scores[ID["A"]].score == pytest.approx(scores[ID["B"]].score)
    assert math.isnan(scores[ID["A"]].motion) and math.isnan(scores[ID["A"]].location)
    with_motion = {m.node_id: m.score for m in engine.ground(scene, "the red sedan turning left").ranking}
    assert with_motion[ID["A"]] > 5 * with_motion[ID["B"]]


def test_without_location_location_look_alikes_tie(engine: QueryEngine, scene: LanguageScene) -> None:
    text = "the red sedan turning left on my left"
    no_loc = {m.node_id: m for m in engine.with_config(QueryConfig(use_location=False)).ground(scene, text).ranking}
    assert no_loc[ID["A"]].score == pytest.approx(no_loc[ID["C"]].score)
    assert math.isnan(no_loc[ID["C"]].location)
    app_loc = engine.with_config(QueryConfig(use_motion=False)).ground(scene, text)
    assert app_loc.node_ids == ids("C")
    assert math.isnan(app_loc.matches[0].motion)


def test_without_appearance_no_category_or_colour_filter(engine: QueryEngine, scene: LanguageScene) -> None:
    no_app = engine.with_config(QueryConfig(use_appearance=False))
    g = no_app.ground(scene, "the blue sedan turning left at the intersection")
    scores = {m.node_id: m for m in g.ranking}
    assert scores[ID["A"]].score == pytest.approx(scores[ID["D"]].score)  # colour no longer counts
    assert math.isnan(scores[ID["D"]].appearance)
    assert len(g.ranking) == len(SPECS)  # pedestrians and the cone are scored too
    assert no_app.ground(scene, "all crossing pedestrians").node_ids == ids("P1")  # motion alone still finds it


def test_a_query_with_no_usable_part(engine: QueryEngine, scene: LanguageScene) -> None:
    g = engine.with_config(QueryConfig(use_motion=False, use_location=False)).ground(scene, "something reversing")
    assert g.matches == ()
    assert g.message.startswith("nothing to compare")


# ---------------------------------------------------------------------------------------------- config, plumbing
@pytest.mark.parametrize(
    ("changes", "field"),
    [
        (dict(use_appearance=False, use_motion=False, use_location=False), "at least one"),
        (dict(use_motion="yes"), "use_motion"),
        (dict(motion_weight=-1.0), "motion_weight"),
        (dict(appearance_temperature=0.0), "appearance_temperature"),
        (dict(candidate_ratio=1.5), "candidate_ratio"),
        (dict(no_match_threshold=-0.1), "no_match_threshold"),
        (dict(group_threshold=2.0), "group_threshold"),
        (dict(color_mismatch=1.2), "color_mismatch"),
        (dict(lexicon_weight=-0.5), "lexicon_weight"),
        (dict(candidate_top_k=-1), "candidate_top_k"),
        (dict(candidate_top_k=1.5), "candidate_top_k"),
        (dict(unknown_floor=3.0), "unknown_floor"),
        (dict(label_weight=1.5), "label_weight"),
    ],
)
def test_config_validation_names_the_field(encoder: TextEncoder, changes: dict, field: str) -> None:
    config = dataclasses.replace(QueryConfig(), **changes)
    with pytest.raises(ValueError, match=field):
        config.validate()
    with pytest.raises(ValueError, match=field):
        QueryEngine(encoder, config)


def test_default_config_is_valid() -> None:
    assert QueryConfig().validate() == QueryConfig()


def test_candidate_top_k_caps_the_candidates(engine: QueryEngine, scene: LanguageScene) -> None:
    g = engine.with_config(QueryConfig(candidate_top_k=1)).ground(scene, "all red sedans")
    assert sum(m.candidate for m in g.ranking) == 1 and len(g.matches) == 1


def test_scene_in_another_text_space_is_rejected(engine: QueryEngine, scene: LanguageScene) -> None:
    other = dataclasses.replace(scene, text_encoder="some-other-encoder")
    with pytest.raises(ValueError, match="some-other-encoder"):
        engine.ground(other, "the red sedan")


def test_masks_of_a_grounding(engine: QueryEngine, scene: LanguageScene) -> None:
    g = engine.ground(scene, "every parked SUV")
    masks = g.masks(scene)
    assert masks.shape == scene.node_id_maps.shape and masks.dtype == bool
    assert masks.sum() == 2
    assert set(scene.node_id_maps[masks].tolist()) == set(ids("E", "F"))


class CountingEncoder:
    """Wraps an encoder and counts the query texts it is asked to embed."""

    def __init__(self, inner: TextEncoder) -> None:
        self.inner = inner
        self.name = inner.name
        self.dim = inner.dim
        self.queries: list[str] = []

    def encode_queries(self, texts):
        self.queries += list(texts)
        return self.inner.encode_queries(texts)

    def encode_passages(self, texts):
        return self.inner.encode_passages(texts)


def test_query_embeddings_are_cached(encoder: TextEncoder, codebooks: MotionCodebooks, scene: LanguageScene) -> None:
    counting = CountingEncoder(encoder)
    engine = QueryEngine(counting, codebooks=codebooks)
    first = engine.ground(scene, "the red sedan turning left at the intersection")
    asked = list(counting.queries)
    assert set(asked) == {"red sedan", "sedan turning left", "at the intersection"}  # parts, one batch
    second = engine.ground(scene, "the red sedan turning left at the intersection")
    assert counting.queries == asked  # nothing re-encoded
    assert second.node_ids == first.node_ids
    assert engine.cache_hits == 3 and engine.cache_misses == 3


def test_empty_query_is_rejected(engine: QueryEngine, scene: LanguageScene) -> None:
    with pytest.raises(ValueError, match="empty"):
        engine.ground(scene, "  ")


# ---------------------------------------------------------------------------------------------- a synthetic world
@pytest.fixture(scope="module")
def world(encoder: TextEncoder, codebooks: MotionCodebooks):
    log = generate_log(7, SMALL_WORLD)
    return log, language_scene_from_log(log, encoder, "ground_truth", codebooks=codebooks)


def test_world_look_alikes(engine: QueryEngine, world) -> None:
    """Seed 7's deliberate look-alikes: two silver SUVs (one parked) and two pedestrians dressed alike
    (one crossing left to right, one standing)."""
    log, scene = world
    node = node_ids_of(log)
    assert engine.ground(scene, "the silver SUV that is parked").node_ids == (node["veh_01"],)
    assert engine.ground(scene, "the silver SUV at the intersection").node_ids == (node["veh_00"],)
    crossing = engine.ground(scene, "the pedestrian in a white top and gray pants crossing from left to right")
    assert crossing.node_ids == (node["ped_00"],)
    standing = engine.ground(scene, "the pedestrian in a white shirt and gray pants standing on the sidewalk")
    assert standing.node_ids == (node["ped_01"],)
    crossing = engine.ground(scene, "the pedestrian in a white top and gray pants crossing from right to left")
    assert crossing.node_ids == ()


def test_world_masks_are_the_instance_masks(engine: QueryEngine, world) -> None:
    log, scene = world
    g = engine.ground(scene, "the silver SUV that is parked")
    masks = g.masks(scene)
    instance = log.object("veh_01").instance_id
    truth = np.stack(
        [np.stack([img.instance == instance for img in log.images if img.frame_idx == f]) for f in scene.frame_indices]
    )
    assert masks.shape == truth.shape
    assert np.array_equal(masks, truth) and masks.any()


def test_world_scene_from_captioner_and_aligner(encoder: TextEncoder, codebooks: MotionCodebooks) -> None:
    """The factory's other sources: the built-in captioner on ground-truth crops and a (briefly) trained aligner."""
    log = generate_log(11, SMALL_WORLD)
    aligner = MotionAligner.fit([log], MotionAlignerConfig(epochs=2), encoder)
    scene = language_scene_from_log(log, encoder, "captioner", aligner=aligner)
    captioned = [n for n in scene.nodes if n.caption is not None]
    assert captioned and all(n.f_app is not None and n.f_app.shape == (encoder.dim,) for n in captioned)
    assert all(n.motion is not None for n in scene.nodes if n.kind)
    assert scene.metadata["motion"] == "aligner"
    g = QueryEngine(encoder, codebooks=codebooks).ground(scene, captioned[0].caption.text)
    assert g.ranking and g.ranking[0].appearance == pytest.approx(1.0)


def test_prepare_embeds_every_part_once_so_grounding_needs_no_encoder_call(
    encoder: TextEncoder, codebooks: MotionCodebooks, scene: LanguageScene
) -> None:
    counting = CountingEncoder(encoder)
    engine = QueryEngine(counting, codebooks=codebooks)
    texts = ["the red sedan turning left at the intersection", "all pedestrians crossing on the right"]
    assert engine.prepare(texts) >= len(texts)
    misses, encoded = engine.cache_misses, len(counting.queries)
    engine.prepare(texts)
    assert engine.cache_misses == misses  # second time: all cached
    for text in texts:
        engine.ground(scene, text)
    assert len(counting.queries) == encoded  # grounding found every part it needed in the cache


@pytest.mark.parametrize(
    ("text", "expected", "group"),
    [
        ("the sedan that is not red", {"D"}, False),
        ("the SUV that isn't white", set(), False),
        ("all cars that are not white", {"A", "B", "C", "D"}, True),
        ("every vehicle other than the white ones", {"A", "B", "C", "D"}, True),
        ("the pedestrian not wearing red who is crossing the street", {"P1"}, False),
        ("all pedestrians not dressed in gray", {"P3", "P4"}, True),
    ],
)
def test_negated_colours_rule_nodes_out(engine: QueryEngine, scene: LanguageScene, text: str, expected: set[str],
                                        group: bool) -> None:
    g = engine.ground(scene, text)
    assert g.group == group
    assert set(g.node_ids) == set(ids(*expected)), (g.message, g.ranking[:5])
    if not expected:
        assert "that is not white" in g.message


def test_auto_labels_correct_an_unsure_aligner(encoder: TextEncoder, codebooks: MotionCodebooks) -> None:
    """The aligner's weights say "going straight", the node's auto-label says "changing lanes to the right":
    with the default blend the lane change is found, with the aligner alone it is not."""
    specs = [
        ObjectSpec(
            "X",
            "vehicle",
            vehicle_caption("red", "sedan"),
            motion_label("X", voc.GOING_STRAIGHT, voc.IN_FRONT_OF_EGO, voc.ON_THE_ROAD),
        ),
        ObjectSpec(
            "Y",
            "vehicle",
            vehicle_caption("blue", "SUV"),
            motion_label("Y", voc.GOING_STRAIGHT, voc.IN_FRONT_OF_EGO, voc.ON_THE_ROAD),
        ),
    ]
    scene = hand_built_scene(specs, encoder, codebooks)
    x = scene.nodes[0]
    relabelled = dataclasses.replace(
        x.motion, labels=motion_label("X", voc.CHANGING_LANE_RIGHT, voc.IN_FRONT_OF_EGO, voc.ON_THE_ROAD)
    )
    scene = dataclasses.replace(scene, nodes=(dataclasses.replace(x, motion=relabelled), *scene.nodes[1:]))
    text = "the car changing lanes to the right"
    blended = QueryEngine(encoder, QueryConfig(), codebooks=codebooks)
    assert blended.config.label_weight == 0.5
    assert blended.ground(scene, text).node_ids == (1,)
    learned_only = QueryEngine(encoder, QueryConfig(label_weight=0.0), codebooks=codebooks)
    assert learned_only.ground(scene, text).node_ids == ()
    # location: the labelled sector moves weight the same way, and a full-label engine follows the labels only
    labels_only = QueryEngine(encoder, QueryConfig(label_weight=1.0), codebooks=codebooks)
    assert labels_only.ground(scene, "the car going straight").node_ids == (2,)


def _with_field_feature(scene: LanguageScene, object_id: str, feature: np.ndarray) -> LanguageScene:
    """``scene`` with ``object_id``'s rendered appearance feature replaced (its caption kept)."""
    nodes = tuple(dataclasses.replace(n, f_app=feature) if n.object_id == object_id else n for n in scene.nodes)
    return dataclasses.replace(scene, nodes=nodes)


def _field_feature_off_by(scene: LanguageScene, object_id: str, encoder: TextEncoder, cosine_drop: float) -> np.ndarray:
    """``object_id``'s own feature turned away so that its cosine to itself drops by ``cosine_drop``."""
    own = scene.node(next(n.node_id for n in scene.nodes if n.object_id == object_id)).f_app
    other = encoder.encode_passages(["a photo of an empty street at night"])[0]
    other = other - (other @ own) * own
    other /= np.linalg.norm(other)
    cos = 1.0 - cosine_drop
    return cos * own + math.sqrt(1.0 - cos * cos) * other


def test_a_caption_that_names_every_asked_colour_keeps_the_node_a_candidate(
    engine: QueryEngine, scene: LanguageScene, encoder: TextEncoder
) -> None:
    """The field's rendered mean mixes views; a gap of about a tenth of cosine must not drop a node whose
    caption says exactly the asked colour (the only red sedan turning left at the intersection is A)."""
    blurred = _with_field_feature(scene, "A", _field_feature_off_by(scene, "A", encoder, 0.15))
    g = engine.ground(blurred, "the red car turning left at the intersection")
    assert [m.object_id for m in g.matches] == ["A"]
    # a caption that contradicts the colour is not rescued
    assert "D" not in {m.object_id for m in engine.ground(blurred, "every red sedan").matches}


def test_a_lane_phrase_is_not_a_look(engine: QueryEngine, scene: LanguageScene, encoder: TextEncoder) -> None:
    """"every vehicle stopped in their lane" names no look ("in their lane" is where it stops): every
    vehicle is equally a vehicle, so a stopped vehicle with an odd field feature is still in the group."""
    blurred = _with_field_feature(scene, "G", _field_feature_off_by(scene, "G", encoder, 0.08))
    g = engine.ground(blurred, "every vehicle stopped in their lane")
    assert "G" in {m.object_id for m in g.matches}
    assert {m.appearance for m in g.ranking} == {1.0}


def test_a_single_query_whose_colour_is_read_as_its_neighbour_finds_the_object_that_fits_the_rest(
    encoder: TextEncoder, codebooks: MotionCodebooks, engine: QueryEngine
) -> None:
    """The captioner names a sunlit silver car white: "the silver car going straight" means the white one going
    straight when no silver car does; a colour that is no neighbour, or a group query, does not reach it."""
    scene = hand_built_scene([
        ObjectSpec("silver_turning", "vehicle", vehicle_caption("silver", "sedan"),
                   motion_label("silver_turning", voc.TURNING_LEFT, voc.IN_FRONT_OF_EGO, voc.AT_THE_INTERSECTION)),
        ObjectSpec("white_straight", "vehicle", vehicle_caption("white", "hatchback"),
                   motion_label("white_straight", voc.GOING_STRAIGHT, voc.IN_FRONT_OF_EGO, voc.ON_THE_ROAD)),
        ObjectSpec("red_parked", "vehicle", vehicle_caption("red", "SUV"),
                   motion_label("red_parked", voc.PARKED, voc.RIGHT_OF_EGO, voc.BY_THE_CURB)),
    ], encoder, codebooks)
    g = engine.ground(scene, "the silver car going straight")
    assert [m.object_id for m in g.matches] == ["white_straight"]
    assert "nearest" in g.message
    assert [m.object_id for m in engine.ground(scene, "the silver car turning left").matches] == ["silver_turning"]
    assert engine.ground(scene, "the blue car going straight").matches == ()
    assert engine.ground(scene, "all the silver cars going straight").matches == ()
    assert engine.ground(scene, "the silver car").matches[0].object_id == "silver_turning"


def test_a_group_naming_a_body_style_takes_that_style_before_a_related_one(
    encoder: TextEncoder, codebooks: MotionCodebooks, engine: QueryEngine
) -> None:
    """"Delete the pickup trucks": the two captioned pickups, not the box truck (a related style stands in only
    where no node has the named one)."""
    def parked(object_id: str, colour: str, style: str) -> ObjectSpec:
        return ObjectSpec(object_id, "vehicle", vehicle_caption(colour, style),
                          motion_label(object_id, voc.PARKED, voc.RIGHT_OF_EGO, voc.BY_THE_CURB))

    pickups = [parked("red_pickup", "red", "pickup truck"), parked("white_pickup", "white", "pickup truck")]
    scene = hand_built_scene([*pickups, parked("box_truck", "yellow", "truck"), parked("sedan", "blue", "sedan")],
                             encoder, codebooks)
    assert {m.object_id for m in engine.ground(scene, "the pickup trucks").matches} == {"red_pickup", "white_pickup"}
    no_pickups = hand_built_scene([parked("box_truck", "yellow", "truck"), parked("sedan", "blue", "sedan")],
                                  encoder, codebooks)
    assert {m.object_id for m in engine.ground(no_pickups, "all the pickup trucks").matches} == {"box_truck"}
