"""``build_language_scene``: a LanguageScene from a scene graph and its log."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from simsplat_core.language.alignment.feature_field import background_latent, gaussian_features
from simsplat_core.language.alignment.motion_training import MotionAligner, MotionAlignerConfig
from simsplat_core.language.alignment.scene_builder import (
    AlignmentConfig,
    AlignmentConfigError,
    BuiltLanguageScene,
    build_language_scene,
)
from simsplat_core.language.appearance.autoencoder import AutoencoderConfig, FeatureAutoencoder
from simsplat_core.language.text import TextEncoder
from simsplat_core.scene import SceneGraph
from simsplat_core.types import SceneLog
from tests.simsplat_core.language.alignment_fixtures import tiny_graph, tiny_log

FAST = AlignmentConfig(fit_iterations=4, fit_frame_stride=1, autoencoder_steps=150, min_area=30, eval_views=2)
MOVERS = ("vehicle", "pedestrian", "cyclist", "other")


@pytest.fixture(scope="module")
def log() -> SceneLog:
    return tiny_log()


@pytest.fixture(scope="module")
def tiny_aligner(log: SceneLog, encoder: TextEncoder) -> MotionAligner:
    return MotionAligner.fit([log], MotionAlignerConfig(epochs=1), encoder)


@pytest.fixture(scope="module")
def built(log: SceneLog, encoder: TextEncoder, tiny_aligner: MotionAligner) -> tuple[SceneGraph, BuiltLanguageScene]:
    graph = tiny_graph()
    return graph, build_language_scene(graph, log, text_encoder=encoder, aligner=tiny_aligner, config=FAST,
                                       scene_hash="abc")


def test_every_object_node_gets_language(built, log: SceneLog, tiny_aligner: MotionAligner) -> None:
    graph, result = built
    scene = result.scene
    assert [n.node_id for n in scene.nodes] == [n.node_id for n in graph.object_nodes]
    assert scene.seq_id == log.seq_id and scene.scene_hash == "abc" and scene.text_encoder
    motion = tiny_aligner.features(log)
    for node in scene.nodes:
        assert node.object_id == graph.node(node.node_id).object_id
        if node.category in MOVERS:
            assert node.kind in ("vehicle", "pedestrian")
            assert node.motion is not None and node.motion.object_id == node.object_id
            np.testing.assert_array_equal(node.f_mot, motion[node.object_id].f_mot)
        else:  # signs, cones, barriers
            assert node.kind == "" and node.motion is None and node.f_mot is None
    assert any(n.category not in MOVERS for n in scene.nodes)


def test_appearance_comes_from_projected_crops_and_the_field(built, encoder: TextEncoder) -> None:
    graph, result = built
    scene = result.scene
    by_object = {n.object_id: n for n in scene.nodes}
    red, truck = by_object["veh_01"], by_object["veh_03"]
    assert red.caption is not None and "red" in red.caption.text
    assert truck.caption is not None and "white" in truck.caption.text
    with_app = [n for n in scene.nodes if n.f_app is not None]
    assert {n.object_id for n in with_app} == set(result.captions) and len(with_app) >= 2
    for node in with_app:
        assert node.f_app.shape == (encoder.dim,) and abs(float(np.linalg.norm(node.f_app)) - 1) < 1e-5
        assert node.caption == result.captions[node.object_id]
    for node in scene.nodes:
        assert (node.f_app is None) == (node.caption is None)
    q = encoder.encode_queries(["a red car", "a white truck"])
    assert float(red.f_app @ q[0]) > float(red.f_app @ q[1])
    assert float(truck.f_app @ q[1]) > float(truck.f_app @ q[0])
    assert result.metrics["f_app_vs_caption_cosine"] > 0.95


def test_the_graph_carries_the_fitted_features(built) -> None:
    graph, result = built
    fitted = result.graph
    assert fitted is not None and fitted is not graph
    assert result.gaussian_features.shape == (graph.num_gaussians, FAST.feature_dim)
    np.testing.assert_array_equal(result.gaussian_features, gaussian_features(fitted).numpy())
    assert background_latent(fitted).shape == (FAST.feature_dim,)
    # the graph passed in is not changed
    assert background_latent(graph) is None and all(n.gaussians.features is None for n in graph.nodes)
    assert result.autoencoder is not None and result.autoencoder.latent_dim == FAST.feature_dim
    back = SceneGraph.from_records(fitted.to_records("tiny"))
    np.testing.assert_array_equal(gaussian_features(back).numpy(), result.gaussian_features)


def test_node_maps_and_metrics(built, log: SceneLog) -> None:
    graph, result = built
    scene = result.scene
    assert scene.node_id_maps.shape == (log.num_frames, 3, 64, 96) and scene.node_id_maps.dtype == np.int32
    assert scene.frame_indices.tolist() == list(range(log.num_frames))
    assert scene.cameras == ("front", "front_left", "front_right")
    truck = next(n for n in scene.nodes if n.object_id == "veh_03")
    assert scene.masks([truck.node_id]).sum() > 1000
    m = result.metrics
    for stage in ("node_maps", "crops", "captions", "autoencoder", "feature_field", "motion", "total"):
        assert m[f"time_{stage}_s"] >= 0
    assert m["mask_pooled_iou"] > 0.7 and m["fit_iterations"] == 4 and m["crops"] > 0
    assert m["object_nodes"] == len(scene.nodes) and m["nodes_with_f_app"] >= 2


def test_a_given_autoencoder_is_used_and_checked(built, log: SceneLog, encoder: TextEncoder) -> None:
    _, first = built
    config = dataclasses.replace(FAST, fit_iterations=0, eval_views=0, measure_masks=False)
    again = build_language_scene(tiny_graph(), log, text_encoder=encoder, aligner=None,
                                 autoencoder=first.autoencoder, config=config)
    assert again.autoencoder is first.autoencoder and "autoencoder_final_loss" not in again.metrics
    assert all(n.motion is None for n in again.scene.nodes)  # no aligner, no motion
    assert "mask_mean_iou" not in again.metrics
    wrong, _ = FeatureAutoencoder.fit(np.eye(4, encoder.dim, dtype=np.float32), None,
                                      AutoencoderConfig(latent_dim=3, steps=2))
    with pytest.raises(ValueError, match="feature_dim"):
        build_language_scene(tiny_graph(), log, text_encoder=encoder, aligner=None, autoencoder=wrong, config=config)


def test_logs_without_pixels_still_get_motion(log: SceneLog, encoder: TextEncoder, tiny_aligner: MotionAligner) -> None:
    bare = dataclasses.replace(log, images=tuple(dataclasses.replace(i, image=None, depth=None, instance=None)
                                                 for i in log.images))  # camera poses only, like AV2
    result = build_language_scene(None, bare, text_encoder=encoder, aligner=tiny_aligner, config=FAST)
    scene = result.scene
    assert scene.node_id_maps is None and scene.cameras == ()
    assert scene.frame_indices.tolist() == list(range(log.num_frames))
    assert result.gaussian_features is None and result.autoencoder is None and result.captions == {}
    assert [n.object_id for n in scene.nodes] == sorted(o.object_id for o in log.objects)
    assert [n.node_id for n in scene.nodes] == list(range(1, len(log.objects) + 1))  # initial_graph numbering
    assert all(n.f_app is None and n.caption is None for n in scene.nodes)
    assert all((n.motion is not None) == (n.category in MOVERS) for n in scene.nodes)
    with pytest.raises(ValueError, match="no cameras"):
        scene.masks([1])
    no_cameras = dataclasses.replace(log, images=())
    assert build_language_scene(None, no_cameras, text_encoder=encoder, aligner=None, config=FAST).scene.nodes
    with pytest.raises(ValueError, match="no scene graph"):
        build_language_scene(None, log, text_encoder=encoder, aligner=None, config=FAST)


@pytest.mark.parametrize("field, value", [
    ("feature_dim", 0), ("fit_iterations", -1), ("fit_lr", 0.0), ("fit_object_weight", float("nan")),
    ("fit_frame_stride", 0), ("crop_frame_stride", 0), ("min_area", -5), ("small_area", -1), ("crop_margin", 1.5),
    ("autoencoder_steps", 0), ("use_vocabulary", "yes"), ("background_passage", "  "), ("eval_views", -1),
    ("measure_masks", 1), ("backend", "vulkan"), ("seed", -1),
])
def test_config_errors_name_the_field(field: str, value) -> None:
    with pytest.raises(AlignmentConfigError, match=f"AlignmentConfig.{field}"):
        AlignmentConfig(**{field: value}).validate()
    assert AlignmentConfig().validate() == AlignmentConfig()


def test_small_objects_fall_back_to_smaller_crops() -> None:
    from simsplat_core.language.alignment.scene_builder import _select_crops
    from simsplat_core.language.appearance.crops import ObjectCrop

    def crop(oid: str, area: int) -> ObjectCrop:
        mask = np.zeros((10, 20), bool)
        mask.flat[:area] = True
        return ObjectCrop(np.zeros((10, 20, 3), np.float32), mask, "vehicle", np.ones(3), 0, "front", oid)

    crops = [crop("big", 150), crop("big", 40), crop("far", 40), crop("far", 60)]
    config = AlignmentConfig(min_area=100, small_area=30)
    assert config.min_floor == 30
    assert [(c.object_id, c.area) for c in _select_crops(crops, config)] == [("big", 150), ("far", 40), ("far", 60)]
    assert AlignmentConfig(min_area=100, small_area=0).min_floor == 100
    assert AlignmentConfig(min_area=4).min_floor == 4
