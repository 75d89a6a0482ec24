"""E5 for the words the edit parser's rules do not know: the nearest supported intent, or none.

An unknown verb ("yank the van out of the scene") or predicate ("have the sedan hit the brakes", "make the
bus pull over") is embedded as an E5 *query* and compared with *passages*: each intent's imperative
phrasings (:data:`INTENT_PHRASES`) and the scenario vocabulary's motion-class prototypes
mapped through ``editing.behaviours.registry.CLASS_INTENT`` ("a car coming to a stop" -> stop). Phrasings of
things the editor cannot do ("fly", "paint it", "make it rain") are passages too, of the intent ``unsupported``.

The best intent is taken only when its cosine is at least :data:`MIN_SIMILARITY` and beats the best other
intent by :data:`MIN_MARGIN`, and is not ``unsupported``; otherwise nothing is close enough and the parser
refuses. The thresholds were set on a probe of unknown verbs (``tests/simsplat_core/editing``): E5-small
cosines of unrelated short phrases sit at 0.80-0.86, paraphrases at 0.87-0.93.

Prototype embeddings are computed once per encoder (by ``encoder.name``) and cached; a query costs one
encoder call (about 10 ms for E5-small on one core), cached by the encoder itself.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass

import numpy as np

from simsplat_core.editing.behaviours import registry as behaviours
from simsplat_core.editing.behaviours.registry import CLASS_INTENT, INTENT_FAMILY
from simsplat_core.editing.parse.lexicon import OP_PHRASES, UNSUPPORTED, UNSUPPORTED_PHRASES
from simsplat_core.language.text import TextEncoder
from simsplat_core.scenario.vocabulary import MOTION_VOCABULARIES

#: Imperative phrasings of each intent (E5 passages, beside the vocabulary's own class prototypes), in embedding
#: order: the ops' (``lexicon.OP_PHRASES``), the behaviours' (``editing.behaviours.registry.INTENT_PHRASES``) and
#: the phrasings to refuse (``lexicon.UNSUPPORTED_PHRASES``).
INTENT_PHRASES: dict[str, tuple[str, ...]] = {**OP_PHRASES, **behaviours.INTENT_PHRASES,
                                              UNSUPPORTED: UNSUPPORTED_PHRASES}
#: Least cosine of a query to its intent's nearest passage.
MIN_SIMILARITY = 0.87
#: Least lead of the best intent over the best intent of another family.
MIN_MARGIN = 0.02


@dataclass(frozen=True)
class IntentMatch:
    """The nearest intent of a phrase.

    Attributes:
        intent: the accepted intent, or ``None`` when nothing supported is close enough.
        nearest: the nearest intent whatever its score (for messages and tests).
        score: cosine to ``nearest``'s closest passage.
        margin: ``score`` less the best other intent's score.
        passage: the passage it was closest to.
    """

    intent: str | None
    nearest: str
    score: float
    margin: float
    passage: str


@dataclass(frozen=True)
class _Prototypes:
    intents: tuple[str, ...]  # [P] intent of each passage
    passages: tuple[str, ...]  # [P]
    matrix: np.ndarray  # [P, D] unit rows


def prototype_passages() -> tuple[tuple[str, str], ...]:
    """``(intent, passage)`` pairs: the intents' imperative phrasings and the vocabulary's class prototypes."""
    pairs = [(intent, phrase) for intent, phrases in INTENT_PHRASES.items() for phrase in phrases]
    for vocabulary in MOTION_VOCABULARIES.values():
        for cls in vocabulary.classes:
            pairs.extend((CLASS_INTENT[cls.name], phrase) for phrase in cls.prototypes)
    return tuple(pairs)


_CACHE: dict[str, _Prototypes] = {}
_LOCK = threading.Lock()


def _prototypes(encoder: TextEncoder) -> _Prototypes:
    with _LOCK:
        found = _CACHE.get(encoder.name)
    if found is not None:
        return found
    pairs = prototype_passages()
    matrix = encoder.encode_passages([p for _, p in pairs])
    built = _Prototypes(tuple(i for i, _ in pairs), tuple(p for _, p in pairs), matrix)
    with _LOCK:
        _CACHE[encoder.name] = built
    return built


def nearest_intent(phrase: str, encoder: TextEncoder, *, min_similarity: float = MIN_SIMILARITY,
                   min_margin: float = MIN_MARGIN) -> IntentMatch:
    """The intent ``phrase`` (an imperative, e.g. "pull over" or "yank it out of the scene") asks for."""
    protos = _prototypes(encoder)
    scores = protos.matrix @ encoder.encode_queries([phrase])[0]  # [P]
    best: dict[str, tuple[float, int]] = {}
    for idx in np.argsort(-scores):
        best.setdefault(protos.intents[idx], (float(scores[idx]), int(idx)))
    ranked = sorted(best.items(), key=lambda kv: -kv[1][0])
    nearest, (score, idx) = ranked[0]
    family = INTENT_FAMILY.get(nearest, nearest)  # the margin is taken to other families
    others = [s for intent, (s, _) in ranked[1:] if INTENT_FAMILY.get(intent, intent) != family]
    margin = score - others[0] if others else score
    ok = nearest != UNSUPPORTED and score >= min_similarity and margin >= min_margin
    return IntentMatch(nearest if ok else None, nearest, score, margin, protos.passages[idx])
