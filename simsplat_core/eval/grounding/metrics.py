"""Grounding metrics (SIMSplat Tables 2 and 3): accuracy and vIoU per category, and the benchmark runner.

Definitions (one query, one method):

* **Accuracy** compares *sets of objects*: the query is correct when the set of objects the method
  returns equals the query's target set. Single-target queries therefore need exactly the one target
  (returning it together with a look-alike is wrong); group queries ("all pedestrians crossing") need
  every target and nothing else; no-match queries (target set empty) are correct only when the method
  returns nothing. Objects are compared by ``object_id`` (node ids are mapped through the scene).
* **vIoU** follows 4D LangSplat: with ``M_t`` the ground-truth and ``M̂_t`` the predicted mask of frame
  ``t`` (all cameras' pixels of that frame together),

      vIoU = (1 / |S_U|) * sum_{t in S_I} IoU(M̂_t, M_t)

  where ``S_U`` are the frames in which the prediction or the ground truth is non-empty and ``S_I`` the
  frames in which both are. Frames where only one side is non-empty count in the denominator with IoU
  0, so masks predicted in frames where the target is absent (or missed frames) are penalised. When
  ``S_U`` is empty (a no-match query answered with nothing, or a target that is never visible answered
  with an empty mask) the prediction is perfect and vIoU is 1; a no-match query answered with any
  visible node gets 0 (``S_I`` is empty).
* **Per category**: each query has one category (``vehicle`` / ``pedestrian``: the kind of object it
  asks for, also for group and no-match queries); ``total`` averages over all queries.

``viou`` is the definition on explicit ``[F, C, H, W]`` masks; ``OverlapCounts`` computes the same
number for any pair of node / object sets from one joint histogram per scene (pixel counts per frame of
every (rendered node, ground-truth object) pair), which makes evaluating many methods on many queries
cheap. ``evaluate_grounding`` runs grounders on a ``GroundingBenchmark`` and ``summarise`` aggregates
the per-query ``QueryOutcome`` records.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np

from simsplat_core.eval.grounding.benchmark import GroundingBenchmark, GroundingQuery, SceneGroundTruth
from simsplat_core.language.scene_language import LanguageScene

logger = logging.getLogger(__name__)

#: Column groups of the tables, in order.
CATEGORIES: tuple[str, ...] = ("vehicle", "pedestrian", "total")


# ---------------------------------------------------------------------------------------------- metrics
def query_correct(predicted: Iterable[str], target: Iterable[str]) -> bool:
    """Whether the predicted object set equals the target set (module docstring; empty == empty)."""
    return set(predicted) == set(target)


def _per_frame(mask: np.ndarray) -> np.ndarray:
    """``[F, ...]`` bool -> ``[F, P]`` with every pixel of a frame (all cameras) on one row."""
    mask = np.asarray(mask, dtype=bool)
    if mask.ndim < 2:
        raise ValueError(f"masks must be [F, ...] with a frame axis first, got shape {mask.shape}")
    return mask.reshape(mask.shape[0], -1)


def frame_ious(predicted: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-frame ``(intersection [F], union [F], IoU [F])`` of two ``[F, C, H, W]`` (or ``[F, ...]``) bool masks.

    IoU is 0 where the union is empty.
    """
    if np.shape(predicted) != np.shape(target):
        raise ValueError(f"predicted masks {np.shape(predicted)} and target masks {np.shape(target)} differ in shape")
    p, g = _per_frame(predicted), _per_frame(target)
    inter = np.count_nonzero(p & g, axis=1)
    union = np.count_nonzero(p | g, axis=1)
    iou = np.where(union > 0, inter / np.maximum(union, 1), 0.0)
    return inter, union, iou


def viou_from_counts(intersection: np.ndarray, predicted_area: np.ndarray, target_area: np.ndarray) -> float:
    """vIoU from per-frame pixel counts ``[F]`` each (module docstring; 1.0 when ``S_U`` is empty)."""
    inter = np.asarray(intersection, dtype=np.float64)
    pa = np.asarray(predicted_area, dtype=np.float64)
    ta = np.asarray(target_area, dtype=np.float64)
    union = pa + ta - inter
    s_u = (pa > 0) | (ta > 0)
    if not s_u.any():
        return 1.0
    s_i = (pa > 0) & (ta > 0)
    return float(np.sum(inter[s_i] / union[s_i]) / np.count_nonzero(s_u))


def viou(predicted: np.ndarray, target: np.ndarray) -> float:
    """4D LangSplat's vIoU of ``[F, C, H, W]`` bool masks (cameras of a frame count as one mask)."""
    if np.shape(predicted) != np.shape(target):
        raise ValueError(f"predicted masks {np.shape(predicted)} and target masks {np.shape(target)} differ in shape")
    p, g = _per_frame(predicted), _per_frame(target)
    return viou_from_counts(np.count_nonzero(p & g, axis=1), np.count_nonzero(p, axis=1), np.count_nonzero(g, axis=1))


@dataclass(frozen=True, eq=False)
class OverlapCounts:
    """Joint pixel histogram of a scene's rendered node ids and its ground-truth objects.

    Attributes:
        node_ids: ``[P]`` rendered labels (index 0 is ``-1``, nothing rendered).
        object_ids: ``[G]`` ground-truth objects (index 0 is ``""``, background).
        counts: ``[F, P, G]`` int64 pixels of frame ``f`` (all cameras) rendered as ``node_ids[p]`` whose
            ground truth is ``object_ids[g]``.
    """

    node_ids: tuple[int, ...]
    object_ids: tuple[str, ...]
    counts: np.ndarray

    @classmethod
    def build(cls, node_id_maps: np.ndarray, truth: SceneGroundTruth) -> OverlapCounts:
        """From ``[F, C, H, W]`` int node-id maps and the ground truth over the same frames and cameras."""
        node_id_maps = np.asarray(node_id_maps)
        labels = truth.instance_maps
        if node_id_maps.shape != labels.shape:
            raise ValueError(
                f"{truth.seq_id}: node-id maps {node_id_maps.shape} and ground-truth maps {labels.shape} differ"
            )
        nodes = np.unique(np.concatenate([[-1], np.unique(node_id_maps)]))
        node_index = np.searchsorted(nodes, node_id_maps)  # [F, C, H, W]
        by_instance = {inst: oid for oid, inst in truth.instance_ids.items()}
        instances = np.unique(labels)
        objects = [""] + [by_instance[int(i)] for i in instances if int(i) in by_instance]
        inst_index = np.zeros(int(max(instances.max(initial=0), 0)) + 1, dtype=np.int64)
        for k, oid in enumerate(objects[1:], start=1):
            inst_index[truth.instance_ids[oid]] = k
        gt_index = inst_index[np.clip(labels, 0, None)]  # unknown instances count as background
        n_f, n_p, n_g = labels.shape[0], len(nodes), len(objects)
        flat = (np.arange(n_f)[:, None] * n_p * n_g + (node_index * n_g + gt_index).reshape(n_f, -1)).ravel()
        counts = np.bincount(flat, minlength=n_f * n_p * n_g).reshape(n_f, n_p, n_g)
        return cls(tuple(int(n) for n in nodes), tuple(objects), counts)

    def viou(self, predicted_nodes: Iterable[int], target_objects: Iterable[str]) -> float:
        """vIoU of the union of ``predicted_nodes``' rendered masks against the union of the targets' masks."""
        p = np.isin(np.asarray(self.node_ids), np.asarray(list(predicted_nodes), dtype=np.int64))
        p[0] = False
        targets = set(target_objects)
        g = np.array([oid in targets for oid in self.object_ids])
        inter = self.counts[:, p][:, :, g].sum(axis=(1, 2))
        pred_area = self.counts[:, p].sum(axis=(1, 2))
        target_area = self.counts[:, :, g].sum(axis=(1, 2))
        return viou_from_counts(inter, pred_area, target_area)


# ---------------------------------------------------------------------------------------------- runner
@runtime_checkable
class Grounder(Protocol):
    """Anything that maps a free-form description to scene-graph nodes (``QueryEngine`` via an adapter)."""

    def ground(self, scene: LanguageScene, text: str) -> tuple[int, ...]:
        """Node ids the description refers to (empty: nothing matches)."""
        ...


@dataclass(frozen=True)
class QueryOutcome:
    """One method's answer to one query.

    Attributes:
        method: the method's name.
        query: the query.
        predicted: object ids of the returned nodes (sorted).
        correct: ``query_correct(predicted, query.target_ids)``.
        viou: vIoU of the returned nodes' rendered masks against the targets' ground-truth masks.
        seconds: wall time of the ``ground`` call.
    """

    method: str
    query: GroundingQuery
    predicted: tuple[str, ...]
    correct: bool
    viou: float
    seconds: float


@dataclass(frozen=True)
class CategoryScore:
    """Accuracy and mean vIoU over ``queries`` queries (``nan`` when there are none)."""

    queries: int
    accuracy: float
    viou: float


def summarise(outcomes: Iterable[QueryOutcome]) -> dict[str, dict[str, CategoryScore]]:
    """``{method: {"vehicle" | "pedestrian" | "total": CategoryScore}}`` in first-seen method order."""
    return summarise_answers((o.method, o.query.category, o.correct, o.viou) for o in outcomes)


def summarise_answers(answers: Iterable[tuple[str, str, bool, float]]) -> dict[str, dict[str, CategoryScore]]:
    """:func:`summarise` of ``(method, query category, correct, vIoU)`` answers (e.g. rows of a stored outcomes
    table), in first-seen method order."""
    grouped: dict[str, dict[str, list[tuple[bool, float]]]] = {}
    for method, category, correct, viou_value in answers:
        per = grouped.setdefault(method, {c: [] for c in CATEGORIES})
        if category in per:
            per[category].append((correct, viou_value))
        per["total"].append((correct, viou_value))
    out: dict[str, dict[str, CategoryScore]] = {}
    for method, per in grouped.items():
        out[method] = {}
        for cat, rows in per.items():
            if rows:
                out[method][cat] = CategoryScore(
                    len(rows), float(np.mean([c for c, _ in rows])), float(np.mean([v for _, v in rows]))
                )
            else:
                out[method][cat] = CategoryScore(0, float("nan"), float("nan"))
    return out


def latency_of(seconds: Sequence[float]) -> dict[str, float]:
    """Median and 90th-percentile of per-query ``seconds`` (``nan`` when there are none)."""
    secs = np.asarray(seconds, np.float64)
    if secs.size == 0:
        return {"median_s": float("nan"), "p90_s": float("nan")}
    return {"median_s": float(np.median(secs)), "p90_s": float(np.percentile(secs, 90))}


@dataclass
class GroundingResults:
    """Every method's answers to every query, with summaries.

    Attributes:
        outcomes: one ``QueryOutcome`` per (method, query), methods in the order given.
    """

    outcomes: list[QueryOutcome] = field(default_factory=list)

    def summary(self) -> dict[str, dict[str, CategoryScore]]:
        return summarise(self.outcomes)

    def for_method(self, method: str) -> list[QueryOutcome]:
        return [o for o in self.outcomes if o.method == method]

    def breakdown(self, method: str, key: str) -> dict[str, CategoryScore]:
        """Scores of ``method`` grouped by a query field (``"kind"``, ``"style"``, ``"slots"``, ...)."""
        groups: dict[str, list[QueryOutcome]] = {}
        for o in self.for_method(method):
            value = getattr(o.query, key)
            name = "+".join(value) if isinstance(value, tuple) else str(value)
            groups.setdefault(name, []).append(o)
        return {
            k: CategoryScore(len(v), float(np.mean([o.correct for o in v])), float(np.mean([o.viou for o in v])))
            for k, v in sorted(groups.items())
        }

    def latency(self, method: str) -> dict[str, float]:
        """Median and 90th-percentile seconds per query of ``method``."""
        return latency_of([o.seconds for o in self.for_method(method)])


def evaluate_grounding(
    scenes: Sequence[LanguageScene],
    benchmark: GroundingBenchmark,
    methods: Mapping[str, Grounder],
) -> GroundingResults:
    """Run every method on every query of ``benchmark`` whose sequence is among ``scenes``.

    Predicted nodes are mapped to objects through the scene (``NodeLanguage.object_id``); masks are the
    scene's rendered node-id maps, compared with the benchmark's ground-truth maps on the scene's frames
    and cameras (``SceneGroundTruth.aligned_to``).

    Raises:
        ValueError: a scene has no node-id maps, or its frames / cameras / size do not match the ground truth.
        KeyError: a method returned a node id the scene does not have.
    """
    by_seq = {s.seq_id: s for s in scenes}
    missing = sorted({q.seq_id for q in benchmark.queries} - set(by_seq))
    if missing:
        logger.warning("no scene for %d sequences of the benchmark (%s); their queries are skipped",
                       len(missing), missing)
    results = GroundingResults()
    for seq_id, scene in by_seq.items():
        queries = [q for q in benchmark.queries if q.seq_id == seq_id]
        if not queries:
            continue
        if scene.node_id_maps is None:
            raise ValueError(f"{seq_id}: the scene has no rendered node-id maps to cut masks from")
        truth = benchmark.ground_truth[seq_id].aligned_to(scene.frame_indices, scene.cameras)
        overlap = OverlapCounts.build(scene.node_id_maps, truth)
        object_of = {n.node_id: n.object_id for n in scene.nodes}
        for name, method in methods.items():
            for q in queries:
                t0 = time.perf_counter()
                nodes = tuple(int(n) for n in method.ground(scene, q.text))
                seconds = time.perf_counter() - t0
                unknown = [n for n in nodes if n not in object_of]
                if unknown:
                    raise KeyError(f"{name}: {seq_id} has no object nodes {unknown} (query {q.text!r})")
                predicted = tuple(sorted({object_of[n] for n in nodes}))
                results.outcomes.append(
                    QueryOutcome(
                        name,
                        q,
                        predicted,
                        query_correct(predicted, q.target_ids),
                        overlap.viou(nodes, q.target_ids),
                        seconds,
                    )
                )
            logger.info("%s: %s answered %d queries", seq_id, name, len(queries))
    return results


__all__ = [
    "CATEGORIES",
    "CategoryScore",
    "Grounder",
    "GroundingResults",
    "OverlapCounts",
    "QueryOutcome",
    "evaluate_grounding",
    "frame_ious",
    "query_correct",
    "latency_of",
    "summarise",
    "summarise_answers",
    "viou",
    "viou_from_counts",
]
