"""Free-form grounding (SIMSplat Sec. 3.2): appearance narrows the candidates, motion and location choose.

    engine = QueryEngine(default_text_encoder())
    g = engine.ground(scene, "the black car turning left at the intersection")
    g.node_ids, g.message            # (4,), "veh_03 (node 4): a black sedan"
    masks = g.masks(scene)           # [F, C, H, W] bool per-frame pixel masks
    engine.ground(scene, "all crossing pedestrians").node_ids      # every crossing pedestrian
    engine.ground(scene, "the purple bus").message                  # "no purple bus in this scene"

**Parts.** ``query_parse.parse_query`` splits the text into an appearance part (subject noun,
colours, garment colours, the remaining appearance words), a motion phrase (with an explicit crossing
direction) and a location phrase (ego-relative sector and map context). Each part is embedded on its
own with the text encoder (query role), so "turning left" is compared with motion features without
"black car at the intersection" pulling it elsewhere.

**Per-signal match scores in [0, 1].** Per object node:

* *appearance* ``p_app = a * g``: ``g = exp(-(s_best - s) / appearance_temperature)`` with ``s`` the
  cosine of the appearance text with the node's ``f_app`` (``s_best`` the best node's; ``g = 1`` when
  the text is only the category noun: "car" against "a red SUV" or "a white van" is E5 noise of a
  few hundredths that decided group queries), and an attribute factor ``a`` from the node's caption:
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
...", "every ...", plurals) every candidate at or above ``group_threshold``; otherwise the grounding is
empty and its message says which part found nothing ("no pedestrian in this scene is crossing").
``calibrate_thresholds`` picks both thresholds from labelled queries.

**Ablations.** ``use_motion`` / ``use_location`` = ``False`` drop those signals entirely (the benchmark's
App / App+Mot / App+Loc / all rows); ``use_appearance = False`` drops the appearance score, the
category filter and the colour factors (the subject noun still tells the motion part whether "waiting"
is a stopped car or a standing pedestrian).

**Measured**: ``simsplat eval grounding`` on a store (the run's ``tables/grounding*.md``) and
``bench/bench_grounding.py`` (``bench/results/grounding.{json,md}``: 5 unseen reconstructed scenes, the
ablation, and the engine on ground-truth-built scenes).
"""

from __future__ import annotations

import collections
import dataclasses
import logging
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from simsplat_core.language.appearance.colors import UNKNOWN
from simsplat_core.language.codebooks import MotionCodebooks
from simsplat_core.language.query_parse import ParsedQuery, parse_query
from simsplat_core.language.scene_language import LanguageScene, NodeLanguage
from simsplat_core.language.text import QUERY, EmbeddingCache, TextEncoder, l2_normalise
from simsplat_core.language.trajectory import agent_kind

logger = logging.getLogger(__name__)

#: Pedestrian motion classes merged into one "crossing" for scoring (the direction is checked on its own).
CROSSING_CLASSES = ("crossing", "crossing_left_to_right", "crossing_right_to_left")
#: Motion classes of an object that does not move (the motion score of static objects and signs).
STATIONARY_CLASSES = ("parked", "stopped", "standing")

#: Keyword priors: motion phrase regex -> the classes it names (``vocabulary.py`` names, "crossing" =
#: any crossing); each query's prior is uniform over the named classes of the kinds it can refer to.
MOTION_KEYWORDS: tuple[tuple[str, tuple[str, ...]], ...] = (
    (r"\bleft\b.*\bturn|\bturn\w*\b.*\bleft\b|(?:hang|swing|veer|bear|tak)\w* (?:a )?left", ("turning_left",)),
    (r"\bright\b.*\bturn|\bturn\w*\b.*\bright\b|(?:hang|swing|veer|bear|tak)\w* (?:a )?right", ("turning_right",)),
    (r"^(?!.*\b(?:left|right)\b).*(?:\bturn|corner)", ("turning_left", "turning_right")),
    (r"straight|cruising|\bcontinu", ("going_straight",)),
    (r"(?:lane|merg|switch|cut|shift|hop)\w*.*\bleft\b|\bleft\b.*\blane", ("changing_lane_left",)),
    (r"(?:lane|merg|switch|cut|shift|hop)\w*.*\bright\b|\bright\b.*\blane", ("changing_lane_right",)),
    (r"\bslow|decelerat|\bbrak(?!\w* (?:to|until))|losing speed|reducing|easing off", ("slowing_down",)),
    (r"speed\w* up|accelerat|picking up speed|gaining speed|pull\w* away|starting to move|moving off|on the gas", ("speeding_up",)),
    (r"(?:coming|comes|pull\w*|brak\w*) (?:up )?to a (?:stop|halt|standstill)|\bstopping\b|\bstops\b|pull\w* up|until it stands", ("stopping",)),
    (r"stationary|not moving|not going anywhere|sitting still|motionless|standstill|standing still(?! in traffic)", ("stopped", "parked", "standing")),
    (r"\bstopped\b|\bhalted\b|idling|queu|waiting|in traffic|\bstuck\b|sitting in (?:the|its) lane|in (?:its|the) lane", ("stopped", "standing")),
    (r"\bparked\b|parking (?:spot|space|bay)", ("parked",)),
    (r"revers|\bback(?:ing|s)? (?:up|out)|backwards?", ("reversing",)),
    (r"cross|across|\bleft\b.*\bright\b|\bright\b.*\bleft\b|(?:to|towards) the (?:left|right)", ("crossing",)),
    (r"walk|stroll|\bjog|running|\bruns\b|wander|pacing", ("walking_along",)),
    (r"\bstand|waiting|loiter|linger|\bstill\b", ("standing",)),
)
#: Merged motion classes by agent kind (what ``MOTION_KEYWORDS`` may name for each kind).
PEDESTRIAN_MERGED = ("crossing", "walking_along", "standing")
SECTOR_KEYWORDS: tuple[tuple[str, str], ...] = (
    ("in_front_of_ego", r"front|ahead"),
    ("behind_ego", r"behind|\bback\b|\brear\b|following"),
    ("left_of_ego", r"\bleft\b"),
    ("right_of_ego", r"\bright\b(?! (?:ahead|in front|behind))"),
)
CONTEXT_KEYWORDS: tuple[tuple[str, str], ...] = (
    ("at_the_intersection", r"intersection|junction|crossroad"),
    ("on_the_crosswalk", r"crosswalk|zebra|pedestrian crossing"),
    ("on_the_sidewalk", r"sidewalk|pavement|footpath|walkway|footway"),
    ("by_the_curb", r"\bcurb|\bkerb|roadside|side of the road|edge of the road|shoulder|parking"),
    ("in_the_oncoming_lane", r"oncoming|opposite|opposing|towards? (?:us|me|ego|our car)"),
    ("on_the_road", r"\broad\b|\bstreet\b|\blane\b|roadway|carriageway"),
)

#: Colour names the captioner confuses or people use interchangeably (symmetric).
SIMILAR_COLORS: frozenset[frozenset[str]] = frozenset(
    frozenset(p)
    for p in (
        ("white", "silver"),
        ("silver", "gray"),
        ("gray", "black"),
        ("beige", "white"),
        ("beige", "brown"),
        ("orange", "red"),
        ("orange", "yellow"),
        ("orange", "brown"),
        ("pink", "red"),
        ("pink", "purple"),
        ("purple", "blue"),
        ("yellow", "beige"),
    )
)

#: Query subtype -> caption subtypes it also fits, with a factor (1 = same thing). Others get
#: ``subtype_mismatch``. "car" is a generic passenger car.
SUBTYPE_FIT: dict[str, dict[str, float]] = {
    "car": {"sedan": 1.0, "hatchback": 1.0, "SUV": 1.0, "van": 0.3, "pickup truck": 0.3},
    "sedan": {"sedan": 1.0, "hatchback": 0.3},
    "hatchback": {"hatchback": 1.0, "sedan": 0.3},
    "SUV": {"SUV": 1.0, "van": 0.3, "pickup truck": 0.3},
    "van": {"van": 1.0, "SUV": 0.3},
    "pickup truck": {"pickup truck": 1.0, "truck": 0.5, "SUV": 0.3},
    "truck": {"truck": 1.0, "pickup truck": 0.5},
    "bus": {"bus": 1.0},
    "motorcycle": {"motorcycle": 1.0},
    "bicycle": {"bicycle": 1.0},
    "adult": {"adult": 1.0},
    "child": {"child": 1.0},
    "traffic cone": {"traffic cone": 1.0},
    "barrier": {"barrier": 1.0},
    "pole": {"pole": 1.0},
    "stop sign": {"stop sign": 1.0, "sign": 0.6},
    "speed limit sign": {"speed limit sign": 1.0, "sign": 0.6},
    "parking sign": {"parking sign": 1.0, "sign": 0.6},
}


@dataclass(frozen=True)
class QueryConfig:
    """Switches, weights and thresholds of the ``QueryEngine`` (module docstring).

    Attributes:
        use_appearance, use_motion, use_location: which signals are used at all (ablations).
        appearance_weight, motion_weight, location_weight: exponents of the signals in the score's product.
        appearance_temperature: raw cosine gap to the best node that divides the appearance score by e.
        candidate_ratio: narrowing rule: candidates keep ``p_app >= candidate_ratio * max p_app``.
        candidate_top_k: at most this many candidates (``0``: no cap).
        color_mismatch, color_similar: factors for a named colour the caption contradicts / nearly has.
        subtype_mismatch: factor for a named subtype the caption contradicts.
        direction_mismatch: factor for a crossing direction the node's trajectory contradicts.
        missing_appearance: appearance score of a node with neither caption nor ``f_app`` (also the
            factor of a named colour the caption could not tell).
        missing_motion: motion / location score of a node without motion features.
        motion_temperature, location_temperature: softmax temperatures over centred prototype cosines.
        lexicon_weight: share of the keyword prior in the query's class distribution (``0`` = E5 only).
        unknown_floor: when the query names no known category or colour, nodes whose raw appearance
            cosine is below this match nothing ("the giraffe").
        no_match_threshold: a single-object query returns the best candidate only at or above this score.
        group_threshold: a group query returns every candidate at or above this score.
        ambiguity_margin: the message flags a runner-up within this score of the chosen node.
        label_weight: share of the node's auto-labels (the labeller's classes from its trajectory, which
            the aligner was trained to reproduce) in the motion and location weights the node is scored
            with; the rest is the aligner's convex weights (``0`` = aligner only). The equal blend (0.5)
            catches what the learned features miss, mostly rare classes: the aligner calls gentle lane
            changes "going straight" (changing_lane_right 0.04-0.39 where the labeller says
            changing_lane_right) and is weak on real logs zero-shot. Measured (demo scenes, 103 queries /
            5 unseen seeds, 230 queries; acc / vIoU): 0 -> 0.961 / 0.864 and 0.943 / 0.829; 0.25 ->
            0.971 / 0.880 and 0.961 / 0.845; 0.5 -> 0.971 / 0.880 and 0.978 / 0.861.
    """

    use_appearance: bool = True
    use_motion: bool = True
    use_location: bool = True
    appearance_weight: float = 1.0
    motion_weight: float = 1.0
    location_weight: float = 1.0
    appearance_temperature: float = 0.05
    candidate_ratio: float = 0.4
    candidate_top_k: int = 0
    color_mismatch: float = 0.05
    color_similar: float = 0.4
    subtype_mismatch: float = 0.2
    direction_mismatch: float = 0.1
    missing_appearance: float = 0.2
    missing_motion: float = 0.5
    motion_temperature: float = 0.1
    location_temperature: float = 0.1
    lexicon_weight: float = 0.5
    unknown_floor: float = 0.82
    no_match_threshold: float = 0.3
    group_threshold: float = 0.4
    ambiguity_margin: float = 0.02
    label_weight: float = 0.5

    def validate(self) -> "QueryConfig":
        """Check every field; returns ``self``.

        Raises:
            ValueError: naming the first invalid field and its value.
        """
        for name in ("use_appearance", "use_motion", "use_location"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"QueryConfig.{name} must be a bool, got {getattr(self, name)!r}")
        if not (self.use_appearance or self.use_motion or self.use_location):
            raise ValueError("QueryConfig: at least one of use_appearance, use_motion, use_location must be True")
        for name in ("appearance_weight", "motion_weight", "location_weight"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise ValueError(f"QueryConfig.{name} must be a finite number >= 0, got {value!r}")
        for name in ("appearance_temperature", "motion_temperature", "location_temperature"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ValueError(f"QueryConfig.{name} must be a finite number > 0, got {value!r}")
        for name in (
            "candidate_ratio",
            "color_mismatch",
            "color_similar",
            "subtype_mismatch",
            "direction_mismatch",
            "missing_appearance",
            "missing_motion",
            "lexicon_weight",
            "no_match_threshold",
            "group_threshold",
            "ambiguity_margin",
            "label_weight",
        ):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and 0.0 <= value <= 1.0):
                raise ValueError(f"QueryConfig.{name} must be in [0, 1], got {value!r}")
        if not (isinstance(self.unknown_floor, (int, float)) and -1.0 <= self.unknown_floor <= 1.0):
            raise ValueError(f"QueryConfig.unknown_floor must be a cosine in [-1, 1], got {self.unknown_floor!r}")
        top_k = self.candidate_top_k
        if not (isinstance(top_k, int) and not isinstance(top_k, bool) and top_k >= 0):
            raise ValueError(f"QueryConfig.candidate_top_k must be an int >= 0 (0 = no cap), got {top_k!r}")
        return self


@dataclass(frozen=True)
class NodeMatch:
    """One scored node.

    Attributes:
        node_id, object_id: the node and its log object.
        score: combined match score in ``[0, 1]``: the product of the used signals' scores (each raised to
            its weight).
        appearance, motion, location: each signal's match score in ``[0, 1]``, ``nan`` when the signal
            was not used for this query (disabled, or the query has no such part).
        candidate: the node survived the appearance narrowing (only candidates can be chosen).
    """

    node_id: int
    object_id: str
    score: float
    appearance: float
    motion: float
    location: float
    candidate: bool = True


@dataclass(frozen=True)
class Grounding:
    """The answer to one query.

    Attributes:
        query: the text.
        parsed: its parts.
        matches: the chosen node(s), best first; empty when nothing matches.
        ranking: every category-compatible node scored, candidates first, then by score.
        group: the query asked for every matching node.
        message: what was found, or why nothing was ("no pedestrian in this scene is crossing").
    """

    query: str
    parsed: ParsedQuery
    matches: tuple[NodeMatch, ...]
    ranking: tuple[NodeMatch, ...]
    group: bool
    message: str

    @property
    def node_ids(self) -> tuple[int, ...]:
        return tuple(m.node_id for m in self.matches)

    def masks(self, scene: LanguageScene) -> np.ndarray:
        """``[F, C, H, W]`` bool per-frame pixel masks of the matched nodes (all ``False`` without a match)."""
        return scene.masks(self.node_ids)


def _softmax(x: np.ndarray, temperature: float) -> np.ndarray:
    z = (x - x.max()) / temperature
    e = np.exp(z)
    return e / e.sum()


def _keyword_prior(
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


def color_fit(query: str, node: str | None, config: QueryConfig) -> float:
    """Factor for a named colour against one of the caption's colours (module docstring)."""
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


@dataclass(frozen=True)
class _QueryVectors:
    """The query's distributions over the codebooks (``None`` for parts the query does not have)."""

    app: np.ndarray | None  # [D] appearance text embedding (None: the text adds nothing to its noun)
    motion: dict[str, float] | None  # merged motion class -> membership in [0, 1]
    sector: dict[str, float] | None
    context: dict[str, float] | None


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
        config: QueryConfig = QueryConfig(),
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

    def with_config(self, config: QueryConfig) -> "QueryEngine":
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
        motion = self._motion_distribution(parsed, emb[mot_text]) if mot_text else None
        books = self.codebooks if (sec_text or ctx_text) else None
        sector = context = None
        if sec_text:
            sector = self._group_distribution(
                emb[sec_text], books.sector.classes, books.sector.prototypes, books.location_centre,
                cfg.location_temperature, _keyword_prior(sec_text, SECTOR_KEYWORDS, books.sector.classes),
            )
        if ctx_text:
            context = self._group_distribution(
                emb[ctx_text], books.context.classes, books.context.prototypes, books.location_centre,
                cfg.location_temperature,
                _keyword_prior(ctx_text, CONTEXT_KEYWORDS, books.context.classes, fallback="on_the_road"),
            )
        return _QueryVectors(emb[app_text] if app_text else None, motion, sector, context)

    def _group_distribution(
        self,
        query: np.ndarray,
        classes: Sequence[str],
        prototypes: np.ndarray,
        centre: np.ndarray,
        temperature: float,
        prior: np.ndarray | None,
    ) -> dict[str, float]:
        """Softmax of centred cosines of ``query`` with ``prototypes`` ``[K, D]``, mixed with a keyword prior."""
        centred = l2_normalise(prototypes - centre) @ l2_normalise((query - centre)[None])[0]
        return _membership(_softmax(centred, temperature), prior, classes, self.config.lexicon_weight)

    def _motion_distribution(self, parsed: ParsedQuery, query: np.ndarray) -> dict[str, float]:
        """Merged motion class -> probability, over both kinds' codebooks (crossing classes merged)."""
        books = self.codebooks
        classes = books.vehicle.classes + books.pedestrian.classes
        prototypes = np.concatenate([books.vehicle.prototypes, books.pedestrian.prototypes])
        kinds = {agent_kind(c) for c in parsed.categories} - {None}
        allowed = set()
        if not kinds or "vehicle" in kinds:
            allowed |= set(books.vehicle.classes)
        if not kinds or "pedestrian" in kinds:
            allowed |= set(PEDESTRIAN_MERGED)
        merged_classes = [c for c in classes if c not in CROSSING_CLASSES] + ["crossing"]
        hits = [c for rx, named in MOTION_KEYWORDS if re.search(rx, parsed.motion) for c in named if c in allowed]
        if "crossing" in hits:
            hits = [c for c in hits if c != "walking_along"]  # "walking across" is a crossing
        prior = _uniform(list(dict.fromkeys(hits)), merged_classes)
        centred = l2_normalise(prototypes - books.motion_centre) @ l2_normalise((query - books.motion_centre)[None])[0]
        probs = _softmax(centred, self.config.motion_temperature)
        merged = collections.defaultdict(float)
        for name, p in zip(classes, probs):
            merged["crossing" if name in CROSSING_CLASSES else name] += float(p)
        probs = np.array([merged[c] for c in merged_classes])
        return _membership(probs, prior, merged_classes, self.config.lexicon_weight)

    # ------------------------------------------------------------------ node side
    def _motion_score(self, parsed: ParsedQuery, dist: dict[str, float], node: NodeLanguage) -> float:
        feats = node.motion
        if feats is None:
            if node.category in ("static", "sign") or not node.kind:
                return float(sum(dist.get(c, 0.0) for c in STATIONARY_CLASSES))
            return self.config.missing_motion
        score = 0.0
        label = feats.labels.motion
        for name, weight in _with_label(feats.motion_probs, label, 1.0, self.config.label_weight).items():
            score += dist.get("crossing" if name in CROSSING_CLASSES else name, 0.0) * weight
        if parsed.crossing_direction and feats.kind == "pedestrian":
            if feats.labels.motion != f"crossing_{parsed.crossing_direction}":
                score *= self.config.direction_mismatch
        return float(min(max(score, 0.0), 1.0))

    def _location_score(
        self, sector: dict[str, float] | None, context: dict[str, float] | None, node: NodeLanguage
    ) -> float:
        feats = node.motion
        if feats is None:
            return self.config.missing_motion
        probs = feats.location_probs
        books = self.codebooks  # sectors and contexts each hold half of the location weights
        probs = _with_label(probs, feats.labels.sector, 0.5, self.config.label_weight, books.sector.classes)
        probs = _with_label(probs, feats.labels.context, 0.5, self.config.label_weight, books.context.classes)
        score = 1.0
        for dist in (sector, context):
            if dist is None:
                continue
            mass = sum(probs.get(c, 0.0) for c in dist)
            if mass <= 0:
                score *= self.config.missing_motion
                continue
            score *= sum(p * probs.get(c, 0.0) / mass for c, p in dist.items())
        return float(np.clip(score, 0.0, 1.0))

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
        use_mot = cfg.use_motion and vectors.motion is not None
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
            missing = cfg.missing_appearance if scene_has_appearance(scene) else 1.0  # no images: neutral
            p_app = np.where(has_caption | has_feature, g * attrs, missing)
        p_mot = np.full(len(nodes), nan)
        if use_mot:
            p_mot = np.array([self._motion_score(parsed, vectors.motion, n) for n in nodes])
        p_loc = (
            np.array([self._location_score(vectors.sector, vectors.context, n) for n in nodes])
            if use_loc
            else np.full(len(nodes), nan)
        )

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
            matches = tuple(m for m in candidates if m.score >= cfg.group_threshold)
        else:
            matches = tuple(candidates[:1]) if candidates and candidates[0].score >= cfg.no_match_threshold else ()
        if not self._scored_parts(parsed):
            matches = ()
        looks = _looks_named(parsed)
        if cfg.use_appearance and looks and not scene_has_appearance(scene):
            matches = ()
            message = (f"{scene.seq_id} has no camera images: its objects' looks ({looks}) cannot be checked; "
                       "ask by category, motion or location instead")
        else:
            message = self._message(scene, parsed, ranking, matches)
        logger.debug("%s: %r -> %s (%s)", scene.seq_id, text, [m.node_id for m in matches], message)
        return Grounding(text, parsed, matches, ranking, parsed.group, message)

    def _scored_parts(self, parsed: ParsedQuery) -> list[str]:
        cfg = self.config
        parts = []
        if cfg.use_appearance and parsed.has_appearance:
            parts.append("appearance")
        if cfg.use_motion and parsed.motion:
            parts.append("motion")
        if cfg.use_location and parsed.location:
            parts.append("location")
        return parts

    def _message(
        self, scene: LanguageScene, parsed: ParsedQuery, ranking: tuple[NodeMatch, ...], matches: tuple[NodeMatch, ...]
    ) -> str:
        cfg = self.config
        if not self._scored_parts(parsed):
            switches = (("appearance", cfg.use_appearance), ("motion", cfg.use_motion), ("location", cfg.use_location))
            enabled = [name for name, on in switches if on]
            return f"nothing to compare: the query has no {' / '.join(enabled)} part that the engine recognised"
        if matches:
            if parsed.group:
                ids = ", ".join(f"{m.object_id} (node {m.node_id})" for m in matches)
                return f"{len(matches)} match{'es' if len(matches) != 1 else ''}: {ids}"
            best = matches[0]
            node = scene.node(best.node_id)
            text = f"{best.object_id} (node {best.node_id})" + (f": {node.caption.text}" if node.caption else "")
            runner = [m for m in ranking if m.candidate and m.node_id != best.node_id]
            if runner and best.score - runner[0].score <= cfg.ambiguity_margin:
                text += f" (ambiguous: {runner[0].object_id} scores {runner[0].score:.3f} vs {best.score:.3f})"
            return text
        subject = (parsed.subject() if parsed.noun or parsed.named_colors or parsed.excluded_colors
                   else (parsed.appearance or "object"))
        if not ranking:
            return f"no {subject} in this scene"
        candidates = [m for m in ranking if m.candidate]
        threshold = cfg.group_threshold if parsed.group else cfg.no_match_threshold

        def best_of(attr: str) -> float:
            values = [getattr(m, attr) for m in candidates if np.isfinite(getattr(m, attr))]
            return max(values) if values else float("nan")

        app_failed = np.isfinite(best_of("appearance")) and best_of("appearance") < threshold
        clauses = []
        mot_failed = cfg.use_motion and parsed.motion and best_of("motion") < threshold
        loc_failed = cfg.use_location and parsed.location and best_of("location") < threshold
        if mot_failed:
            clauses.append(_predicate(parsed.motion))
        if loc_failed:
            clauses.append(parsed.location)
        if not clauses and not app_failed:  # each part matches some node, but no node matches them all
            if cfg.use_motion and parsed.motion:
                clauses.append(_predicate(parsed.motion))
            if cfg.use_location and parsed.location:
                clauses.append(parsed.location)
        if not clauses:
            return f"no {subject} in this scene"
        verb = "is" if not clauses[0].startswith("that ") else ""
        return " ".join(w for w in ("no", subject, "in this scene", verb, " ".join(clauses)) if w)


def scene_has_appearance(scene: LanguageScene) -> bool:
    """Whether any object node of ``scene`` has a caption or ``f_app`` (``False`` for logs without images)."""
    return any(n.caption is not None or n.f_app is not None for n in scene.nodes)


def _looks_named(parsed: ParsedQuery) -> str:
    """The query's appearance words beyond the category ("red", "not red", "big"); ``""`` when none."""
    words = [*parsed.named_colors, *(f"not {c}" for c in parsed.excluded_colors)]
    if parsed.appearance_extra and not parsed.named_colors:
        words.append(parsed.appearance_extra)
    return ", ".join(words)


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


def _predicate(motion: str) -> str:
    """"crossing" -> "crossing"; "turns left" -> "that turns left" (a finite verb needs a relative pronoun)."""
    first = motion.split(" ", 1)[0]
    if first.endswith("ing") or first.endswith("ed") or first in ("in", "at", "from", "stationary", "not"):
        return motion
    return f"that {motion}"


def calibrate_thresholds(
    engine: QueryEngine,
    examples: Sequence[tuple[LanguageScene, str, frozenset[int]]],
    balanced: bool = True,
) -> QueryConfig:
    """``engine.config`` with ``no_match_threshold`` and ``group_threshold`` chosen on labelled queries.

    Each example is ``(scene, query, expected node ids)``; an empty set means the query should match
    nothing. Single-object queries are right when the best candidate is expected and reaches the
    threshold, or nothing is expected and it does not; group queries score the Jaccard index of the
    returned and expected sets (1 when both are empty). With ``balanced`` the single-object accuracy is
    the mean of the accuracies on queries that should and should not match (benchmarks hold far more
    of the former, and a plain mean would trade "says so when nothing matches" for a few weak true
    matches). Each threshold is the middle of the longest run of candidate values (midpoints between
    observed scores) that maximises the objective; a threshold without examples of its kind keeps its
    current value.

    Raises:
        ValueError: no examples.
    """
    if not examples:
        raise ValueError("calibrate_thresholds needs at least one labelled example")
    singles: list[tuple[float, bool, bool]] = []  # (best candidate score, best is expected, nothing expected)
    groups: list[tuple[list[tuple[float, int]], frozenset[int]]] = []
    for scene, text, expected in examples:
        parsed = parse_query(text)
        ranking = engine.rank(scene, parsed) if engine._scored_parts(parsed) else ()
        candidates = [(m.score, m.node_id) for m in ranking if m.candidate]
        expected = frozenset(expected)
        if parsed.group:
            groups.append((candidates, expected))
        else:
            best_score, best_id = candidates[0] if candidates else (-1.0, -1)
            singles.append((best_score, best_id in expected, not expected))

    def single_accuracy(t: float) -> float:
        right = np.array([(ok and s >= t) if not empty else (s < t) for s, ok, empty in singles], dtype=float)
        empty = np.array([e for _, _, e in singles], dtype=bool)
        if balanced and empty.any() and (~empty).any():
            return float(0.5 * (right[empty].mean() + right[~empty].mean()))
        return float(right.mean())

    def group_jaccard(t: float) -> float:
        values = []
        for candidates, expected in groups:
            got = {node for score, node in candidates if score >= t}
            union = got | expected
            values.append(1.0 if not union else len(got & expected) / len(union))
        return float(np.mean(values))

    cfg = engine.config
    no_match = _best_threshold([s for s, _, _ in singles], single_accuracy) if singles else cfg.no_match_threshold
    group = _best_threshold([s for c, _ in groups for s, _ in c], group_jaccard) if groups else cfg.group_threshold
    if singles:
        logger.info("no-match threshold %.3f: accuracy %.3f on %d single-object queries",
                    no_match, single_accuracy(no_match), len(singles))
    if groups:
        logger.info("group threshold %.3f: mean Jaccard %.3f on %d group queries",
                    group, group_jaccard(group), len(groups))
    return dataclasses.replace(cfg, no_match_threshold=float(no_match), group_threshold=float(group)).validate()


def _best_threshold(scores: Sequence[float], objective) -> float:
    """Middle of the longest run of thresholds (between consecutive observed scores) maximising ``objective``."""
    values = sorted({min(max(s, 0.0), 1.0) for s in scores} | {0.0, 1.0})
    points = [0.0] + [0.5 * (a + b) for a, b in zip(values, values[1:])] + [1.0]
    points = sorted(set(points))
    objectives = [objective(t) for t in points]
    top = max(objectives)
    best_run: tuple[int, int] | None = None
    start = None
    for i, value in enumerate(objectives + [-1.0]):
        if value >= top - 1e-12 and start is None:
            start = i
        elif value < top - 1e-12 and start is not None:
            run = (start, i - 1)
            if best_run is None or points[run[1]] - points[run[0]] > points[best_run[1]] - points[best_run[0]]:
                best_run = run
            start = None
    assert best_run is not None
    return 0.5 * (points[best_run[0]] + points[best_run[1]])
