"""Feature autoencoder: reconstruction, identity of objects, determinism, save/load."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from simsplat_core.language.appearance.autoencoder import (
    AutoencoderConfig,
    AutoencoderState,
    FeatureAutoencoder,
    reconstruction_cosine,
)

DIM = 96
CONFIG = AutoencoderConfig(latent_dim=8, hidden=(64, 32), steps=200, lr=5e-3, seed=3)


def _caption_like(rng: np.random.Generator, combos: np.ndarray, common: np.ndarray, words: np.ndarray) -> np.ndarray:
    """Unit rows like caption embeddings: a large shared direction plus one "colour" and one
    "subtype" word vector per row (``combos [N, 2]``); pairwise cosines ~0.7-0.9, as for E5 captions."""
    x = 2.5 * common + words[combos[:, 0]] + words[combos[:, 1]] + 0.02 * rng.standard_normal((len(combos), DIM))
    return (x / np.linalg.norm(x, axis=1, keepdims=True)).astype(np.float32)


@pytest.fixture(scope="module")
def data() -> tuple[np.ndarray, np.ndarray]:
    """20 objects of distinct looks plus a look-alike of object 4; 60 vocabulary rows."""
    rng = np.random.default_rng(0)
    common = rng.standard_normal(DIM)
    words = rng.standard_normal((10, DIM))
    combos = np.array([(c, s) for c in range(6) for s in range(6, 10)])
    scene = _caption_like(rng, combos[rng.permutation(len(combos))[:20]], common, words)
    scene = np.concatenate([scene, scene[4:5]])
    vocab = _caption_like(rng, combos[rng.integers(0, len(combos), 60)], common, words)
    return scene, vocab


@pytest.fixture(scope="module")
def trained(data):
    scene, vocab = data
    return FeatureAutoencoder.fit(scene, vocab, CONFIG, text_space="toy")


def test_reconstruction_cosine_high_on_training_features(data, trained):
    scene, vocab = data
    ae, _ = trained
    assert reconstruction_cosine(ae, scene).min() > 0.97
    assert reconstruction_cosine(ae, vocab).mean() > 0.9


def test_nearest_object_of_each_decoded_latent_is_itself(data, trained):
    scene, _ = data
    ae, _ = trained
    decoded = ae.decode(ae.encode(scene))
    nearest = (decoded @ scene.T).argmax(axis=1)
    same_feature = np.isclose((scene[nearest] * scene).sum(axis=1), 1.0, atol=1e-6)  # look-alikes tie
    assert same_feature.all()


def test_training_reduces_loss(trained):
    _, report = trained
    assert report.final_loss < 0.2 * report.losses[0]
    assert len(report.losses) >= 10 and report.steps == CONFIG.steps


def test_shapes_and_unit_norm(data, trained):
    scene, _ = data
    ae, _ = trained
    z = ae.encode(scene)
    assert z.shape == (len(scene), CONFIG.latent_dim) and z.dtype == np.float32
    decoded = ae.decode(z)
    assert decoded.shape == scene.shape
    np.testing.assert_allclose(np.linalg.norm(decoded, axis=1), 1.0, atol=1e-5)
    with pytest.raises(ValueError, match=r"\[N, 96\]"):
        ae.encode(z)
    with pytest.raises(ValueError, match=r"\[N, 8\]"):
        ae.decode(scene)


def test_decode_torch_is_differentiable(trained):
    ae, _ = trained
    z = torch.zeros(2, CONFIG.latent_dim, requires_grad=True)
    ae.decode_torch(z).sum().backward()
    assert z.grad is not None and torch.isfinite(z.grad).all()


def test_save_load_round_trip_is_identical(tmp_path, data, trained):
    scene, _ = data
    ae, _ = trained
    path = tmp_path / "ae.npz"
    np.savez(path, **ae.state().to_arrays())
    with np.load(path) as arrays:
        state = AutoencoderState.from_arrays(dict(arrays))
    loaded = FeatureAutoencoder(state)
    assert (state.input_dim, state.latent_dim, state.hidden, state.text_space) == (DIM, 8, (64, 32), "toy")
    np.testing.assert_array_equal(loaded.encode(scene), ae.encode(scene))
    np.testing.assert_array_equal(loaded.decode(ae.encode(scene)), ae.decode(ae.encode(scene)))


def test_training_is_deterministic_for_a_seed(data, trained):
    scene, vocab = data
    ae, _ = trained
    short = AutoencoderConfig(**{**CONFIG.__dict__, "steps": 30})
    a, _ = FeatureAutoencoder.fit(scene, vocab, short)
    b, _ = FeatureAutoencoder.fit(scene, vocab, short)
    c, _ = FeatureAutoencoder.fit(scene, vocab, AutoencoderConfig(**{**short.__dict__, "seed": 4}))
    for x, y in zip(a.state().encoder, b.state().encoder):
        np.testing.assert_array_equal(x, y)
    assert not np.array_equal(a.state().encoder[0], c.state().encoder[0])
    assert torch.get_num_threads() >= 1  # fit restored the thread setting it changed


def test_fit_without_vocabulary_and_state_shape_checks(data):
    scene, _ = data
    ae, report = FeatureAutoencoder.fit(scene[:6], None, AutoencoderConfig(latent_dim=4, hidden=(32,), steps=20))
    assert ae.encode(scene[:6]).shape == (6, 4) and np.isfinite(report.final_loss)
    broken = AutoencoderState(**{**ae.state().__dict__, "latent_dim": 5})
    with pytest.raises(ValueError, match="does not fit"):
        FeatureAutoencoder(broken)
    with pytest.raises(ValueError, match="at least one"):
        FeatureAutoencoder.fit(scene[:0], None, AutoencoderConfig(steps=1))
