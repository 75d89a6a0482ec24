"""What a query returns: ``NodeMatch`` (one scored node) and ``Grounding`` (the answer to one query)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simsplat_core.language.grounding.parse import ParsedQuery
from simsplat_core.language.scene_language import LanguageScene


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
