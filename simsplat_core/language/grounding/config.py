"""``QueryConfig``: the switches, weights and thresholds of the ``QueryEngine`` (``engine`` module docstring)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from simsplat_core.language.grounding.parse import ParsedQuery


@dataclass(frozen=True)
class QueryConfig:
    """Switches, weights and thresholds of the ``QueryEngine`` (``engine`` module docstring).

    Attributes:
        use_appearance, use_motion, use_location: which signals are used at all (ablations).
        appearance_weight, motion_weight, location_weight: exponents of the signals in the score's product.
        appearance_temperature: raw cosine gap to the best node that divides the appearance score by e.
        candidate_ratio: narrowing rule: candidates keep ``p_app >= candidate_ratio * max p_app``.
        candidate_top_k: at most this many candidates (``0``: no cap).
        caption_confirmed_floor: the feature-field factor of a node whose caption names every colour
            the query names (and fits its subtype) is at least this: the field's rendered mean mixes
            views and can sit 0.05 cosine below the best node's, which alone must not drop a node the
            caption confirms ("the silver car turning left" whose caption is "a silver hatchback").
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
    caption_confirmed_floor: float = 0.5
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

    def validate(self) -> QueryConfig:
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
            "caption_confirmed_floor",
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

    def scored_parts(self, parsed: ParsedQuery) -> list[str]:
        """The parts of ``parsed`` this config scores: ``"appearance"``, ``"motion"``, ``"location"`` in order
        (empty: nothing to compare, the query matches nothing)."""
        parts = []
        if self.use_appearance and parsed.has_appearance:
            parts.append("appearance")
        if self.use_motion and parsed.motion:
            parts.append("motion")
        if self.use_location and parsed.location:
            parts.append("location")
        return parts
