"""Text space: E5 roles, normalisation, semantic ordering, the cache and the registry."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

from simsplat_core.language.text import (
    EmbeddingCache,
    TextEncoder,
    TextEncoderUnavailable,
    available_text_encoders,
    make_text_encoder,
    register_text_encoder,
)


def test_embeddings_are_unit_float32_rows(encoder: TextEncoder) -> None:
    texts = ["a car turning left", "a pedestrian standing on the sidewalk", "the red bus"]
    for out in (encoder.encode_queries(texts), encoder.encode_passages(texts)):
        assert out.shape == (3, encoder.dim) and out.dtype == np.float32
        np.testing.assert_allclose(np.linalg.norm(out, axis=1), 1.0, atol=1e-5)
    assert encoder.dim == 384


def test_query_and_passage_roles_differ(encoder: TextEncoder) -> None:
    q = encoder.encode_queries(["a car turning left"])[0]
    p = encoder.encode_passages(["a car turning left"])[0]
    assert float(q @ p) < 0.99


def test_closer_phrases_score_higher(encoder: TextEncoder) -> None:
    q = encoder.encode_queries(["a car turning left"])[0]
    turn, stand = encoder.encode_passages(["vehicle making a left turn", "pedestrian standing"])
    assert float(q @ turn) > float(q @ stand)
    left, right = encoder.encode_passages(["a vehicle making a left turn", "a vehicle making a right turn"])
    assert float(q @ left) > float(q @ right)


def test_cached_embeddings_are_reused(encoder: TextEncoder) -> None:
    first = encoder.encode_passages(["a cached phrase about a truck"])
    misses = encoder.cache.misses
    again = encoder.encode_passages(["a cached phrase about a truck", "a cached phrase about a truck"])
    assert encoder.cache.misses == misses
    np.testing.assert_array_equal(again[0], first[0])
    np.testing.assert_array_equal(again[1], first[0])


def test_empty_input_and_single_string(encoder: TextEncoder) -> None:
    assert encoder.encode_queries([]).shape == (0, encoder.dim)
    with pytest.raises(TypeError):
        encoder.encode_queries("not a list")


def test_cache_computes_each_missing_text_once_and_evicts_lru() -> None:
    calls: list[list[str]] = []

    def compute(texts: list[str]) -> np.ndarray:
        calls.append(texts)
        return np.array([[len(t), 1.0] for t in texts], dtype=np.float32)

    cache = EmbeddingCache(max_entries=2)
    out = cache.lookup("query", ["a", "bb", "a"], compute)
    assert calls == [["a", "bb"]]
    np.testing.assert_array_equal(out[:, 0], [1, 2, 1])
    cache.lookup("query", ["a"], compute)  # "a" becomes most recent
    cache.lookup("passage", ["a"], compute)  # other role: a miss, evicts "bb"
    assert calls[-1] == ["a"] and len(cache) == 2
    cache.lookup("query", ["bb"], compute)
    assert calls[-1] == ["bb"]


class _FakeEncoder:
    name = "fake"
    dim = 2

    def encode_queries(self, texts):
        return np.tile([1.0, 0.0], (len(texts), 1)).astype(np.float32)

    encode_passages = encode_queries


def test_registry_builds_registered_encoders_and_names_unknown_ones() -> None:
    register_text_encoder("fake-for-test", _FakeEncoder)
    assert "fake-for-test" in available_text_encoders()
    assert isinstance(make_text_encoder("fake-for-test"), TextEncoder)
    with pytest.raises(KeyError, match="registered"):
        make_text_encoder("no-such-encoder")


@pytest.mark.parametrize(
    ("name", "module"), [("clip", "open_clip"), ("sentence-transformers", "sentence_transformers")]
)
def test_optional_encoders_explain_what_is_missing(name: str, module: str) -> None:
    if importlib.util.find_spec(module) is not None:
        pytest.skip(f"{module} is installed")
    with pytest.raises(TextEncoderUnavailable, match="pip install"):
        make_text_encoder(name)
