"""Free-form grounding (SIMSplat Sec. 3.2): appearance narrows the candidates, motion and location choose.

    engine = QueryEngine(default_text_encoder())
    g = engine.ground(scene, "the black car turning left at the intersection")
    g.node_ids, g.message            # (4,), "veh_03 (node 4): a black sedan"
    masks = g.masks(scene)           # [F, C, H, W] bool per-frame pixel masks
    engine.ground(scene, "all crossing pedestrians").node_ids      # every crossing pedestrian
    engine.ground(scene, "the purple bus").message                  # "no purple bus in this scene"

**Parts.** ``parse.parse_query`` splits the text into an appearance part (subject noun,
colours, garment colours, the remaining appearance words), a motion phrase (with an explicit crossing
direction) and a location phrase (ego-relative sector and map context). Each part is embedded on its
own with the text encoder (query role), so "turning left" is compared with motion features without
"black car at the intersection" pulling it elsewhere.

**Per-signal match scores in [0, 1].** Per object node:

* *appearance* ``p_app = a * g``: ``g = exp(-(s_best - s) / appearance_temperature)`` with ``s`` the
  cosine of the appearance text with the node's ``f_app`` (``s_best`` the best node's; ``g = 1`` when
  the text is only the category noun: "car" against "a red SUV" or "a white van" is E5 noise of a
  few hundredths that decided group queries; ``g >= caption_confirmed_floor`` when the caption names
  every colour the query names and fits its subtype: the field's rendered mean mixes views and can sit
  0.05 cosine below the best node, which alone dropped "a silver hatchback" from "the silver car turning
  left"), and an attribute factor ``a`` from the node's caption:
  each colour the query names multiplies by 1 when the caption has it (garment colours compared
  garment by garment: E5 cannot tell "red shirt and blue pants" from "blue shirt and red pants"), by
  ``color_similar`` for a neighbouring name (white/silver, silver/gray, orange/red, ...) and by
  ``color_mismatch`` otherwise; a named subtype ("SUV") that the
  caption contradicts ("sedan") multiplies by ``subtype_mismatch`` (or a milder factor for related
  body styles). A named category is a hard filter: a "pedestrian" query never returns a car.
* *motion* ``p_mot = sum_k m_q(k) w(k)``: ``w`` are the node's convex weights over the motion codebook
  (``ObjectMotionFeatures.motion_probs``: the coordinates of ``f_mot`` on its prototypes) and
  ``m_q(k)`` in ``[0, 1]`` how far the query names class ``k``: ``(1 - lexicon_weight)`` times a
  softmax of centred cosines between the motion text's embedding and the prototypes of both kinds
  (``motion_temperature``), divided by its maximum, plus ``lexicon_weight`` for every class a keyword
  names (``MOTION_KEYWORDS``; "stationary" names both stopped and parked). Raw E5 cosines of these
  phrases all sit in 0.8-0.95, so they are centred on the prototypes' mean, like the aligner's loss;
  E5 also ranks "stopped" closer to "stopping" than to "stopped", which the keywords correct. The
  three crossing classes are merged (E5 cannot separate the directions); a parsed crossing direction
  is checked against the node's trajectory label instead (``direction_mismatch`` when it differs).
  ``p_mot`` is thus the probability that the node moves the way the query says, comparable across
  queries.
* *location* ``p_loc``: the same over the sector (front / behind / left / right of ego) and context
  (intersection, crosswalk, sidewalk, curb, oncoming lane, road) codebooks, multiplied over the
  groups the query mentions ("on my left at the intersection" must be both).

A node that lacks a signal gets a fixed score for it: ``missing_appearance`` without caption and
``f_app`` (too few pixels ever to be described: unlikely to be what someone describes; in a scene
where *no* node has either, a log without camera images such as Argoverse 2's, appearance is neutral
instead: the category still filters, and a query naming colours or other looks matches nothing and
says the log has no images), and
``missing_motion`` without motion features (static objects get the query's stationary mass for
motion instead).

**Narrowing and choosing.** With appearance on, the candidates are the category-compatible nodes whose
``p_app`` is at least ``candidate_ratio`` of the best one's (optionally at most ``candidate_top_k``);
the score of a candidate is the product of the scores of the signals the query uses and the config
enables (each raised to its weight): read as the probability that every part matches, so one clearly
failed part (a car that is not turning) sinks the whole match. A single-object
query returns the best candidate when its score reaches ``no_match_threshold``, a group query ("all
...", "every ...", plurals) every candidate at or above ``group_threshold`` (of those captioned the body style
it names, when any is: "the pickup trucks" are not joined by a box truck); otherwise the grounding is
empty and its message says which part found nothing ("no pedestrian in this scene is crossing") -- except
that a single-object query naming a colour and a motion or location that no candidate fits takes the node
whose caption names a neighbouring colour and fits the rest (``_nearest_colour``: the captioner names a
sunlit silver car white, so "the silver car continuing straight" is the white one doing it; the message says
so).
``simsplat_core.eval.grounding.calibration.calibrate_thresholds`` picks both thresholds from labelled
queries.

**Ablations.** ``use_motion`` / ``use_location`` = ``False`` drop those signals entirely (the benchmark's
App / App+Mot / App+Loc / all rows); ``use_appearance = False`` drops the appearance score, the
category filter and the colour factors (the subject noun still tells the motion part whether "waiting"
is a stopped car or a standing pedestrian).

**Measured**: ``simsplat eval grounding`` on a store (the run's ``tables/grounding*.md``) and
``bench/bench_grounding.py`` (``bench/results/grounding.{json,md}``: 5 unseen reconstructed scenes, the
ablation, and the engine on ground-truth-built scenes).

**Modules** (of ``language.grounding``). ``engine`` (this one), ``parse`` (the parts of a query), ``lexicon``
(keyword and colour tables), ``config`` (``QueryConfig``), ``scoring`` (the per-signal
scores as functions), ``messages`` (the answer in words), ``result`` (``NodeMatch``,
``Grounding``).
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from simsplat_core.language.codebooks import MotionCodebooks
from simsplat_core.language.grounding.config import QueryConfig
from simsplat_core.language.grounding.lexicon import CONTEXT_KEYWORDS, SECTOR_KEYWORDS
from simsplat_core.language.grounding.messages import grounding_message, nearest_colour_message, no_images_message
from simsplat_core.language.grounding.parse import ParsedQuery, parse_query
from simsplat_core.language.grounding.result import Grounding, NodeMatch
from simsplat_core.language.grounding.scoring import (
    attribute_fit,
    group_distribution,
    keyword_prior,
    location_score,
    looks_named,
    motion_distribution,
    motion_score,
    scene_has_appearance,
    subtype_fit,
)
from simsplat_core.language.scene_language import LanguageScene
from simsplat_core.language.text import QUERY, EmbeddingCache, TextEncoder, l2_normalise
from simsplat_core.scenario import vocabulary as voc

logger = logging.getLogger(__name__)

#: The default configuration (frozen, so one instance serves every query engine).
DEFAULT_QUERY_CONFIG = QueryConfig()


@dataclass(frozen=True)
class _QueryVectors:
    """The query's distributions over the codebooks (``None`` for parts the query does not have)."""

    app: np.ndarray | None  # [D] appearance text embedding (None: the text adds nothing to its noun)
    motion: dict[str, float] | None  # merged motion class -> membership in [0, 1]
    sector: dict[str, float] | None
    context: dict[str, float] | None


def _named_style_first(scene: LanguageScene, parsed: ParsedQuery, matches: tuple[NodeMatch, ...],
                       config: QueryConfig) -> tuple[NodeMatch, ...]:
    """A group query naming a body style ("the pickup trucks") takes the nodes captioned that style when there
    are any: a related style ("truck", ``SUBTYPE_FIT`` 0.5) stands in only for a style no node has."""
    if parsed.subtype is None:
        return matches
    named = tuple(m for m in matches if (cap := scene.node(m.node_id).caption) is not None
                  and subtype_fit(parsed.subtype, cap.subtype, config) >= 1.0)
    return named or matches


class QueryEngine:
    """Grounds free-form descriptions in a ``LanguageScene`` (module docstring).

    Args:
        text_encoder: the encoder of the scene's text space (``scene.text_encoder`` must equal its name).
        config: switches, weights and thresholds; validated here.
        codebooks: the motion/location prototypes; built from ``text_encoder`` on first use when ``None``.
        cache_size: query embeddings kept (E5 takes tens to hundreds of ms per uncached text).
    """

    def __init__(
        self,
        text_encoder: TextEncoder,
        config: QueryConfig = DEFAULT_QUERY_CONFIG,
        codebooks: MotionCodebooks | None = None,
        cache_size: int = 4096,
    ) -> None:
        self.text_encoder = text_encoder
        self.config = config.validate()
        if codebooks is not None and codebooks.encoder_name != text_encoder.name:
            raise ValueError(
                f"codebooks are in the space of {codebooks.encoder_name!r}, the text encoder is {text_encoder.name!r}"
            )
        self._codebooks = codebooks
        self._cache = EmbeddingCache(cache_size)

    @property
    def cache_hits(self) -> int:
        """Texts ``embed`` found in the (shared) embedding cache."""
        return self._cache.hits

    @property
    def cache_misses(self) -> int:
        """Texts ``embed`` had to encode."""
        return self._cache.misses

    def with_config(self, config: QueryConfig) -> QueryEngine:
        """A new engine with ``config`` sharing this one's encoder, codebooks and embedding cache."""
        other = QueryEngine(self.text_encoder, config, self._codebooks, self._cache.max_entries)
        other._cache = self._cache
        return other

    # ------------------------------------------------------------------ text side
    @property
    def codebooks(self) -> MotionCodebooks:
        if self._codebooks is None:
            self._codebooks = MotionCodebooks.build(self.text_encoder)
        return self._codebooks

    def embed(self, texts: Sequence[str]) -> dict[str, np.ndarray]:
        """``text -> [D]`` query embeddings, uncached texts encoded in one batch."""
        wanted = list(dict.fromkeys(t for t in texts if t))
        if not wanted:
            return {}
        rows = self._cache.lookup(QUERY, wanted, lambda batch: l2_normalise(self.text_encoder.encode_queries(batch)))
        return dict(zip(wanted, rows))

    def prepare(self, texts: Sequence[str], batch_size: int = 64) -> int:
        """Embed, in batches, everything answering ``texts`` will need (the whole texts too, which
        text-only baselines sharing the encoder embed), so a benchmark pays batched rather than
        one-by-one encoder calls. Returns how many texts were embedded."""
        wanted: list[str] = []
        for text in texts:
            parsed = parse_query(text)
            wanted += [text, parsed.appearance, parsed.motion_text, parsed.sector, parsed.context]
        wanted = list(dict.fromkeys(t for t in wanted if t))
        for start in range(0, len(wanted), batch_size):
            self.embed(wanted[start:start + batch_size])
        return len(wanted)

    def _query_vectors(self, parsed: ParsedQuery) -> _QueryVectors:
        cfg = self.config
        app_text = parsed.appearance if (cfg.use_appearance and parsed.appearance_extra) else ""
        texts = [
            app_text,
            parsed.motion_text if cfg.use_motion else "",
            parsed.sector if cfg.use_location else "",
            parsed.context if cfg.use_location else "",
        ]
        emb = self.embed(texts)
        app_text, mot_text, sec_text, ctx_text = texts
        motion = motion_distribution(parsed, emb[mot_text], self.codebooks, cfg) if mot_text else None
        sector = context = None
        if sec_text:
            books = self.codebooks
            sector = group_distribution(
                emb[sec_text], books.sector.classes, books.sector.prototypes, books.location_centre,
                cfg.location_temperature, keyword_prior(sec_text, SECTOR_KEYWORDS, books.sector.classes),
                cfg.lexicon_weight,
            )
        if ctx_text:
            books = self.codebooks
            context = group_distribution(
                emb[ctx_text], books.context.classes, books.context.prototypes, books.location_centre,
                cfg.location_temperature,
                keyword_prior(ctx_text, CONTEXT_KEYWORDS, books.context.classes, fallback=voc.ON_THE_ROAD),
                cfg.lexicon_weight,
            )
        return _QueryVectors(emb[app_text] if app_text else None, motion, sector, context)

    # ------------------------------------------------------------------ grounding
    def rank(self, scene: LanguageScene, parsed: ParsedQuery) -> tuple[NodeMatch, ...]:
        """Every category-compatible node of ``scene`` scored for ``parsed``: candidates first, best first."""
        if scene.text_encoder != self.text_encoder.name:
            raise ValueError(
                f"{scene.seq_id}: the scene's features are in the space of {scene.text_encoder!r}, "
                f"the engine encodes queries with {self.text_encoder.name!r}"
            )
        cfg = self.config
        vectors = self._query_vectors(parsed)
        nodes = list(scene.nodes)
        if cfg.use_appearance and parsed.categories:
            nodes = [n for n in nodes if n.category in parsed.categories]
        if not nodes:
            return ()
        use_app = cfg.use_appearance and parsed.has_appearance
        motion = vectors.motion if cfg.use_motion else None
        use_mot = motion is not None
        use_loc = cfg.use_location and (vectors.sector is not None or vectors.context is not None)

        nan = float("nan")
        p_app = np.full(len(nodes), nan)
        if use_app:
            # a node described by one appearance source (caption or f_app) is judged by that one
            has_caption = np.array([n.caption is not None for n in nodes])
            has_feature = np.array([n.f_app is not None for n in nodes])
            g = np.ones(len(nodes))
            if vectors.app is not None and has_feature.any():
                sims = np.array([float(n.f_app @ vectors.app) if n.f_app is not None else nan for n in nodes])
                best = float(np.max(sims[has_feature]))
                g[has_feature] = np.exp(-(best - sims[has_feature]) / cfg.appearance_temperature)
                if not parsed.categories and not parsed.named_colors:  # "the giraffe": nothing known to check
                    g[has_feature & (np.nan_to_num(sims, nan=1.0) < cfg.unknown_floor)] = 0.0
            attrs = np.array([attribute_fit(parsed, n, cfg) if n.caption is not None else 1.0 for n in nodes])
            if parsed.named_colors:
                confirmed = has_caption & (attrs >= 1.0)
                g[confirmed] = np.maximum(g[confirmed], cfg.caption_confirmed_floor)
            missing = cfg.missing_appearance if scene_has_appearance(scene) else 1.0  # no images: neutral
            p_app = np.where(has_caption | has_feature, g * attrs, missing)
        p_mot = np.full(len(nodes), nan)
        if motion is not None:
            p_mot = np.array([motion_score(parsed, motion, n, cfg) for n in nodes])
        p_loc = np.full(len(nodes), nan)
        if use_loc:
            books = self.codebooks
            p_loc = np.array([location_score(vectors.sector, vectors.context, n, cfg, books) for n in nodes])

        signals = (
            (p_app, cfg.appearance_weight, use_app),
            (p_mot, cfg.motion_weight, use_mot),
            (p_loc, cfg.location_weight, use_loc),
        )
        used = [(p, w) for p, w, on in signals if on and w > 0]
        if used:
            scores = np.exp(sum(w * np.log(np.maximum(p, 1e-12)) for p, w in used))
        else:
            scores = np.zeros(len(nodes))

        candidate = np.ones(len(nodes), dtype=bool)
        if use_app and np.nanmax(p_app) > 0:
            candidate = p_app >= cfg.candidate_ratio * np.nanmax(p_app)
            if cfg.candidate_top_k:
                keep = np.argsort(-p_app, kind="stable")[: cfg.candidate_top_k]
                capped = np.zeros(len(nodes), dtype=bool)
                capped[keep] = True
                candidate &= capped
        order = sorted(range(len(nodes)), key=lambda i: (not candidate[i], -scores[i], nodes[i].node_id))
        return tuple(
            NodeMatch(
                node_id=nodes[i].node_id,
                object_id=nodes[i].object_id,
                score=float(scores[i]),
                appearance=float(p_app[i]),
                motion=float(p_mot[i]),
                location=float(p_loc[i]),
                candidate=bool(candidate[i]),
            )
            for i in order
        )

    def _nearest_colour(self, scene: LanguageScene, parsed: ParsedQuery,
                        ranking: tuple[NodeMatch, ...]) -> NodeMatch | None:
        """For a single-object query naming colours and a motion or location that no candidate fits: the node
        whose caption names a neighbouring colour (``SIMILAR_COLORS``: the captioner names a sunlit silver body
        white, a grey one silver) and that fits everything else, scored by the caption's colour factor alone
        (the field feature follows the caption's name) -- when it reaches ``no_match_threshold``."""
        cfg = self.config
        if not (cfg.use_appearance and parsed.named_colors and cfg.scored_parts(parsed)
                and (parsed.motion or parsed.location)):
            return None
        best: NodeMatch | None = None
        for m in ranking:
            node = scene.node(m.node_id)
            if m.candidate or node.caption is None:
                continue
            attrs = attribute_fit(parsed, node, cfg)
            if attrs < cfg.color_similar:
                continue
            parts = [(attrs, cfg.appearance_weight)] + [(p, w) for p, w in ((m.motion, cfg.motion_weight),
                                                                           (m.location, cfg.location_weight))
                                                       if np.isfinite(p)]
            score = float(np.exp(sum(w * np.log(max(p, 1e-12)) for p, w in parts)))
            if score >= cfg.no_match_threshold and (best is None or score > best.score):
                best = dataclasses.replace(m, score=score, appearance=attrs)
        return best

    def ground(self, scene: LanguageScene, text: str) -> Grounding:
        """Ground ``text`` in ``scene`` (module docstring).

        Raises:
            ValueError: empty text, or a scene in another text encoder's space.
        """
        parsed = parse_query(text)
        ranking = self.rank(scene, parsed)
        candidates = [m for m in ranking if m.candidate]
        cfg = self.config
        if parsed.group:
            matches = _named_style_first(scene, parsed, tuple(m for m in candidates if m.score >= cfg.group_threshold),
                                         cfg)
        else:
            matches = tuple(candidates[:1]) if candidates and candidates[0].score >= cfg.no_match_threshold else ()
        if not cfg.scored_parts(parsed):
            matches = ()
        nearest = None if matches or parsed.group else self._nearest_colour(scene, parsed, ranking)
        looks = looks_named(parsed)
        if cfg.use_appearance and looks and not scene_has_appearance(scene):
            matches = ()
            message = no_images_message(scene, looks)
        elif nearest is not None:
            matches = (nearest,)
            message = nearest_colour_message(scene, parsed, nearest)
        else:
            message = grounding_message(scene, parsed, ranking, matches, cfg)
        logger.debug("%s: %r -> %s (%s)", scene.seq_id, text, [m.node_id for m in matches], message)
        return Grounding(text, parsed, matches, ranking, parsed.group, message)
