"""A store holding only the ingested Argoverse 2 sample (no camera images): stage decisions, alignment from
its tracks and map, and motion/location queries through the tasks and ``simsplat query --json``
(skipped when ../shared/data is absent; no Prefect start)."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from flows.cli import app
from flows.pipeline import align_targets, plan_alignment
from simsplat_core.data.av2 import load_av2_log
from simsplat_core.language.alignment.motion_training import MotionAlignerConfig
from storage import ArtifactStore, write_scene_log
from storage.language_scenes import read_language_scene
from tasks.align import align_scene, train_motion_aligner
from tasks.query import answer_query
from tasks.stages import NO_IMAGES, decide_stages, plan_stages

pytestmark = pytest.mark.shared_data

AV2_LOG = "av2/sensor-log-7fab2350"
SEQ = "sensor-log-7fab2350"


@pytest.fixture(scope="module")
def av2_store(shared_data, tmp_path_factory):
    """The AV2 sample ingested into a fresh store, an aligner trained on it and its language scene."""
    store = ArtifactStore(tmp_path_factory.mktemp("av2-store"))
    log = load_av2_log(shared_data / AV2_LOG)
    assert log.seq_id == SEQ
    write_scene_log(store, log)
    model = train_motion_aligner.fn(store.root, [SEQ], MotionAlignerConfig(epochs=20))
    stored = align_scene.fn(store.root, SEQ, None, model.model_hash)
    return store, model, stored


def test_stage_decisions_follow_what_a_log_holds(av2_store):
    store = av2_store[0]
    (plan,) = plan_stages(store.root, [SEQ])
    assert (plan.source, plan.images, plan.reconstructs, plan.evaluates) == ("av2", 0, False, False)
    assert plan.skipped() == {"reconstruct": NO_IMAGES, "evaluate": NO_IMAGES}
    synthetic = decide_stages("s", "synthetic", 120)
    assert synthetic.reconstructs and synthetic.evaluates and synthetic.skipped() == {}
    waymo = decide_stages("w", "waymo", 5)
    assert waymo.reconstructs and not waymo.evaluates and "real log" in waymo.skip_evaluate
    # the alignment plan: the aligner trains on every stored log, the image-less log is aligned from its tracks
    alignment = plan_alignment(store.root)
    assert alignment.training_seq_ids == [SEQ] and alignment.targets == [(SEQ, None)]
    assert align_targets(alignment.stages, []) == [(SEQ, None)]
    with pytest.raises(ValueError, match="no complete log \\['nope'\\]"):
        plan_alignment(store.root, ["nope"])


def test_image_less_log_gets_a_stored_language_scene_from_its_tracks(av2_store):
    store, model, stored = av2_store
    assert not stored.skipped and stored.scene_hash == ""
    loaded = read_language_scene(store, SEQ)
    scene = loaded.scene
    assert loaded.model_hash == model.model_hash and loaded.records is None and loaded.autoencoder is None
    assert scene.node_id_maps is None and scene.scene_hash == ""
    movers = [n for n in scene.nodes if n.motion is not None]
    assert len(movers) == 103  # the auto-labeller's movable objects of the sample
    assert all(n.f_app is None and n.caption is None for n in scene.nodes)
    assert {n.motion.labels.motion for n in movers} >= {"parked", "changing_lane_left", "walking_along"}
    again = align_scene.fn(store.root, SEQ, None, model.model_hash)
    assert again.skipped and again.language_hash == stored.language_hash


def test_motion_and_location_queries_on_av2(av2_store):
    store = av2_store[0]
    lane_change = answer_query(store.root, SEQ, "the vehicle changing lanes to the left")
    (node_id,) = lane_change.grounding.node_ids
    node = lane_change.scene.node(node_id)
    assert node.category == "vehicle" and node.motion.labels.motion == "changing_lane_left"
    assert lane_change.png_uri == "" and lane_change.frame is None  # no cameras to draw on

    parked = answer_query(store.root, SEQ, "all parked cars on the right")
    assert len(parked.grounding.node_ids) >= 2
    for nid in parked.grounding.node_ids:
        labels = parked.scene.node(nid).motion.labels
        assert (labels.motion, labels.sector) == ("parked", "right_of_ego")

    walking = answer_query(store.root, SEQ, "all pedestrians walking along the sidewalk")
    assert walking.grounding.node_ids
    assert all(walking.scene.node(n).category == "pedestrian" for n in walking.grounding.node_ids)

    red = answer_query(store.root, SEQ, "the red car")
    assert red.grounding.node_ids == ()
    assert "no camera images" in red.grounding.message and "red" in red.grounding.message


def test_query_json_prints_one_object_on_stdout(av2_store):
    store = av2_store[0]
    result = CliRunner().invoke(app, ["query", "--store", str(store.root), "--seq", SEQ, "--json", "--top", "3",
                                      "all parked cars on the right"])
    assert result.exit_code == 0, result.output
    answer = json.loads(result.stdout)
    assert answer["query"] == "all parked cars on the right" and answer["seq_id"] == SEQ
    assert answer["group"] is True and answer["png"] is None and len(answer["ranking"]) == 3
    assert answer["matches"] and answer["message"].startswith(f"{len(answer['matches'])} matches")
    first = answer["matches"][0]
    assert set(first) >= {"node_id", "object_id", "category", "caption", "motion", "motion_label", "scores"}
    assert first["category"] == "vehicle" and first["caption"] is None and first["motion_label"] == "parked"
    assert first["scores"]["appearance"] == 1.0  # no images: appearance is neutral
    assert 0.0 < first["scores"]["score"] <= 1.0 and first["chosen"] is True
