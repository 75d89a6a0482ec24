"""Per-Gaussian appearance features fitted by rendering, relevance maps, persistence in the graph."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest
import torch

from simsplat_core.language.alignment.feature_field import (
    BACKGROUND_LATENT_KEY,
    FeatureFieldError,
    FeatureFitConfig,
    FieldFitReport,
    background_latent,
    feature_views,
    fit_feature_field,
    gaussian_features,
    initial_features,
    node_mean_features,
    set_gaussian_features,
    similarity_map,
)
from simsplat_core.language.appearance.autoencoder import AutoencoderConfig, FeatureAutoencoder
from simsplat_core.language.node_masks import NodeIdMaps, object_node_ids, render_node_id_maps
from simsplat_core.language.text import TextEncoder
from simsplat_core.scene import SceneGraph
from simsplat_core.types import SceneLog
from tests.simsplat_core.language.alignment_fixtures import tiny_graph, tiny_log

BACKGROUND = "road, sidewalk, buildings, trees and sky"


@dataclass
class Fitted:
    log: SceneLog
    graph: SceneGraph
    maps: NodeIdMaps
    autoencoder: FeatureAutoencoder
    latents: dict[int, np.ndarray]
    targets: dict[int, np.ndarray]
    z_bg: np.ndarray
    report: FieldFitReport


@pytest.fixture(scope="module")
def fitted(encoder: TextEncoder) -> Fitted:
    """Node targets from the world's ground-truth appearance captions (the field is tested on its own)."""
    log, graph = tiny_log(), tiny_graph()
    maps = render_node_id_maps(graph, log)
    node_of = object_node_ids(graph)
    objects = sorted(o.object_id for o in log.objects if o.object_id in node_of)
    captions = [next(o for o in log.objects if o.object_id == oid).attributes["caption_appearance"] for oid in objects]
    feats = encoder.encode_passages(captions + [BACKGROUND])
    ae, _ = FeatureAutoencoder.fit(feats, None, AutoencoderConfig(steps=200))
    z = ae.encode(feats)
    latents = {node_of[oid]: z[i] for i, oid in enumerate(objects)}
    targets = {node_of[oid]: feats[i] for i, oid in enumerate(objects)}
    report = fit_feature_field(graph, feature_views(log, maps), latents, z[-1],
                               FeatureFitConfig(iterations=12, lr=0.05, object_weight=5.0),
                               autoencoder=ae, node_targets=targets, background_target=feats[-1])
    # the input graph is not changed: the fitted one is the report's
    assert report.graph is not None and report.graph is not graph
    assert background_latent(graph) is None and all(n.gaussians.features is None for n in graph.nodes)
    return Fitted(log, report.graph, maps, ae, latents, targets, z[-1], report)


def _cameras(log: SceneLog, frame: int) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
    images = log.images_at(frame)
    return (np.stack([i.cam_to_world for i in images]), np.stack([i.K for i in images]),
            tuple(i.camera for i in images))


def test_fit_lowers_the_error_and_stores_features(fitted: Fitted) -> None:
    report = fitted.report
    assert report.iterations == 12 and report.views == fitted.log.num_frames and report.eval_views == 4
    assert report.latent_mse_after < report.latent_mse_before
    assert report.object_cosine_after > report.object_cosine_before - 1e-3
    assert report.object_cosine_before > 0.8  # the node-latent initialisation is already close
    assert np.isfinite(list(report.summary().values())).all()
    feats = gaussian_features(fitted.graph)
    assert feats.shape == (fitted.graph.num_gaussians, fitted.autoencoder.latent_dim)
    np.testing.assert_allclose(background_latent(fitted.graph), fitted.z_bg, rtol=1e-6)


def test_red_car_pixels_read_as_a_red_car(fitted: Fitted, encoder: TextEncoder) -> None:
    node_of = object_node_ids(fitted.graph)
    red, white = node_of["veh_01"], node_of["veh_03"]  # "a red sedan", "a white truck"
    queries = encoder.encode_queries(["a red car", "a blue car", "a white truck"])
    hits = {"red": [], "blue": [], "white": []}
    on_truck = {"red": [], "white": []}
    for frame in range(fitted.log.num_frames):
        c2w, ks, cams = _cameras(fitted.log, frame)
        ids = np.stack([fitted.maps.image(frame, c) for c in cams])
        sims = similarity_map(fitted.graph, frame, c2w, ks, 96, 64, fitted.autoencoder, queries)
        assert sims.shape == (3, *ids.shape) and sims.dtype == np.float32
        for name, sim in zip(("red", "blue", "white"), sims):
            hits[name].append(sim[ids == red])
        on_truck["red"].append(sims[0][ids == white])
        on_truck["white"].append(sims[2][ids == white])
    red_px, blue_px = np.concatenate(hits["red"]), np.concatenate(hits["blue"])
    assert red_px.size > 400
    assert (red_px > blue_px).mean() > 0.95 and red_px.mean() > blue_px.mean() + 0.02
    assert np.concatenate(on_truck["white"]).mean() > np.concatenate(on_truck["red"]).mean() + 0.02


def test_node_features_decode_to_their_targets(fitted: Fitted) -> None:
    rendered = fitted.report.node_features  # mean rendered latent over each node's own pixels
    means = node_mean_features(fitted.graph, fitted.latents)  # opacity-weighted mean of the Gaussians
    assert set(rendered) <= set(fitted.latents) and set(means) == set(fitted.latents)
    nodes = sorted(rendered)
    decoded = fitted.autoencoder.decode(np.stack([rendered[n] for n in nodes]))
    # against the autoencoder's own round trip of the targets (200 steps of training: not exact)
    targets = fitted.autoencoder.decode(np.stack([fitted.latents[n] for n in nodes]))
    cos = decoded @ targets.T
    node_of = object_node_ids(fitted.graph)
    for oid in ("veh_01", "veh_03"):  # the clearly visible objects
        row = nodes.index(node_of[oid])
        assert cos[row, row] > 0.98
        assert cos[row].max() - cos[row, row] < 1e-3  # nearest target: its own (or an identical caption)


def test_features_round_trip_through_records(fitted: Fitted) -> None:
    records = fitted.graph.to_records("tiny")
    assert records.gaussians["feature"].shape == (fitted.graph.num_gaussians, fitted.autoencoder.latent_dim)
    assert BACKGROUND_LATENT_KEY in records.metadata
    back = SceneGraph.from_records(records)
    torch.testing.assert_close(gaussian_features(back), gaussian_features(fitted.graph))
    np.testing.assert_array_equal(background_latent(back), background_latent(fitted.graph))
    c2w, ks, _ = _cameras(fitted.log, 1)
    query = fitted.targets[object_node_ids(fitted.graph)["veh_01"]]
    np.testing.assert_allclose(similarity_map(back, 1, c2w, ks, 96, 64, fitted.autoencoder, query),
                               similarity_map(fitted.graph, 1, c2w, ks, 96, 64, fitted.autoencoder, query), atol=1e-4)


def test_initial_features_follow_the_nodes() -> None:
    graph = tiny_graph()
    some = graph.object_nodes[0].node_id
    z = np.arange(4, dtype=np.float32)
    bg = -np.ones(4, dtype=np.float32)
    feats = initial_features(graph, {some: z}, bg).numpy()
    offsets = graph.node_offsets()
    start, stop = offsets[some]
    np.testing.assert_array_equal(feats[start:stop], np.broadcast_to(z, (stop - start, 4)))
    b0, b1 = offsets[0]
    np.testing.assert_array_equal(feats[b0:b1], np.broadcast_to(bg, (b1 - b0, 4)))
    other = graph.object_nodes[1].node_id  # no latent: background
    o0, o1 = offsets[other]
    np.testing.assert_array_equal(feats[o0:o1], np.broadcast_to(bg, (o1 - o0, 4)))
    with pytest.raises(FeatureFieldError, match="width"):
        initial_features(graph, {some: np.zeros(3)}, bg)


def test_missing_or_malformed_features_raise(fitted: Fitted) -> None:
    graph = tiny_graph()
    with pytest.raises(FeatureFieldError, match="no per-Gaussian features"):
        gaussian_features(graph)
    c2w, ks, _ = _cameras(fitted.log, 0)
    with pytest.raises(FeatureFieldError):
        similarity_map(graph, 0, c2w, ks, 96, 64, fitted.autoencoder, np.ones(384, np.float32))
    with pytest.raises(FeatureFieldError, match=r"\[N="):
        set_gaussian_features(graph, np.zeros((3, 8), np.float32))
    with_features = set_gaussian_features(graph, np.ones((graph.num_gaussians, 2), np.float32))
    assert gaussian_features(with_features).shape == (graph.num_gaussians, 2)
    with pytest.raises(FeatureFieldError, match="no per-Gaussian features"):
        gaussian_features(graph)  # set_gaussian_features returned a copy
    with pytest.raises(ValueError, match="query has 5 dims"):
        similarity_map(fitted.graph, 0, c2w, ks, 96, 64, fitted.autoencoder, np.ones(5, np.float32))
    one = similarity_map(fitted.graph, 0, c2w, ks, 96, 64, fitted.autoencoder, np.ones(384, np.float32))
    two = similarity_map(fitted.graph, 0, c2w, ks, 96, 64, fitted.autoencoder, np.ones((2, 384), np.float32))
    assert one.shape == (3, 64, 96) and two.shape == (2, 3, 64, 96)
    np.testing.assert_allclose(two[1], one, atol=1e-6)


@pytest.mark.parametrize("field, value", [("iterations", -1), ("lr", 0.0), ("object_weight", 0.0),
                                          ("backend", "opengl"), ("eval_views", -2), ("eval_pixel_stride", 0)])
def test_fit_config_errors_name_the_field(field: str, value) -> None:
    with pytest.raises(ValueError, match=f"FeatureFitConfig.{field}"):
        FeatureFitConfig(**{field: value}).validate()
