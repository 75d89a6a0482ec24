"""Answer a parsed description over one log: per-frame truth per object, windows, ranked hits.

A clause holds for object ``o`` at frame ``f`` when (``describe`` names the parts):

* ``o``'s category is one the subject allows and its appearance fits (``grounding.scoring.attribute_fit`` of the
  captioner's caption, at least ``SearchConfig.min_appearance``; logs without captions cannot check
  colours or subtypes and let every object of the category through);
* its window motion class at ``f`` is one the clause names (the crossing classes count as "crossing"; a
  named crossing direction must be the labelled one), its sector at ``f`` one named, every named map
  context holds at ``f``;
* appearance: a named colour must be the caption's colour (``SearchConfig.query`` counts a neighbour colour,
  "blue" for "purple", as a mismatch: the grounding engine may let the nearest colour win among one scene's
  candidates, a search over many logs must not);
* "in the ego lane": ``0 < along < ego_lane_ahead_m`` and ``|offset| < ego_lane_half_m`` against the ego's own
  path ahead (``frames.EgoPath``: the lane bends with the ego through a turn);
* a cut-in: a lane-change class, ``0 < along < cut_in_ahead_m``, ``|offset| < cut_in_half_m`` and the offset
  closing in (``|offset|`` shrinking by more than ``cut_in_closing_mps``);
* the ego as the subject: only the ego's own facts (``frames.EGO_ID``) answer the clause; other clauses never
  pick the ego;
* a count (``AgentClause.count``): that many distinct objects hold at once (``together``: each within
  ``together_m`` of another of them);
* a relation holds with some other object for which the related clause holds at ``f``: *following* = the
  other is ahead within ``follow_m`` along ``o``'s heading, within ``lane_half_m`` sideways, heading within
  ``follow_deg``; *leading* the same the other way round; *beside* = within ``beside_m`` sideways and
  ``beside_ahead_m`` along.

The description holds at frame ``f`` when every clause holds for some object (``count`` objects). Hits are
windows of ``windows.frame_windows`` (per object for one-clause, one-object descriptions, per log otherwise);
score = mean appearance fit of the hit's objects times ``0.5 + 0.5 * min(1, frames / full_window_frames)``.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from simsplat_core.geometry import wrap_angle
from simsplat_core.language.grounding.config import QueryConfig
from simsplat_core.language.grounding.lexicon import CROSSING_CLASSES
from simsplat_core.language.grounding.scoring import attribute_fit
from simsplat_core.language.scene_language import NodeLanguage
from simsplat_core.scenario import vocabulary as voc
from simsplat_core.scenario.agents import EGO_ID
from simsplat_core.search.describe import BESIDE, FOLLOWING, LEADING, AgentClause, SearchQuery, parse_description
from simsplat_core.search.frames import ObjectFrames
from simsplat_core.search.windows import frame_windows

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class SearchConfig:
    """Thresholds of the module docstring (metres, degrees, frames)."""

    min_appearance: float = 0.35
    ego_lane_ahead_m: float = 40.0
    ego_lane_half_m: float = 1.8
    cut_in_ahead_m: float = 30.0
    cut_in_half_m: float = 4.5
    cut_in_closing_mps: float = 0.3
    together_m: float = 3.0
    follow_m: float = 30.0
    lane_half_m: float = 2.0
    follow_deg: float = 30.0
    beside_m: float = 5.0
    beside_ahead_m: float = 5.0
    min_frames: int = 3
    max_gap: int = 2
    full_window_frames: int = 20
    query: QueryConfig = field(default_factory=lambda: QueryConfig(color_similar=QueryConfig().color_mismatch))


@dataclass(frozen=True)
class SearchHit:
    """One place where the description holds.

    Attributes:
        seq_id: the log.
        object_ids: the objects that make it hold (subject first, then related / other clauses' objects).
        window: ``(first frame, last frame)``, inclusive.
        score: ranking score in ``[0, 1]``.
        picture: URI of the picture drawn for the hit (``""`` when none was drawn).
    """

    seq_id: str
    object_ids: tuple[str, ...]
    window: tuple[int, int]
    score: float
    picture: str = ""

    @property
    def middle_frame(self) -> int:
        return (self.window[0] + self.window[1]) // 2


@dataclass(frozen=True)
class SearchResult:
    """A description answered over one log: the ranked hits, the frames covered, and why nothing matched."""

    seq_id: str
    query: SearchQuery
    hits: tuple[SearchHit, ...]
    frames: np.ndarray  # [F] bool: the description holds (before windowing)
    message: str = ""


def _motion_ok(clause: AgentClause, of: ObjectFrames) -> np.ndarray:
    """``[F]`` bool: the object's window motion is one the clause names."""
    if not clause.motions:
        return of.present.copy()
    names = set(clause.motions)
    if voc.CROSSING in names:
        names |= set(CROSSING_CLASSES)
    ok = np.isin(of.motion, list(names))
    if clause.crossing_direction and of.kind == voc.PEDESTRIAN:
        left_to_right = clause.crossing_direction == "left_to_right"
        wanted = voc.CROSSING_LEFT_TO_RIGHT if left_to_right else voc.CROSSING_RIGHT_TO_LEFT
        ok &= of.motion == wanted
    return ok


def appearance_fit(clause: AgentClause, of: ObjectFrames, node: NodeLanguage | None, config: SearchConfig) -> float:
    """How far the object looks like the subject (0: wrong category); the ego is the ego clauses' subject only."""
    if clause.is_ego or of.object_id == EGO_ID:
        return float(clause.is_ego and of.object_id == EGO_ID)
    cats = clause.parsed.categories
    if cats and of.category not in cats:
        return 0.0
    if of.kind not in clause.kinds:
        return 0.0
    if node is None or node.caption is None:
        # an aligned log's object without a caption (never seen well enough) cannot show a named colour or subtype
        named = clause.parsed.named_colors or clause.parsed.subtype not in (None, "car")
        return config.query.missing_appearance if named and node is not None else 1.0
    return float(attribute_fit(clause.parsed, node, config.query))


def _pair_geometry(a: ObjectFrames, b: ObjectFrames) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(along, lateral, heading difference deg)`` ``[F]`` of ``b`` in the frame of ``a`` (``nan``: either absent)."""
    d = b.xy - a.xy
    c, s = np.cos(a.heading), np.sin(a.heading)
    along = d[:, 0] * c + d[:, 1] * s
    lateral = -d[:, 0] * s + d[:, 1] * c
    dh = np.abs(np.rad2deg(wrap_angle(np.nan_to_num(b.heading - a.heading))))
    return along, lateral, dh


def _related(a: ObjectFrames, b: ObjectFrames, relation: str, config: SearchConfig) -> np.ndarray:
    """``[F]`` bool: ``a`` stands in ``relation`` to ``b``."""
    both = a.present & b.present
    if relation == LEADING:
        return _related(b, a, FOLLOWING, config)
    along, lateral, dh = _pair_geometry(a, b)
    with np.errstate(invalid="ignore"):
        if relation == FOLLOWING:
            ok = (along > 0) & (along < config.follow_m) & (np.abs(lateral) < config.lane_half_m)
            ok &= dh < config.follow_deg
            ok &= (a.speed > 0.5) & (b.speed > 0.5)
        elif relation == BESIDE:
            ok = (np.abs(along) < config.beside_ahead_m) & (np.abs(lateral) < config.beside_m)
        else:
            raise ValueError(f"unknown relation {relation!r}")
    return both & np.nan_to_num(ok).astype(bool)


def _cutting_in(of: ObjectFrames, num_frames: int, config: SearchConfig) -> np.ndarray:
    """``[F]`` bool: ahead of the ego near its path with the sideways offset closing in (module docstring)."""
    gap = np.abs(of.lane_offset)
    closing = np.zeros(num_frames, dtype=bool)
    rows = np.flatnonzero(of.present)
    if len(rows) > 2:
        rate = np.gradient(gap[rows], rows) / of.frame_s  # m/s
        closing[rows] = rate < -config.cut_in_closing_mps
    with np.errstate(invalid="ignore"):
        near = (of.lane_along > 0) & (of.lane_along < config.cut_in_ahead_m) & (gap < config.cut_in_half_m)
    return near & closing


def _count_holds(ct: ClauseTruth, objects: Mapping[str, ObjectFrames], clause: AgentClause,
                 config: SearchConfig) -> np.ndarray:
    """``[F]`` bool: at least ``clause.count`` objects hold the clause (``together``: each near another)."""
    truth = ct.truth
    if clause.together and len(ct.object_ids) > 1:
        xy = np.stack([objects[o].xy for o in ct.object_ids])  # [O, F, 2]
        d = np.linalg.norm(xy[:, None] - xy[None], axis=-1)  # [O, O, F]
        near = np.nan_to_num(d < config.together_m) & truth[:, None] & truth[None]
        near[np.arange(len(truth)), np.arange(len(truth))] = False
        truth = truth & near.any(axis=1)
    return truth.sum(axis=0) >= clause.count


@dataclass(frozen=True)
class ClauseTruth:
    """A clause evaluated over a log: ``truth`` ``[O, F]`` per object, the objects' appearance fits ``[O]``, and per
    (object, frame) the related object (``""`` when none)."""

    object_ids: tuple[str, ...]
    truth: np.ndarray
    fit: np.ndarray
    partner: np.ndarray


def clause_truth(clause: AgentClause, objects: Mapping[str, ObjectFrames], num_frames: int,
                 nodes: Mapping[str, NodeLanguage] | None, config: SearchConfig) -> ClauseTruth:
    """Per-object, per-frame truth of one clause (module docstring)."""
    ids = tuple(objects)
    truth = np.zeros((len(ids), num_frames), dtype=bool)
    fit = np.zeros(len(ids))
    partner = np.full((len(ids), num_frames), "", dtype=object)
    if clause.unknown_places:
        return ClauseTruth(ids, truth, fit, partner)
    rel = clause_truth(clause.related, objects, num_frames, nodes, config) if clause.related is not None else None
    for i, oid in enumerate(ids):
        of = objects[oid]
        if (oid == EGO_ID) != clause.is_ego:
            continue
        fit[i] = appearance_fit(clause, of, (nodes or {}).get(oid), config)
        if fit[i] < config.min_appearance:
            continue
        ok = of.present & _motion_ok(clause, of)
        if clause.sectors:
            ok &= np.isin(of.sector, clause.sectors)
        for ctx in clause.contexts:
            ok &= of.context(ctx)
        if clause.in_ego_lane:
            with np.errstate(invalid="ignore"):
                ok &= (of.lane_along > 0) & (of.lane_along < config.ego_lane_ahead_m) \
                    & (np.abs(of.lane_offset) < config.ego_lane_half_m)
        if clause.cut_in:
            ok &= _cutting_in(of, num_frames, config)
        if rel is not None:
            with_partner = np.zeros(num_frames, dtype=bool)
            for j, other in enumerate(rel.object_ids):
                if other == oid or not rel.truth[j].any():
                    continue
                pair = ok & rel.truth[j] & _related(of, objects[other], clause.relation, config)
                partner[i][pair & ~with_partner] = other
                with_partner |= pair
            ok &= with_partner
        truth[i] = ok
    return ClauseTruth(ids, truth, fit, partner)


def _most_common(values: np.ndarray) -> str:
    vals = [v for v in values if v]
    return max(set(vals), key=vals.count) if vals else ""


def _score(fits: list[float], window: tuple[int, int], config: SearchConfig) -> float:
    frames = window[1] - window[0] + 1
    return float(np.mean(fits) * (0.5 + 0.5 * min(1.0, frames / config.full_window_frames)))


def _no_hit_message(seq_id: str, query: SearchQuery, truths: list[ClauseTruth]) -> str:
    for clause, ct in zip(query.clauses, truths):
        if clause.count > 1 and ct.truth.any():
            together = " together" if clause.together else ""
            return f"{seq_id}: never {clause.count} objects{together} match {clause.text!r} in the same frames"
        if clause.unknown_places:
            return f"{seq_id}: the map has no {' or '.join(clause.unknown_places)} ({clause.text!r} holds nowhere)"
        if not ct.truth.any():
            return f"{seq_id}: nothing matches {clause.describe()!r} in any frame"
    return f"{seq_id}: the parts of {query.text!r} each hold somewhere but never in the same frames for long enough"


def search_log(seq_id: str, objects: Mapping[str, ObjectFrames], num_frames: int, query: SearchQuery | str,
               nodes: Mapping[str, NodeLanguage] | None = None, config: SearchConfig | None = None) -> SearchResult:
    """Answer ``query`` over one log's per-frame object facts (``frames.log_frames``); ``nodes`` maps object ids to
    their language nodes (captions) when the log is aligned."""
    cfg = config or SearchConfig()
    q = parse_description(query) if isinstance(query, str) else query
    truths = [clause_truth(c, objects, num_frames, nodes, cfg) for c in q.clauses]
    holds = np.ones(num_frames, dtype=bool)
    for clause, ct in zip(q.clauses, truths):
        holds &= _count_holds(ct, objects, clause, cfg) if len(ct.object_ids) else np.zeros(num_frames, dtype=bool)
    hits: list[SearchHit] = []
    if len(truths) == 1 and q.clauses[0].count == 1:
        ct = truths[0]
        for i, oid in enumerate(ct.object_ids):
            for w in frame_windows(ct.truth[i], min_frames=cfg.min_frames, max_gap=cfg.max_gap):
                partner = _most_common(ct.partner[i][w[0]: w[1] + 1])
                ids_w = (oid, partner) if partner else (oid,)
                hits.append(SearchHit(seq_id, ids_w, w, _score([float(ct.fit[i])], w, cfg)))
    else:
        for w in frame_windows(holds, min_frames=cfg.min_frames, max_gap=cfg.max_gap):
            ids = []
            fits: list[float] = []
            for clause, ct in zip(q.clauses, truths):
                counts = ct.truth[:, w[0]: w[1] + 1].sum(axis=1)
                for best in np.argsort(-counts, kind="stable")[: clause.count]:
                    if counts[best] > 0 and ct.object_ids[best] not in ids:
                        ids.append(ct.object_ids[best])
                        fits.append(float(ct.fit[best]))
                        partner = _most_common(ct.partner[best][w[0]: w[1] + 1])
                        if partner and partner not in ids:
                            ids.append(partner)
            hits.append(SearchHit(seq_id, tuple(ids), w, _score(fits or [0.0], w, cfg)))
    hits.sort(key=lambda h: (-h.score, h.window[0], h.object_ids))
    message = "" if hits else _no_hit_message(seq_id, q, truths)
    logger.debug("%s: %r -> %d hits", seq_id, q.text, len(hits))
    return SearchResult(seq_id, q, tuple(hits), holds, message)
