"""The ``QueryEngine``'s answer in words: what was found, or which part of the query found nothing."""

from __future__ import annotations

import numpy as np

from simsplat_core.language.grounding.config import QueryConfig
from simsplat_core.language.grounding.parse import ParsedQuery
from simsplat_core.language.grounding.result import NodeMatch
from simsplat_core.language.scene_language import LanguageScene


def grounding_message(
    scene: LanguageScene,
    parsed: ParsedQuery,
    ranking: tuple[NodeMatch, ...],
    matches: tuple[NodeMatch, ...],
    config: QueryConfig,
) -> str:
    """The message of a ``Grounding``: the chosen node(s) ("veh_03 (node 4): a black sedan", flagged when a
    runner-up scores within ``config.ambiguity_margin``), or why nothing matches ("no pedestrian in this
    scene is crossing"; "nothing to compare" when the query has no part ``config`` scores)."""
    if not config.scored_parts(parsed):
        switches = (("appearance", config.use_appearance), ("motion", config.use_motion),
                    ("location", config.use_location))
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
        if runner and best.score - runner[0].score <= config.ambiguity_margin:
            text += f" (ambiguous: {runner[0].object_id} scores {runner[0].score:.3f} vs {best.score:.3f})"
        return text
    subject = (parsed.subject() if parsed.noun or parsed.named_colors or parsed.excluded_colors
               else (parsed.appearance or "object"))
    if not ranking:
        return f"no {subject} in this scene"
    candidates = [m for m in ranking if m.candidate]
    threshold = config.group_threshold if parsed.group else config.no_match_threshold

    def best_of(attr: str) -> float:
        values = [getattr(m, attr) for m in candidates if np.isfinite(getattr(m, attr))]
        return max(values) if values else float("nan")

    app_failed = np.isfinite(best_of("appearance")) and best_of("appearance") < threshold
    clauses = []
    mot_failed = config.use_motion and parsed.motion and best_of("motion") < threshold
    loc_failed = config.use_location and parsed.location and best_of("location") < threshold
    if mot_failed:
        clauses.append(_predicate(parsed.motion))
    if loc_failed:
        clauses.append(parsed.location)
    if not clauses and not app_failed:  # each part matches some node, but no node matches them all
        if config.use_motion and parsed.motion:
            clauses.append(_predicate(parsed.motion))
        if config.use_location and parsed.location:
            clauses.append(parsed.location)
    if not clauses:
        return f"no {subject} in this scene"
    verb = "is" if not clauses[0].startswith("that ") else ""
    return " ".join(w for w in ("no", subject, "in this scene", verb, " ".join(clauses)) if w)



def nearest_colour_message(scene: LanguageScene, parsed: ParsedQuery, match: NodeMatch) -> str:
    """The message of a grounding that took a node of a neighbouring colour (``QueryEngine._nearest_colour``)."""
    node = scene.node(match.node_id)
    caption = node.caption.text if node.caption else ""
    return (f"{match.object_id} (node {match.node_id}): {caption} (no {parsed.subject()} fits the rest; this one's "
            "colour is the nearest)")


def no_images_message(scene: LanguageScene, looks: str) -> str:
    """Why a query about looks (``looks``: "red, big") has no answer in a scene built without images."""
    return (f"{scene.seq_id} has no camera images: its objects' looks ({looks}) cannot be checked; "
            "ask by category, motion or location instead")


def _predicate(motion: str) -> str:
    """"crossing" -> "crossing"; "turns left" -> "that turns left" (a finite verb needs a relative pronoun)."""
    first = motion.split(" ", 1)[0]
    if first.endswith("ing") or first.endswith("ed") or first in ("in", "at", "from", "stationary", "not"):
        return motion
    return f"that {motion}"
