"""The scores of the ``QueryEngine`` (``engine`` module docstring), as pure functions of a config.

Text side: a query part's membership over codebook classes (``group_distribution`` for the sector and
context parts, ``motion_distribution`` for the motion part, crossing classes merged), each mixing a
softmax of centred prototype cosines with a keyword prior (``keyword_prior`` over ``lexicon``).
Node side: the appearance factors of a node's caption (``color_fit``, ``subtype_fit``,
``attribute_fit``) and the motion and location match scores of a node's features (``motion_score``,
``location_score``), all in ``[0, 1]``.
"""

from __future__ import annotations

import collections
import re
from collections.abc import Sequence

import numpy as np

from simsplat_core.language.appearance.colors import UNKNOWN
from simsplat_core.language.codebooks import MotionCodebooks
from simsplat_core.language.grounding.config import QueryConfig
from simsplat_core.language.grounding.lexicon import (
    CROSSING_CLASSES,
    MOTION_KEYWORDS,
    PEDESTRIAN_MERGED,
    SIMILAR_COLORS,
    STATIONARY_CLASSES,
    SUBTYPE_FIT,
)
from simsplat_core.language.grounding.parse import ParsedQuery
from simsplat_core.language.scene_language import LanguageScene, NodeLanguage
from simsplat_core.language.text import l2_normalise
from simsplat_core.scenario import vocabulary as voc
from simsplat_core.scenario.trajectory import agent_kind


# ---------------------------------------------------------------------------------------------- text side
def _softmax(x: np.ndarray, temperature: float) -> np.ndarray:
    z = (x - x.max()) / temperature
    e = np.exp(z)
    return e / e.sum()


def scene_has_appearance(scene: LanguageScene) -> bool:
    """Whether any object node of ``scene`` has a caption or ``f_app`` (``False`` for logs without images)."""
    return any(n.caption is not None or n.f_app is not None for n in scene.nodes)


def looks_named(parsed: ParsedQuery) -> str:
    """The query's appearance words beyond the category ("red", "not red", "big"); ``""`` when none."""
    words = [*parsed.named_colors, *(f"not {c}" for c in parsed.excluded_colors)]
    if parsed.appearance_extra and not parsed.named_colors:
        words.append(parsed.appearance_extra)
    return ", ".join(words)


def keyword_prior(
    phrase: str, table: Sequence[tuple[str, str]], classes: Sequence[str], fallback: str | None = None
) -> np.ndarray | None:
    """Uniform distribution over the classes whose keyword regex matches ``phrase`` (``None``: no match).

    ``fallback`` counts only when no other class is hit ("in the oncoming lane" is oncoming, not merely
    on the road).
    """
    hits = [name for name, rx in table if name in classes and re.search(rx, phrase)]
    if fallback in hits and len(hits) > 1:
        hits.remove(fallback)
    return _uniform(hits, classes)


def _membership(
    probs: np.ndarray, prior: np.ndarray | None, classes: Sequence[str], lexicon_weight: float
) -> dict[str, float]:
    """Class -> how far the query names it, in ``[0, 1]``: the text-space softmax relative to its top class,
    mixed with the keyword hits (1 for every class a keyword names: "stationary" names stopped and parked)."""
    member = probs / max(float(probs.max()), 1e-12)
    if prior is not None:
        member = (1.0 - lexicon_weight) * member + lexicon_weight * (prior > 0)
    return dict(zip(classes, map(float, member)))


def _uniform(hits: Sequence[str], classes: Sequence[str]) -> np.ndarray | None:
    """Uniform distribution over ``hits`` (a subset of ``classes``), ``None`` when empty."""
    if not hits:
        return None
    out = np.zeros(len(classes))
    for name in hits:
        out[list(classes).index(name)] = 1.0
    return out / out.sum()


def group_distribution(
    query: np.ndarray,
    classes: Sequence[str],
    prototypes: np.ndarray,
    centre: np.ndarray,
    temperature: float,
    prior: np.ndarray | None,
    lexicon_weight: float,
) -> dict[str, float]:
    """Softmax of centred cosines of ``query`` ``[D]`` with ``prototypes`` ``[K, D]``, mixed with a keyword prior."""
    centred = l2_normalise(prototypes - centre) @ l2_normalise((query - centre)[None])[0]
    return _membership(_softmax(centred, temperature), prior, classes, lexicon_weight)


def motion_distribution(
    parsed: ParsedQuery, query: np.ndarray, books: MotionCodebooks, config: QueryConfig
) -> dict[str, float]:
    """Merged motion class -> probability of the motion text's embedding ``query`` ``[D]``, over both
    kinds' codebooks (crossing classes merged)."""
    classes = books.vehicle.classes + books.pedestrian.classes
    prototypes = np.concatenate([books.vehicle.prototypes, books.pedestrian.prototypes])
    kinds = {agent_kind(c) for c in parsed.categories} - {None}
    allowed = set()
    if not kinds or "vehicle" in kinds:
        allowed |= set(books.vehicle.classes)
    if not kinds or "pedestrian" in kinds:
        allowed |= set(PEDESTRIAN_MERGED)
    merged_classes = [c for c in classes if c not in CROSSING_CLASSES] + [voc.CROSSING]
    hits = [c for rx, named in MOTION_KEYWORDS if re.search(rx, parsed.motion) for c in named if c in allowed]
    if voc.CROSSING in hits:
        hits = [c for c in hits if c != voc.WALKING_ALONG]  # "walking across" is a crossing
    prior = _uniform(list(dict.fromkeys(hits)), merged_classes)
    centred = l2_normalise(prototypes - books.motion_centre) @ l2_normalise((query - books.motion_centre)[None])[0]
    probs = _softmax(centred, config.motion_temperature)
    merged: collections.defaultdict[str, float] = collections.defaultdict(float)
    for name, p in zip(classes, probs):
        merged[voc.CROSSING if name in CROSSING_CLASSES else name] += float(p)
    probs = np.array([merged[c] for c in merged_classes])
    return _membership(probs, prior, merged_classes, config.lexicon_weight)


# ---------------------------------------------------------------------------------------------- node side
def color_fit(query: str, node: str | None, config: QueryConfig) -> float:
    """Factor for a named colour against one of the caption's colours (``engine`` module docstring)."""
    if node is None or node == UNKNOWN:
        return config.missing_appearance
    if query == node:
        return 1.0
    if frozenset((query, node)) in SIMILAR_COLORS:
        return config.color_similar
    return config.color_mismatch


def subtype_fit(query: str | None, node: str | None, config: QueryConfig) -> float:
    """Factor for a named subtype against the caption's subtype."""
    if query is None or node is None:
        return 1.0
    fits = SUBTYPE_FIT.get(query)
    if fits is None:
        return 1.0 if query == node else config.subtype_mismatch
    return fits.get(node, config.subtype_mismatch)


def attribute_fit(parsed: ParsedQuery, node: NodeLanguage, config: QueryConfig) -> float:
    """Product of the colour and subtype factors of ``parsed`` against ``node.caption`` (an excluded colour
    that the caption names as the body colour, or as either garment colour of a person, contradicts)."""
    cap = node.caption
    named = parsed.named_colors
    if cap is None:
        return 1.0
    factor = 1.0
    shown: tuple[str | None, ...]  # the caption's colours an excluded colour contradicts
    if cap.category == "pedestrian" or node.category == "pedestrian":
        upper, lower = cap.upper_color, cap.lower_color
        if upper is None and lower is None and cap.colors:
            upper, lower = cap.colors[0], cap.colors[-1]
        if parsed.upper_color:
            factor *= color_fit(parsed.upper_color, upper, config)
        if parsed.lower_color:
            factor *= color_fit(parsed.lower_color, lower, config)
        for colour in parsed.colors:
            factor *= max(color_fit(colour, upper, config), color_fit(colour, lower, config))
        shown = (upper, lower)
    else:
        body = cap.colors or (UNKNOWN,)
        for colour in named:
            # the main colour fits fully, a second colour (barriers: "orange and white") nearly
            factor *= max([color_fit(colour, body[0], config)] + [0.8 * color_fit(colour, c, config) for c in body[1:]])
        shown = body[:1]
    for colour in parsed.excluded_colors:  # "not red": a red caption is contradicted
        if colour in shown:
            factor *= config.color_mismatch
    return factor * subtype_fit(parsed.subtype, cap.subtype, config)


def motion_score(parsed: ParsedQuery, dist: dict[str, float], node: NodeLanguage, config: QueryConfig) -> float:
    """How far ``node`` moves the way the query's motion membership ``dist`` says, in ``[0, 1]``."""
    feats = node.motion
    if feats is None:
        if node.category in ("static", "sign") or not node.kind:
            return float(sum(dist.get(c, 0.0) for c in STATIONARY_CLASSES))
        return config.missing_motion
    score = 0.0
    label = feats.labels.motion
    for name, weight in _with_label(feats.motion_probs, label, 1.0, config.label_weight).items():
        score += dist.get(voc.CROSSING if name in CROSSING_CLASSES else name, 0.0) * weight
    if parsed.crossing_direction and feats.kind == "pedestrian":
        if feats.labels.motion != f"crossing_{parsed.crossing_direction}":
            score *= config.direction_mismatch
    return float(min(max(score, 0.0), 1.0))


def location_score(
    sector: dict[str, float] | None,
    context: dict[str, float] | None,
    node: NodeLanguage,
    config: QueryConfig,
    books: MotionCodebooks,
) -> float:
    """How far ``node`` is where the query's sector and context memberships say (their product), in ``[0, 1]``.

    A static node (no motion features) answers the sector from its ``static_location`` shares; a context, or a
    sector without shares, scores ``missing_motion``."""
    feats = node.motion
    if feats is None:
        shares = node.static_location
        if sector is None or not shares:
            return config.missing_motion
        score = sum(p * shares.get(c, 0.0) for c, p in sector.items())  # the shares sum to 1
        if context is not None:
            score *= config.missing_motion
        return float(np.clip(score, 0.0, 1.0))
    probs = feats.location_probs
    # sectors and contexts each hold half of the location weights
    probs = _with_label(probs, feats.labels.sector, 0.5, config.label_weight, books.sector.classes)
    probs = _with_label(probs, feats.labels.context, 0.5, config.label_weight, books.context.classes)
    score = 1.0
    for dist in (sector, context):
        if dist is None:
            continue
        mass = sum(probs.get(c, 0.0) for c in dist)
        if mass <= 0:
            score *= config.missing_motion
            continue
        score *= sum(p * probs.get(c, 0.0) / mass for c, p in dist.items())
    return float(np.clip(score, 0.0, 1.0))


def _with_label(probs: dict[str, float], label: str | None, mass: float, weight: float,
                group: Sequence[str] | None = None) -> dict[str, float]:
    """``(1 - weight) * probs + weight * mass * onehot(label)`` over ``label``'s group of classes.

    ``group`` limits the blend to one group of a shared distribution (the sectors or the contexts of
    the location weights, each holding ``mass`` 0.5); ``None``: all of ``probs`` (``mass`` 1).
    """
    if weight <= 0 or label is None or label not in probs:
        return probs
    members = set(probs) if group is None else set(group)
    out = {c: (p * (1.0 - weight) if c in members else p) for c, p in probs.items()}
    out[label] += weight * mass
    return out
