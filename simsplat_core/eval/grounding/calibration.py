"""Threshold calibration of the ``QueryEngine`` on labelled queries (an evaluation step: the benchmark
calibrates on held-out scenes; the pipeline runs with the configured thresholds).

    config = calibrate_thresholds(engine, [(scene, "the red sedan turning left", frozenset({1})), ...])
    calibrated = engine.with_config(config)
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Sequence

import numpy as np

from simsplat_core.language.grounding.config import QueryConfig
from simsplat_core.language.grounding.engine import QueryEngine
from simsplat_core.language.grounding.parse import parse_query
from simsplat_core.language.scene_language import LanguageScene

logger = logging.getLogger(__name__)


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
        ranking = engine.rank(scene, parsed) if engine.config.scored_parts(parsed) else ()
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
