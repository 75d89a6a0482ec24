"""Caption-then-embed features: shapes, unit norm, per-object aggregation, look-alikes."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.language.appearance.embedders import (
    AppearanceEmbedder,
    CaptionEmbedder,
    aggregate_views,
    object_features,
)
from tests.simsplat_core.language.appearance.helpers import PAINTS, HashTextEncoder, make_crop, paint_vehicle

SUV = (4.85, 1.95, 1.78)
SEDAN = (4.6, 1.82, 1.45)


def _scene_crops():
    """Two black sedans (look-alikes, two views each, different sizes/noise) and a red SUV."""
    crops = []
    objects = (("sedan_a", "black", SEDAN), ("sedan_b", "black", SEDAN), ("suv", "red", SUV))
    for k, (oid, paint, box) in enumerate(objects):
        for frame, (h, w) in enumerate(((40, 90), (24, 54))):
            rgb, mask = paint_vehicle(PAINTS[paint], height=h, width=w, seed=10 * k + frame)
            crops.append(make_crop(rgb, mask, "vehicle", box, oid, frame))
    return crops


def test_caption_embedder_shapes_and_norm():
    embedder = CaptionEmbedder(HashTextEncoder())
    assert isinstance(embedder, AppearanceEmbedder)
    crops = _scene_crops()
    feats = embedder.embed(crops)
    assert feats.shape == (len(crops), embedder.dim) and feats.dtype == np.float32
    np.testing.assert_allclose(np.linalg.norm(feats, axis=1), 1.0, atol=1e-5)
    assert embedder.embed([]).shape == (0, embedder.dim)
    assert "hash-bow-64" in embedder.name


def test_caption_embedder_embeds_captions_as_passages():
    class RoleSpy(HashTextEncoder):
        def encode_queries(self, texts):
            raise AssertionError("scene-side captions must be embedded as passages")

    crops = _scene_crops()
    embedder = CaptionEmbedder(RoleSpy())
    expected = HashTextEncoder().encode_passages([c.text for c in embedder.captions(crops)])
    np.testing.assert_allclose(embedder.embed(crops), expected)


def test_object_features_average_views_per_object():
    embedder = CaptionEmbedder(HashTextEncoder())
    crops = _scene_crops()
    feats = object_features(embedder, crops)
    assert feats.object_ids == ("sedan_a", "sedan_b", "suv")
    assert feats.features.shape == (3, embedder.dim)
    assert feats.view_features.shape == (len(crops), embedder.dim)
    assert feats.view_object.tolist() == [0, 0, 1, 1, 2, 2]
    np.testing.assert_allclose(np.linalg.norm(feats.features, axis=1), 1.0, atol=1e-5)
    mean = feats.view_features[:2].mean(axis=0)
    np.testing.assert_allclose(feats.feature("sedan_a"), mean / np.linalg.norm(mean), atol=1e-6)


def test_lookalikes_near_identical_and_different_car_far():
    feats = object_features(CaptionEmbedder(HashTextEncoder()), _scene_crops())
    a, b, suv = feats.feature("sedan_a"), feats.feature("sedan_b"), feats.feature("suv")
    assert a @ b > 0.999
    assert a @ suv < 0.9 and b @ suv < 0.9


def test_aggregate_views_weights_and_errors():
    views = np.array([[1.0, 0.0], [0.0, 1.0], [0.0, 1.0]], np.float32)
    out = aggregate_views(["x", "x", "y"], views, weights=np.array([3.0, 1.0, 1.0]))
    np.testing.assert_allclose(out.features[0], np.array([3.0, 1.0]) / np.sqrt(10.0), atol=1e-6)
    with pytest.raises(ValueError, match="object ids"):
        aggregate_views(["x"], views)


def test_track_captions_one_per_object():
    captions = CaptionEmbedder(HashTextEncoder()).track_captions(_scene_crops())
    assert {k: v.text for k, v in captions.items()} == {
        "sedan_a": "a black sedan",
        "sedan_b": "a black sedan",
        "suv": "a red SUV",
    }
