"""The aligner-training task without orchestration: stores a model that scores like the trained one, then skips."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from simsplat_core.language.alignment.motion_training import MotionAlignerConfig
from simsplat_core.language.text import default_text_encoder
from simsplat_core.world import WorldConfig, generate_log
from storage import ArtifactStore, write_scene_log
from storage.alignment import list_aligner_models, read_aligner_manifest
from tasks.align import load_motion_aligner, train_motion_aligner

CONFIG = MotionAlignerConfig(epochs=3)


@pytest.fixture(scope="module")
def store_with_logs(tmp_path_factory):
    store = ArtifactStore(tmp_path_factory.mktemp("store"))
    for seed in (1, 2):
        log = generate_log(seed=seed, config=WorldConfig(num_frames=20, width=48, height=32), seq_id=f"s{seed}")
        write_scene_log(store, log)
    return store


def test_trains_stores_reloads_and_skips(store_with_logs):
    store = store_with_logs
    first = train_motion_aligner.fn(store.root, ["s1", "s2"], CONFIG)
    assert not first.skipped and first.relpath == f"alignment/{first.model_hash}/model"
    manifest = read_aligner_manifest(store, first.model_hash)
    assert manifest["provenance"]["seq_ids"] == ["s1", "s2"] and manifest["metrics"]["logs"] == 2.0
    assert list_aligner_models(store) == [first.model_hash]

    again = train_motion_aligner.fn(store.root, ["s2", "s1"], CONFIG)  # same logs, other order
    assert again.skipped and again.model_hash == first.model_hash and again.seconds == 0.0

    from storage import read_scene_log

    log = read_scene_log(store, "s1", load_images=False)
    aligner = load_motion_aligner(store, first.model_hash)
    features = aligner.features(log)
    assert features, "movers of the log get motion features"
    query = default_text_encoder().encode_queries(["a car going straight"])[0]
    mot, loc = aligner.score(query, features)
    assert mot.shape == loc.shape == (len(features),) and np.all(np.isfinite(mot))


def test_other_config_is_another_model(store_with_logs):
    a = train_motion_aligner.fn(store_with_logs.root, ["s1"], CONFIG)
    b = train_motion_aligner.fn(store_with_logs.root, ["s1"], MotionAlignerConfig(epochs=2))
    assert a.model_hash != b.model_hash


def test_missing_log_and_empty_input_are_named(tmp_path):
    with pytest.raises(FileNotFoundError, match="logs/nope: no complete scene log"):
        train_motion_aligner.fn(str(tmp_path), ["nope"], CONFIG)
    with pytest.raises(ValueError, match="no logs"):
        train_motion_aligner.fn(str(tmp_path), [], CONFIG)
    with pytest.raises(FileNotFoundError, match="no complete alignment model"):
        load_motion_aligner(ArtifactStore(tmp_path), "ab" * 32)


@pytest.fixture(scope="module")
def aligned(store_with_logs):
    from simsplat_core.language.alignment.scene_builder import AlignmentConfig
    from simsplat_core.scene import ReconstructionConfig
    from tasks.align import align_scene
    from tasks.reconstruct import reconstruct_scene

    store = store_with_logs
    model = train_motion_aligner.fn(store.root, ["s1", "s2"], CONFIG)
    scene = reconstruct_scene.fn(store.root, "s1", ReconstructionConfig(iterations=2))
    config = AlignmentConfig(fit_iterations=3, autoencoder_steps=50, use_vocabulary=False, eval_views=0, min_area=4)
    stored = align_scene.fn(store.root, "s1", scene.scene_hash, model.model_hash, config)
    return store, model, scene, config, stored


def test_align_scene_stores_a_language_scene_that_reads_back(aligned):
    from simsplat_core.scene import SceneGraph
    from storage.language_scenes import list_language_scenes, read_language_scene
    from tasks.align import align_scene

    store, model, scene, config, stored = aligned
    assert not stored.skipped and stored.relpath.startswith(f"alignment/{model.model_hash}/scenes/s1/")
    assert list_language_scenes(store, "s1") == [(model.model_hash, stored.language_hash)]

    loaded = read_language_scene(store, "s1")
    lang = loaded.scene
    assert lang.scene_hash == scene.scene_hash and lang.node_id_maps is not None
    assert lang.node_id_maps.shape[:2] == (20, 3) and lang.node_id_maps.dtype == np.int32
    movers = [n for n in lang.nodes if n.motion is not None]
    assert movers and all(n.f_mot.shape == (384,) for n in movers)
    with_pixels = [n for n in lang.nodes if n.f_app is not None]
    assert with_pixels and all(abs(float(np.linalg.norm(n.f_app)) - 1.0) < 1e-3 for n in with_pixels)
    assert all(n.caption is not None for n in with_pixels)
    # masks cut from the stored maps cover the nodes' pixels
    assert lang.masks([with_pixels[0].node_id]).any()
    # the stored Gaussians carry the fitted features and render them
    graph = SceneGraph.from_records(loaded.records)
    features = graph.at(0).features
    assert features is not None and features.shape[1] == config.feature_dim
    assert loaded.autoencoder is not None and loaded.autoencoder.latent_dim == config.feature_dim

    again = align_scene.fn(store.root, "s1", scene.scene_hash, model.model_hash, config)
    assert again.skipped and again.language_hash == stored.language_hash


def test_answer_query_grounds_and_draws(aligned, tmp_path):
    from storage.language_scenes import read_language_scene
    from tasks.query import answer_query

    store = aligned[0]
    lang = read_language_scene(store, "s1").scene
    target = next(n for n in lang.nodes if n.caption is not None and n.category == "vehicle")
    out = tmp_path / "answer.png"
    answer = answer_query(store.root, "s1", target.caption.text, out=str(out))
    assert answer.grounding.ranking, "every vehicle is scored"
    assert out.exists() and out.stat().st_size > 0
    assert answer.frame in lang.frame_indices.tolist()
    with pytest.raises(ValueError, match="frame 999 is not in the scene"):
        answer_query(store.root, "s1", "a car", out=str(out), frame=999)
    with pytest.raises(FileNotFoundError, match="no language scene of 's2'"):
        answer_query(store.root, "s2", "a car", out=str(out))


def test_align_scene_with_a_vlm_captioner_over_http(aligned, monkeypatch):
    """captioner="vlm": one request per captioned object to the OpenAI-compatible server, its captions stored,
    another language hash than the built-in captioner's (the model name is part of it)."""
    import dataclasses

    from storage.language_scenes import read_language_scene
    from tasks.align import align_scene
    from tests.simsplat_core.vlm.chat_server import ChatServer, text_reply

    store, model, scene, config, stored = aligned
    server = ChatServer(reply=text_reply("A purple hatchback.")).start()
    try:
        monkeypatch.setenv("SIMSPLAT_VLM_URL", server.base_url)
        monkeypatch.setenv("SIMSPLAT_VLM_MODEL", "stand-in-vlm")
        vlm = align_scene.fn(store.root, "s1", scene.scene_hash, model.model_hash,
                             dataclasses.replace(config, captioner="vlm"))
    finally:
        server.stop()
    assert not vlm.skipped and vlm.language_hash != stored.language_hash
    lang = read_language_scene(store, "s1", model.model_hash, vlm.language_hash).scene
    captioned = [n for n in lang.nodes if n.caption is not None]
    assert captioned and all(n.caption.text == "a purple hatchback" for n in captioned)
    assert len(server.requests) == len(captioned)
    assert {r["body"]["model"] for r in server.requests} == {"stand-in-vlm"}


def test_a_stored_aligner_covering_most_logs_is_reused_not_retrained(tmp_path):
    store = ArtifactStore(tmp_path / "store")
    for seed in (1, 2, 3):
        write_scene_log(store, generate_log(seed=seed, config=WorldConfig(num_frames=20, width=48, height=32),
                                            seq_id=f"s{seed}"))
    first = train_motion_aligner.fn(store.root, ["s1", "s2"], CONFIG)

    grown = train_motion_aligner.fn(store.root, ["s1", "s2", "s3"], CONFIG)  # 2 of 3 logs covered
    assert grown.skipped and grown.model_hash == first.model_hash and grown.seq_ids == ("s1", "s2")
    assert list_aligner_models(store) == [first.model_hash]

    other_config = train_motion_aligner.fn(store.root, ["s1", "s2", "s3"], MotionAlignerConfig(epochs=2))
    assert not other_config.skipped and other_config.model_hash != first.model_hash

    real = dataclasses.replace(generate_log(seed=4, config=WorldConfig(num_frames=20, width=48, height=32),
                                            seq_id="r4"), source="waymo")
    write_scene_log(store, real)
    with_a_new_source = train_motion_aligner.fn(store.root, ["s1", "s2", "r4"], CONFIG)  # 2 of 3, none of waymo
    assert not with_a_new_source.skipped and with_a_new_source.seq_ids == ("s1", "s2", "r4")

    exact = train_motion_aligner.fn(store.root, ["s1", "s2", "s3"], CONFIG, reuse_share=1.0)
    assert not exact.skipped and exact.seq_ids == ("s1", "s2", "s3")
    assert train_motion_aligner.fn(store.root, ["s3", "s1"], CONFIG).model_hash == exact.model_hash  # covers all
