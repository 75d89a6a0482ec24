"""Evaluation of the motion/location labeller and of motion grounding.

* ``labeller_agreement``: the auto-labeller against the synthetic world's own annotations (its
  trajectory-derived captions ``caption_motion`` / ``caption_location``, and the behaviour the
  generator intended). Logs without those attributes are skipped.
* ``grounding_accuracy``: for every motion / location class present in a log, free-form queries
  (``PhraseClass.queries``, worded differently from the prototype phrases) are encoded with the text
  encoder and the object with the highest cosine to ``f_mot`` (motion queries) or ``f_loc``
  (location queries, "<subject> <predicate>", e.g. "the car ahead of me") is picked among the objects
  of the query's kind (vehicles or pedestrians: category grounding is the appearance features' job).
  Top-1 is correct when the picked object's auto-label has the queried class. A class is queried
  only when the log has both positives and negatives among the candidates. ``chance`` is the mean
  fraction of positives (the accuracy of a random pick); ``oracle`` scores the auto-label's own
  prototype instead of ``f_mot`` / ``f_loc`` (the ceiling that the text space allows).
"""

from __future__ import annotations

import collections
import dataclasses
import logging
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from simsplat_core.language.alignment.motion_training import MotionAligner
from simsplat_core.language.codebooks import cosine_scores
from simsplat_core.language.motion_labels import LabelThresholds, MotionLabel, label_log
from simsplat_core.language.scene_language import ObjectMotionFeatures
from simsplat_core.language.text import TextEncoder
from simsplat_core.scenario import vocabulary as voc
from simsplat_core.scenario.vocabulary import LOCATION_CONTEXT, LOCATION_SECTOR, MOTION_VOCABULARIES
from simsplat_core.types import SceneLog

logger = logging.getLogger(__name__)

#: The world's motion captions (``world/captions.py``) as labeller classes.
WORLD_MOTION: dict[str, str] = {
    "turning left": voc.TURNING_LEFT,
    "turning right": voc.TURNING_RIGHT,
    "veering left": voc.TURNING_LEFT,
    "veering right": voc.TURNING_RIGHT,
    "changing lanes to the left": voc.CHANGING_LANE_LEFT,
    "changing lanes to the right": voc.CHANGING_LANE_RIGHT,
    "coming to a stop": voc.STOPPING,
    "slowing down": voc.SLOWING_DOWN,
    "speeding up": voc.SPEEDING_UP,
    "going straight": voc.GOING_STRAIGHT,
    "parked": voc.PARKED,
    "stopped": voc.STOPPED,
    "standing": voc.STANDING,
    "crossing the street from left to right": voc.CROSSING_LEFT_TO_RIGHT,
    "crossing the street from right to left": voc.CROSSING_RIGHT_TO_LEFT,
    "crossing the street": voc.CROSSING,
    "walking along the sidewalk": voc.WALKING_ALONG,
    "walking": voc.WALKING_ALONG,
}
#: The generator's intended behaviours (``world/behaviors.py``) as sets of acceptable classes.
WORLD_BEHAVIOUR: dict[str, frozenset[str]] = {
    "straight": frozenset({voc.GOING_STRAIGHT}),
    "turn_left": frozenset({voc.TURNING_LEFT}),
    "turn_right": frozenset({voc.TURNING_RIGHT}),
    "lane_change_left": frozenset({voc.CHANGING_LANE_LEFT}),
    "lane_change_right": frozenset({voc.CHANGING_LANE_RIGHT}),
    "slow_down": frozenset({voc.SLOWING_DOWN}),
    "stop": frozenset({voc.STOPPING, voc.SLOWING_DOWN}),
    "stopped": frozenset({voc.STOPPED}),
    "parked": frozenset({voc.PARKED}),
    "crossing": frozenset({voc.CROSSING_LEFT_TO_RIGHT, voc.CROSSING_RIGHT_TO_LEFT, voc.CROSSING}),
    "walking": frozenset({voc.WALKING_ALONG}),
    "standing": frozenset({voc.STANDING}),
}
WORLD_SECTOR: dict[str, str] = {
    "in front of ego": voc.IN_FRONT_OF_EGO,
    "behind ego": voc.BEHIND_EGO,
    "on the left of ego": voc.LEFT_OF_EGO,
    "on the right of ego": voc.RIGHT_OF_EGO,
}
WORLD_CONTEXT: dict[str, str] = {
    "at the intersection": voc.AT_THE_INTERSECTION,
    "on the crosswalk": voc.ON_THE_CROSSWALK,
    "on the sidewalk": voc.ON_THE_SIDEWALK,
    "by the curb": voc.BY_THE_CURB,
    "in the oncoming lane": voc.IN_THE_ONCOMING_LANE,
    "on the road": voc.ON_THE_ROAD,
    "": voc.ON_THE_ROAD,
}
#: Query subjects per agent kind for location queries.
SUBJECTS: dict[str, tuple[str, ...]] = {
    "vehicle": ("the car", "the vehicle"),
    "pedestrian": ("the pedestrian", "the person"),
}


def parse_world_location(caption: str) -> tuple[str, str]:
    """``(sector, context)`` classes of a world location caption such as ``"in front of ego at the intersection"``."""
    for phrase, sector in WORLD_SECTOR.items():
        if caption.startswith(phrase):
            return sector, WORLD_CONTEXT[caption[len(phrase) :].strip()]
    raise ValueError(f"unrecognised location caption {caption!r}")


@dataclass
class AgreementReport:
    """Agreement of the labeller with the world's annotations, as fractions of ``objects``.

    Attributes:
        objects: movable objects compared.
        motion, sector, context: agreement with the trajectory-derived captions.
        behaviour: agreement with the intended behaviour (``WORLD_BEHAVIOUR``).
        disagreements: ``(seq_id, object_id, field, world, labeller)`` for every mismatch.
        confusion: ``{(field, world, labeller): count}`` of the mismatches.
    """

    objects: int = 0
    motion: float = 0.0
    sector: float = 0.0
    context: float = 0.0
    behaviour: float = 0.0
    disagreements: list[tuple[str, str, str, str, str]] = field(default_factory=list)

    @property
    def confusion(self) -> dict[tuple[str, str, str], int]:
        return dict(collections.Counter(d[2:] for d in self.disagreements))

    def summary(self) -> dict[str, float | int]:
        return {k: getattr(self, k) for k in ("objects", "motion", "sector", "context", "behaviour")}


def labeller_agreement(logs: Sequence[SceneLog], thresholds: LabelThresholds | None = None) -> AgreementReport:
    """Compare ``label_log`` with the world's ``caption_motion`` / ``caption_location`` / ``behavior`` attributes."""
    hits: collections.Counter[str] = collections.Counter()
    report = AgreementReport()
    for log in logs:
        labels = label_log(log, thresholds)
        for obj in log.objects:
            label = labels.get(obj.object_id)
            attrs = obj.attributes
            if label is None or "caption_motion" not in attrs:
                continue
            report.objects += 1
            sector, context = parse_world_location(attrs["caption_location"])
            checks = [
                ("motion", WORLD_MOTION[attrs["caption_motion"]], label.motion),
                ("sector", sector, label.sector),
                ("context", context, label.context),
            ]
            for name, world, mine in checks:
                hits[name] += world == mine
                if world != mine:
                    report.disagreements.append((log.seq_id, obj.object_id, name, world, mine))
            intended = WORLD_BEHAVIOUR.get(attrs.get("behavior", ""), frozenset())
            hits["behaviour"] += label.motion in intended
            if label.motion not in intended:
                report.disagreements.append(
                    (log.seq_id, obj.object_id, "behaviour", attrs.get("behavior", ""), label.motion)
                )
    if report.objects:
        for name in ("motion", "sector", "context", "behaviour"):
            setattr(report, name, hits[name] / report.objects)
    return report


@dataclass
class GroundingReport:
    """Top-1 grounding accuracy (fractions) over ``queries`` queries of each type.

    Attributes:
        motion, location: accuracy with the aligner's features.
        motion_oracle, location_oracle: accuracy with the auto-label prototypes (text-space ceiling).
        motion_chance, location_chance: expected accuracy of a random pick.
        motion_queries, location_queries: number of queries.
        per_class: ``{class: (queries, accuracy, oracle accuracy)}``.
    """

    motion: float = 0.0
    location: float = 0.0
    motion_oracle: float = 0.0
    location_oracle: float = 0.0
    motion_chance: float = 0.0
    location_chance: float = 0.0
    motion_queries: int = 0
    location_queries: int = 0
    per_class: dict[str, tuple[int, float, float]] = field(default_factory=dict)

    def summary(self) -> dict[str, float | int]:
        return {k: v for k, v in self.__dict__.items() if k != "per_class"}


@dataclass
class _Tally:
    correct: float = 0.0
    oracle: float = 0.0
    chance: float = 0.0
    count: int = 0
    per_class: collections.Counter = field(default_factory=collections.Counter)
    per_class_oracle: collections.Counter = field(default_factory=collections.Counter)
    per_class_n: collections.Counter = field(default_factory=collections.Counter)

    def add(self, cls: str, correct: bool, oracle: bool, chance: float) -> None:
        self.correct += correct
        self.oracle += oracle
        self.chance += chance
        self.count += 1
        self.per_class[cls] += correct
        self.per_class_oracle[cls] += oracle
        self.per_class_n[cls] += 1

    def rate(self, value: float) -> float:
        return value / self.count if self.count else float("nan")


def _query_plan(kind: str) -> list[tuple[str, str, str]]:
    """``(query type, class, query text)`` of every query for objects of ``kind``."""
    plan = [("motion", c.name, q) for c in MOTION_VOCABULARIES[kind].classes for q in c.queries]
    for vocab in (LOCATION_SECTOR, LOCATION_CONTEXT):
        plan += [("location", c.name, f"{s} {q}") for c in vocab.classes for s in SUBJECTS[kind] for q in c.queries]
    return plan


def _has_class(label: MotionLabel, query_type: str, cls: str) -> bool:
    return label.motion == cls if query_type == "motion" else cls in label.location


def _top1_is_positive(features: np.ndarray, query: np.ndarray, positive: np.ndarray) -> bool:
    """Whether the row of ``[N, D]`` ``features`` closest (cosine) to ``query`` ``[D]`` is ``positive`` ``[N]``."""
    return bool(positive[int(np.argmax(cosine_scores(features, query)))])


def grounding_accuracy(aligner: MotionAligner, logs: Sequence[SceneLog], encoder: TextEncoder) -> GroundingReport:
    """Top-1 accuracy of picking an object of the queried class (module docstring) over ``logs``."""
    if encoder.name != aligner.codebooks.encoder_name:
        raise ValueError(f"queries from {encoder.name!r} cannot be compared with "
                         f"{aligner.codebooks.encoder_name!r} features")
    tallies = {"motion": _Tally(), "location": _Tally()}
    books = aligner.codebooks
    location_protos = dict(zip(books.location_classes, books.location_prototypes))
    for log in logs:
        feats = aligner.features(log)
        for kind in MOTION_VOCABULARIES:
            cands: list[ObjectMotionFeatures] = [f for f in feats.values() if f.kind == kind]
            if len(cands) < 2:
                continue
            motion_protos = dict(zip(books.motion(kind).classes, books.motion(kind).prototypes))
            oracle = {
                "motion": np.stack([motion_protos[f.labels.motion] for f in cands]),
                "location": np.stack([0.5 * (location_protos[f.labels.sector] + location_protos[f.labels.context])
                                      for f in cands]),
            }
            learned = {"motion": np.stack([f.f_mot for f in cands]), "location": np.stack([f.f_loc for f in cands])}
            plan = _query_plan(kind)
            queries = encoder.encode_queries([p[2] for p in plan])
            for (qtype, cls, _), query in zip(plan, queries):
                positive = np.array([_has_class(f.labels, qtype, cls) for f in cands])
                if positive.all() or not positive.any():
                    continue
                tallies[qtype].add(
                    cls,
                    _top1_is_positive(learned[qtype], query, positive),
                    _top1_is_positive(oracle[qtype], query, positive),
                    float(positive.mean()),
                )
    report = GroundingReport()
    for qtype, tally in tallies.items():
        setattr(report, qtype, tally.rate(tally.correct))
        setattr(report, f"{qtype}_oracle", tally.rate(tally.oracle))
        setattr(report, f"{qtype}_chance", tally.rate(tally.chance))
        setattr(report, f"{qtype}_queries", tally.count)
        for cls, n in tally.per_class_n.items():
            report.per_class[cls] = (n, tally.per_class[cls] / n, tally.per_class_oracle[cls] / n)
    return report


def split_objects(log: SceneLog, seed: int = 0) -> tuple[SceneLog, SceneLog]:
    """Two logs with the same frames, ego and map and a random half of the objects each (images dropped).

    Used to train on one half of a single real log and evaluate grounding on the other half.
    """
    ids = [obj.object_id for obj in log.objects]
    order = np.random.default_rng(seed).permutation(len(ids))
    halves = ({ids[i] for i in order[::2]}, {ids[i] for i in order[1::2]})
    return tuple(  # type: ignore[return-value]
        dataclasses.replace(
            log,
            seq_id=f"{log.seq_id}-half{k}",
            images=(),
            tracks=tuple(t for t in log.tracks if t.object_id in half),
            objects=tuple(o for o in log.objects if o.object_id in half),
        )
        for k, half in enumerate(halves)
    )
