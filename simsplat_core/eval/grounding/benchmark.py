"""Grounding benchmark generation (SIMSplat Tables 2 and 3) from synthetic logs with ground truth.

    bench = build_benchmark(logs, BenchmarkConfig(seed=0))
    bench.queries[0]          # GroundingQuery(seq_id, text, style, target_ids, kind, category, ...)
    bench.ground_truth[seq]   # SceneGroundTruth: instance maps [F, C, H, W], object_id -> instance id

Facts per object (``ObjectFacts``) come from the log's ground truth: body style and colour of vehicles
and clothing colours of pedestrians from ``ObjectInfo.attributes`` (the world's generator), motion and
location classes from the trajectory auto-labeller (``motion_labels.label_log``, which agrees with the
world's own trajectory-derived captions), visibility from the ground-truth instance masks.

Queries, per log:

* **single**: for every *well visible* vehicle and pedestrian (at least ``min_visible_frames`` frames
  with ``min_frame_pixels`` pixels over all cameras), ``paraphrases_per_target`` descriptions, each a
  different combination of constraints (``Description``: noun, colour, clothing, motion, location) in a
  different style (``paraphrases.SINGLE_STYLES``). A description is used only when it is *unique*: no
  other object of the log (visible or not, any category) satisfies all its constraints under any
  plausible reading. Matching is conservative: a generic noun ("car", "vehicle") fits every vehicle,
  "crossing the street" both directions; beyond its auto-labels an object also fits the motions its
  label implies ("coming to a stop" is also "slowing down" and "going straight") and every sector and
  map context it occupies near the reference frame (``plausible_readings``: 10 degrees of slack at
  sector boundaries, +-1 s around the reference frame, all map predicates rather than the labeller's
  first), so no query hinges on the labeller's tie-breaking. Combinations are drawn from families
  (appearance only, appearance + motion, appearance + location, appearance + motion + location, motion
  and/or location with a bare noun) with ``BenchmarkConfig.family_weights``, without repeating a family
  while others remain. A target that no
  combination singles out (identical look-alikes doing the same thing in the same place) gets one
  group query over every object matching its full description.
* **group**: ``group_per_log`` descriptions with one or two constraints ("all parked cars", "every
  pedestrian crossing the street", "the white vans") that match between 2 and ``group_max`` objects,
  all of them well visible (a description that also fits a barely visible object, or that another
  reading would extend to more objects, is skipped: whether that object belongs to the answer would be
  a coin toss).
* **none**: ``none_per_log`` descriptions that fit no object under any plausible reading: a
  well-visible object's description with one constraint changed (colour, body style, clothing, motion
  or location) -- near misses that a method choosing the best appearance match without checking the
  rest gets wrong.

Ground truth of a query is its target object set and, per frame, the targets' pixels in the instance
masks (``SceneGroundTruth.masks``); scenes map the objects to their node ids (``object_id``).
Generation is deterministic for a given ``(config.seed, seq_id)``.
"""

from __future__ import annotations

import dataclasses
import itertools
import logging
import zlib
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

from simsplat_core.eval.grounding.paraphrases import (
    BROADER_TERMS,
    DESCRIBABLE_CONTEXTS,
    EXACT_TERM,
    GROUP_STYLES,
    MOTION_TERMS,
    SINGLE_STYLES,
    Wording,
    realise,
    realise_group,
)
from simsplat_core.geometry import wrap_angle
from simsplat_core.language.motion_labels import (
    LabelThresholds,
    MotionLabel,
    label_trajectories,
    location_context,
    vehicle_off_lane,
)
from simsplat_core.scenario import vocabulary as voc
from simsplat_core.scenario.map_context import MapContext
from simsplat_core.scenario.trajectory import ObjectTrajectory, ego_yaw, log_trajectories, to_ego_frame
from simsplat_core.scenario.vocabulary import LOCATION_SECTOR, MOTION_VOCABULARIES
from simsplat_core.types import SceneLog

logger = logging.getLogger(__name__)

QUERY_KINDS: tuple[str, ...] = ("single", "group", "none")
#: Categories a query can ask for.
QUERY_CATEGORIES: tuple[str, ...] = ("vehicle", "pedestrian")
#: Families of constraint combinations for single-target descriptions.
FAMILIES: tuple[str, ...] = ("app", "app+mot", "app+loc", "app+mot+loc", "mot", "loc", "mot+loc")


# ---------------------------------------------------------------------------------------------- facts
@dataclass(frozen=True)
class ObjectFacts:
    """Ground-truth attributes of one object.

    Attributes:
        object_id, category, instance_id: from ``ObjectInfo``.
        subtype: body style (vehicles) or catalogue name.
        color: vehicle / static colour; upper / lower: pedestrian clothing colours (else ``None``).
        motion, sector, context: auto-label classes (``None`` for static objects).
        visible_frames: frames with at least ``min_frame_pixels`` pixels (all cameras together).
        pixels: total ground-truth pixels over the log.
        max_frame_pixels: the most pixels in one frame (all cameras together).
        motions, sectors, contexts: every class a listener could also read into the object
            (``plausible_readings``; the auto-labels included). Uniqueness, group membership and
            no-match checks use these, so a description never counts as unique, complete or empty
            when another reading of the scene contradicts it.
    """

    object_id: str
    category: str
    instance_id: int
    subtype: str | None
    color: str | None
    upper: str | None
    lower: str | None
    motion: str | None
    sector: str | None
    context: str | None
    visible_frames: int = 0
    pixels: int = 0
    max_frame_pixels: int = 0
    motions: frozenset[str] = frozenset()
    sectors: frozenset[str] = frozenset()
    contexts: frozenset[str] = frozenset()


#: Auto-label classes whose trajectories also fit other classes' words ("a car coming to a stop" is
#: also "slowing down" and "going straight"); the labeller's priority order keeps only the first.
IMPLIED_MOTIONS: dict[str, frozenset[str]] = {
    voc.STOPPING: frozenset({voc.SLOWING_DOWN, voc.GOING_STRAIGHT}),
    voc.SLOWING_DOWN: frozenset({voc.GOING_STRAIGHT}),
    voc.SPEEDING_UP: frozenset({voc.GOING_STRAIGHT}),
}
#: Location readings: sectors within this many degrees of the object's bearing, and every sector and
#: map context the object is in within this many seconds of the reference frame, count as plausible.
SECTOR_MARGIN_DEG = 10.0
LOCATION_WINDOW_S = 1.0


def _sectors_of(angle_deg: float, th: LabelThresholds, margin: float) -> set[str]:
    a = float(angle_deg)
    out = set()
    if abs(a) <= th.front_deg + margin:
        out.add(voc.IN_FRONT_OF_EGO)
    if abs(a) >= th.behind_deg - margin:
        out.add(voc.BEHIND_EGO)
    if th.front_deg - margin < a < th.behind_deg + margin:
        out.add(voc.LEFT_OF_EGO)
    if -th.behind_deg - margin < a < -th.front_deg + margin:
        out.add(voc.RIGHT_OF_EGO)
    return out


def plausible_readings(
    traj: ObjectTrajectory, label: MotionLabel, ego_poses: np.ndarray, map_context: MapContext | None,
    th: LabelThresholds | None = None,
) -> tuple[frozenset[str], frozenset[str], frozenset[str]]:
    """``(motions, sectors, contexts)`` a listener could read into one object.

    Motion: the label and ``IMPLIED_MOTIONS``. Location: over the visible rows within
    ``LOCATION_WINDOW_S`` of the reference row, every sector within ``SECTOR_MARGIN_DEG`` of the
    object's bearing and every map context whose predicate holds (``motion_labels`` takes the first
    one in priority order; here a pedestrian on a crosswalk inside the junction is also "at the
    intersection", an oncoming car inside the junction also "in the oncoming lane").
    """
    th = th or LabelThresholds()
    motions = {label.motion, *IMPLIED_MOTIONS.get(label.motion, ())}
    ref = traj.reference_row()
    near = np.abs(traj.t - traj.t[ref]) <= LOCATION_WINDOW_S + 1e-9
    rows = np.flatnonzero(near & traj.visible) if (near & traj.visible).any() else np.array([ref])
    sectors, contexts = {label.sector}, {label.context}
    for row in rows:
        pose = ego_poses[int(traj.frame_idx[row])]
        xy = to_ego_frame(traj.xy[row : row + 1], pose)[0]
        sectors |= _sectors_of(np.rad2deg(np.arctan2(xy[1], xy[0])), th, SECTOR_MARGIN_DEG)
        contexts.add(location_context(traj, int(row), pose, map_context, th))
        if traj.facts is None or map_context is None:
            continue
        facts = traj.facts.take(slice(int(row), int(row) + 1))
        if facts.at_intersection[0]:
            contexts.add(voc.AT_THE_INTERSECTION)
        if facts.on_sidewalk[0]:
            contexts.add(voc.ON_THE_SIDEWALK)
        if traj.kind == "pedestrian" and facts.in_crosswalk[0]:
            contexts.add(voc.ON_THE_CROSSWALK)
        if traj.kind == "vehicle":
            if vehicle_off_lane(facts, map_context, th)[0]:
                contexts.add(voc.BY_THE_CURB)
            if abs(float(np.rad2deg(wrap_angle(traj.heading[row] - ego_yaw(pose))))) >= th.oncoming_deg:
                contexts.add(voc.IN_THE_ONCOMING_LANE)
    return frozenset(motions), frozenset(sectors), frozenset(contexts)


def object_facts(log: SceneLog, labels: dict[str, MotionLabel] | None = None,
                 min_frame_pixels: int = 30) -> dict[str, ObjectFacts]:
    """``object_id -> ObjectFacts`` of every object of a log with ground-truth instance masks."""
    map_context = MapContext.from_features(log.map_features) if log.map_features else None
    trajectories = log_trajectories(log, map_context, min_frames=1)
    labels = label_trajectories(trajectories, log.ego_poses, map_context) if labels is None else labels
    n_inst = max((o.instance_id for o in log.objects), default=0) + 1
    per_frame = np.zeros((log.num_frames, n_inst), dtype=np.int64)
    for img in log.images:
        if img.instance is not None:
            per_frame[img.frame_idx] += np.bincount(img.instance.ravel().clip(0, n_inst - 1), minlength=n_inst)[:n_inst]
    out = {}
    for obj in log.objects:
        a = obj.attributes
        lab = labels.get(obj.object_id)
        counts = per_frame[:, obj.instance_id]
        traj = trajectories.get(obj.object_id)
        readings = (
            plausible_readings(traj, lab, log.ego_poses, map_context)
            if lab is not None and traj is not None
            else (frozenset(), frozenset(), frozenset())
        )
        out[obj.object_id] = ObjectFacts(
            object_id=obj.object_id,
            category=obj.category,
            instance_id=obj.instance_id,
            subtype=a.get("subtype"),
            color=a.get("color"),
            upper=a.get("upper_color"),
            lower=a.get("lower_color"),
            motion=lab.motion if lab else None,
            sector=lab.sector if lab else None,
            context=lab.context if lab else None,
            visible_frames=int(np.count_nonzero(counts >= min_frame_pixels)),
            pixels=int(counts.sum()),
            max_frame_pixels=int(counts.max(initial=0)),
            motions=readings[0],
            sectors=readings[1],
            contexts=readings[2],
        )
    return out


# ---------------------------------------------------------------------------------------------- descriptions
@dataclass(frozen=True)
class Description:
    """Constraints a description puts on an object (``None`` = not mentioned).

    Attributes:
        category: ``"vehicle"`` / ``"pedestrian"`` (always mentioned, by the noun).
        subtype: vehicle body style; ``None`` is a generic noun that fits every vehicle.
        color: vehicle colour; upper / lower: clothing colours.
        motion: ``paraphrases.MOTION_TERMS`` key (a set of auto-label classes).
        sector, context: location classes at the reference frame.
    """

    category: str
    subtype: str | None = None
    color: str | None = None
    upper: str | None = None
    lower: str | None = None
    motion: str | None = None
    sector: str | None = None
    context: str | None = None

    def matches(self, f: ObjectFacts, lenient: bool = False) -> bool:
        """Whether ``f`` satisfies every constraint: by its auto-labels, or (``lenient``) by any of its
        plausible readings (``ObjectFacts.motions`` / ``sectors`` / ``contexts``)."""
        if f.category != self.category:
            return False
        for name in ("subtype", "color", "upper", "lower"):
            want = getattr(self, name)
            if want is not None and getattr(f, name) != want:
                return False
        if lenient:
            if self.motion is not None and not (MOTION_TERMS[self.motion][1] & (f.motions or {f.motion})):
                return False
            if self.sector is not None and self.sector not in (f.sectors or {f.sector}):
                return False
            if self.context is not None and self.context not in (f.contexts or {f.context}):
                return False
            return True
        if self.motion is not None and f.motion not in MOTION_TERMS[self.motion][1]:
            return False
        return (self.sector is None or f.sector == self.sector) and (self.context is None or f.context == self.context)

    @property
    def slots(self) -> tuple[str, ...]:
        """Mentioned constraints, in a fixed order (``"noun"`` only for a specific vehicle body style)."""
        names = (("subtype", "noun"), ("color", "color"), ("upper", "upper"), ("lower", "lower"),
                 ("motion", "motion"), ("sector", "sector"), ("context", "context"))
        return tuple(label for attr, label in names if getattr(self, attr) is not None)

    @property
    def family(self) -> str:
        """``FAMILIES`` entry: which of appearance / motion / location the description uses."""
        parts = []
        if self.subtype or self.color or self.upper or self.lower:
            parts.append("app")
        if self.motion:
            parts.append("mot")
        if self.sector or self.context:
            parts.append("loc")
        return "+".join(parts) if parts else "category"

    def wording(self, matched: Sequence[ObjectFacts] = ()) -> Wording:
        """What the paraphraser needs: these constraints and the body styles of the objects a generic noun
        has to fit."""
        generic_subtypes = tuple(sorted({f.subtype for f in matched if f.subtype}))
        return Wording(**dataclasses.asdict(self), generic_subtypes=generic_subtypes)


def matching(desc: Description, facts: Iterable[ObjectFacts], lenient: bool = False) -> list[ObjectFacts]:
    return [f for f in facts if desc.matches(f, lenient)]


def unambiguous_targets(desc: Description, facts: Sequence[ObjectFacts]) -> list[ObjectFacts] | None:
    """The objects ``desc`` refers to by their auto-labels, or ``None`` when another reading of the
    scene would add an object (the answer would depend on how the listener reads it)."""
    strict = matching(desc, facts)
    if [f.object_id for f in matching(desc, facts, lenient=True)] != [f.object_id for f in strict]:
        return None
    return strict


def _motion_terms(f: ObjectFacts) -> list[str]:
    if f.motion is None:
        return []
    return [EXACT_TERM[f.motion], *BROADER_TERMS.get(f.motion, ())]


def _location_options(f: ObjectFacts) -> list[tuple[str | None, str | None]]:
    ctx = f.context if f.context in DESCRIBABLE_CONTEXTS else None
    opts: list[tuple[str | None, str | None]] = [(None, None), (f.sector, None)]
    if ctx is not None:
        opts += [(None, ctx), (f.sector, ctx)]
    return opts


def candidate_descriptions(f: ObjectFacts) -> list[Description]:
    """Every combination of ``f``'s own attributes a description may mention (category always)."""
    if f.category == "vehicle":
        appearance = [
            {"subtype": s, "color": c} for s, c in itertools.product((f.subtype, None), (f.color, None))
        ]
    elif f.category == "pedestrian":
        appearance = [{}, {"upper": f.upper}, {"upper": f.upper, "lower": f.lower}]
    else:
        return []
    out = []
    for app, mot, (sector, ctx) in itertools.product(appearance, [None, *_motion_terms(f)], _location_options(f)):
        out.append(Description(f.category, motion=mot, sector=sector, context=ctx, **app))
    return out


# ---------------------------------------------------------------------------------------------- ground truth
@dataclass(frozen=True, eq=False)
class SceneGroundTruth:
    """Ground-truth instance maps of one log.

    Attributes:
        seq_id: the sequence.
        frame_indices: ``[F]`` int64 frames.
        cameras: the ``C`` camera names.
        instance_maps: ``[F, C, H, W]`` int32 ``ObjectInfo.instance_id`` per pixel (0 = background).
        instance_ids: ``object_id -> instance id``.
    """

    seq_id: str
    frame_indices: np.ndarray
    cameras: tuple[str, ...]
    instance_maps: np.ndarray
    instance_ids: dict[str, int]

    @classmethod
    def from_log(cls, log: SceneLog) -> SceneGroundTruth:
        """From a log whose images carry instance masks (all frames, the log's camera order).

        Raises:
            ValueError: an image has no instance mask.
        """
        cams = log.cameras
        frames = np.arange(log.num_frames, dtype=np.int64)
        first = log.images[0] if log.images else None
        if first is None:
            raise ValueError(f"{log.seq_id}: the log has no images")
        maps = np.zeros((len(frames), len(cams), first.height, first.width), dtype=np.int32)
        cam_index = {c: i for i, c in enumerate(cams)}
        for img in log.images:
            if img.instance is None:
                raise ValueError(f"{log.seq_id}: image {img.camera}@{img.frame_idx} has no instance mask")
            maps[img.frame_idx, cam_index[img.camera]] = img.instance
        return cls(log.seq_id, frames, tuple(cams), maps, {o.object_id: o.instance_id for o in log.objects})

    def aligned_to(self, frame_indices: np.ndarray, cameras: Sequence[str]) -> SceneGroundTruth:
        """The ground truth on a scene's frames and cameras (in that order).

        Raises:
            ValueError: a frame or camera is not in the ground truth.
        """
        frame_indices = np.asarray(frame_indices, dtype=np.int64)
        row = {int(f): i for i, f in enumerate(self.frame_indices)}
        missing = [int(f) for f in frame_indices if int(f) not in row]
        if missing:
            raise ValueError(f"{self.seq_id}: no ground truth for frames {missing[:5]}")
        cams = [c for c in cameras if c not in self.cameras]
        if cams:
            raise ValueError(f"{self.seq_id}: no ground truth for cameras {cams}")
        rows = [row[int(f)] for f in frame_indices]
        cols = [self.cameras.index(c) for c in cameras]
        if rows == list(range(len(self.frame_indices))) and cols == list(range(len(self.cameras))):
            return self
        maps = self.instance_maps[np.ix_(rows, cols)]
        return dataclasses.replace(self, frame_indices=frame_indices, cameras=tuple(cameras), instance_maps=maps)

    def masks(self, object_ids: Iterable[str]) -> np.ndarray:
        """``[F, C, H, W]`` bool pixels of any of ``object_ids`` (unknown ids raise ``KeyError``)."""
        inst = [self.instance_ids[o] for o in object_ids]
        return np.isin(self.instance_maps, np.asarray(inst, dtype=np.int32))


# ---------------------------------------------------------------------------------------------- queries
@dataclass(frozen=True)
class GroundingQuery:
    """One benchmark query.

    Attributes:
        seq_id: the sequence.
        text: the free-form description.
        style: ``paraphrases.SINGLE_STYLES`` / ``GROUP_STYLES`` entry.
        target_ids: sorted object ids it refers to (empty for ``kind == "none"``).
        kind: ``"single"``, ``"group"`` or ``"none"``.
        category: ``"vehicle"`` or ``"pedestrian"`` (what it asks for).
        slots: constraints it mentions (``Description.slots``).
        family: ``Description.family``.
        query_id: ``"<seq_id>/<n>"``, unique within a benchmark.
        source_id: the object it was written for (single and none queries), else ``""``.
        perturbed: for ``none`` queries, the constraint that was changed.
        description: the constraints the text puts into words.
    """

    seq_id: str
    text: str
    style: str
    target_ids: tuple[str, ...]
    kind: str
    category: str
    slots: tuple[str, ...]
    family: str
    query_id: str = ""
    source_id: str = ""
    perturbed: str = ""
    description: Description | None = None


@dataclass(frozen=True)
class BenchmarkConfig:
    """Sizes and knobs of the generated benchmark (module docstring).

    Attributes:
        paraphrases_per_target: single-target descriptions per well-visible object.
        group_per_log, group_max: group queries per log and the largest group.
        none_per_log: no-match queries per log.
        min_visible_frames, min_frame_pixels: what "well visible" means.
        family_weights: sampling weights of the single-target families (``FAMILIES`` order).
        seed: combined with the sequence id into each log's generator.
    """

    paraphrases_per_target: int = 3
    group_per_log: int = 3
    group_max: int = 6
    none_per_log: int = 2
    min_visible_frames: int = 3
    min_frame_pixels: int = 30
    family_weights: tuple[float, ...] = (1.0, 1.0, 1.0, 1.0, 0.5, 0.3, 0.5)
    seed: int = 0

    def __post_init__(self) -> None:
        if len(self.family_weights) != len(FAMILIES):
            raise ValueError(f"family_weights needs {len(FAMILIES)} values ({FAMILIES}), got {self.family_weights}")
        for name in ("paraphrases_per_target", "group_per_log", "none_per_log", "min_visible_frames"):
            if getattr(self, name) < 0:
                raise ValueError(f"BenchmarkConfig.{name} must be >= 0, got {getattr(self, name)}")
        if self.group_max < 2:
            raise ValueError(f"BenchmarkConfig.group_max must be >= 2, got {self.group_max}")


@dataclass(frozen=True, eq=False)
class GroundingBenchmark:
    """Queries over several logs and each log's ground-truth maps."""

    queries: tuple[GroundingQuery, ...]
    ground_truth: dict[str, SceneGroundTruth] = field(default_factory=dict)
    config: BenchmarkConfig = field(default_factory=BenchmarkConfig)

    def counts(self) -> dict[str, int]:
        """Queries by kind and by category."""
        return query_counts((q.kind, q.category) for q in self.queries)


def query_counts(queries: Iterable[tuple[str, str]]) -> dict[str, int]:
    """Queries by kind and by category, and their total, from ``(kind, category)`` pairs."""
    out = {k: 0 for k in (*QUERY_KINDS, *QUERY_CATEGORIES)}
    total = 0
    for kind, category in queries:
        out[kind] += 1
        out[category] += 1
        total += 1
    out["total"] = total
    return out


def _rng(config: BenchmarkConfig, seq_id: str) -> np.random.Generator:
    return np.random.default_rng([config.seed, zlib.crc32(seq_id.encode())])


def _well_visible(f: ObjectFacts, config: BenchmarkConfig) -> bool:
    return f.visible_frames >= config.min_visible_frames


def _pick_weighted(rng: np.random.Generator, items: list, weights: list[float]):
    w = np.asarray(weights, dtype=np.float64)
    return items[int(rng.choice(len(items), p=w / w.sum()))]


def _single_queries(
    target: ObjectFacts, facts: list[ObjectFacts], config: BenchmarkConfig, rng: np.random.Generator
) -> list[tuple[Description, str, str, tuple[str, ...]]]:
    """``(description, kind, style, targets)`` of one target's queries."""
    unique: dict[str, list[Description]] = {}
    for desc in candidate_descriptions(target):
        targets = unambiguous_targets(desc, facts)
        if desc.family in FAMILIES and targets is not None and [m.object_id for m in targets] == [target.object_id]:
            unique.setdefault(desc.family, []).append(desc)
    if not unique:
        full = max(candidate_descriptions(target), key=lambda d: len(d.slots))
        group = unambiguous_targets(full, facts)
        if group is not None and len(group) >= 2 and all(_well_visible(f, config) for f in group):
            return [(full, "group", str(rng.choice(GROUP_STYLES)), tuple(sorted(f.object_id for f in group)))]
        return []
    weights = dict(zip(FAMILIES, config.family_weights))
    styles = list(rng.permutation(SINGLE_STYLES))
    out: list[tuple[Description, str, str, tuple[str, ...]]] = []
    remaining: list[str] = []
    for k in range(config.paraphrases_per_target):
        if not remaining:  # every family used once: start another round (distinct descriptions still)
            remaining = [fam for fam in FAMILIES if unique.get(fam) and weights[fam] > 0]
            if not remaining:
                break
        fam = _pick_weighted(rng, remaining, [weights[f] for f in remaining])
        remaining.remove(fam)
        desc = unique[fam].pop(int(rng.integers(len(unique[fam]))))
        out.append((desc, "single", styles[k % len(styles)], (target.object_id,)))
    return out


def group_candidates(facts: list[ObjectFacts], config: BenchmarkConfig) -> list[tuple[Description, list[ObjectFacts]]]:
    """Descriptions with one or two constraints fitting 2..group_max objects, all well visible."""
    seen: set[Description] = set()
    out = []
    for f in facts:
        if f.category not in QUERY_CATEGORIES or not _well_visible(f, config):
            continue
        options: list[Description] = []
        for term in _motion_terms(f):
            options.append(Description(f.category, motion=term))
        if f.context in DESCRIBABLE_CONTEXTS:
            options.append(Description(f.category, context=f.context))
        if f.category == "vehicle":
            options += [Description(f.category, color=f.color), Description(f.category, subtype=f.subtype),
                        Description(f.category, subtype=f.subtype, color=f.color)]
            if f.motion is not None:
                options.append(Description(f.category, color=f.color, motion=EXACT_TERM[f.motion]))
        else:
            options.append(Description(f.category, upper=f.upper))
            if f.motion is not None:
                options.append(Description(f.category, motion=EXACT_TERM[f.motion], sector=f.sector))
        for desc in options:
            if desc in seen:
                continue
            seen.add(desc)
            group = unambiguous_targets(desc, facts)
            if (group is not None and 2 <= len(group) <= config.group_max
                    and all(_well_visible(g, config) for g in group)):
                out.append((desc, group))
    return out


#: Constraints a no-match description may change, by category.
PERTURBABLE: dict[str, tuple[str, ...]] = {
    "vehicle": ("color", "subtype", "motion", "sector", "context"),
    "pedestrian": ("upper", "lower", "motion", "sector", "context"),
}
_CONTEXTS_BY_CATEGORY = {
    "vehicle": (voc.AT_THE_INTERSECTION, voc.BY_THE_CURB, voc.IN_THE_ONCOMING_LANE),
    "pedestrian": (voc.AT_THE_INTERSECTION, voc.ON_THE_CROSSWALK, voc.ON_THE_SIDEWALK),
}


def _alternatives(slot: str, f: ObjectFacts) -> list[str]:
    """Values of ``slot`` other than ``f``'s own that make sense for its category."""
    # simsplat_core.world loads the world generator and numba: imported only where distractors are drawn
    from simsplat_core.world.palette import (  # noqa: PLC0415
        LOWER_COLORS,
        NAMED_COLORS,
        UPPER_COLORS,
        VEHICLE_KINDS,
    )

    if slot in ("color", "upper", "lower"):
        pool = {"color": tuple(NAMED_COLORS), "upper": UPPER_COLORS, "lower": LOWER_COLORS}[slot]
        return [c for c in pool if c != getattr(f, slot)]
    if slot == "subtype":
        return [k.subtype for k in VEHICLE_KINDS if k.subtype != f.subtype]
    if slot == "motion":
        terms = dict.fromkeys(EXACT_TERM[c] for c in MOTION_VOCABULARIES[f.category].names)
        return [t for t in terms if f.motion not in MOTION_TERMS[t][1]]
    if slot == "sector":
        return [s for s in LOCATION_SECTOR.names if s != f.sector]
    if slot == "context":
        return [c for c in _CONTEXTS_BY_CATEGORY[f.category] if c != f.context]
    raise ValueError(f"unknown slot {slot!r}")


def _none_query(
    source: ObjectFacts, facts: list[ObjectFacts], rng: np.random.Generator
) -> tuple[Description, str] | None:
    """A description of ``source`` with one constraint changed so that no object fits it."""
    bases = [d for d in candidate_descriptions(source) if len(d.slots) >= 1]
    slots = PERTURBABLE[source.category]
    for _ in range(30):
        base = bases[int(rng.integers(len(bases)))]
        slot = slots[int(rng.integers(len(slots)))]
        alts = _alternatives(slot, source)
        desc = dataclasses.replace(base, **{slot: alts[int(rng.integers(len(alts)))]})
        if slot == "lower" and desc.upper is None:
            desc = dataclasses.replace(desc, upper=source.upper)
        if not matching(desc, facts, lenient=True):
            return desc, slot
    return None


def generate_queries(log: SceneLog, config: BenchmarkConfig | None = None,
                     facts: dict[str, ObjectFacts] | None = None) -> list[GroundingQuery]:
    """The queries of one log (module docstring); deterministic for ``(config.seed, log.seq_id)``."""
    config = config or BenchmarkConfig()
    rng = _rng(config, log.seq_id)
    facts = facts if facts is not None else object_facts(log, min_frame_pixels=config.min_frame_pixels)
    all_facts = list(facts.values())
    targets = [f for f in all_facts if f.category in QUERY_CATEGORIES and _well_visible(f, config)]
    raw: list[tuple[Description, str, str, tuple[str, ...], str, str]] = []
    group_targets: set[tuple[str, ...]] = set()
    for target in targets:
        for desc, kind, style, ids in _single_queries(target, all_facts, config, rng):
            if kind == "group":
                if ids in group_targets:
                    continue
                group_targets.add(ids)
            raw.append((desc, kind, style, ids, target.object_id if kind == "single" else "", ""))
    candidates = group_candidates(all_facts, config)
    order = rng.permutation(len(candidates))
    used_families: set[tuple[str, str]] = set()
    picked = 0
    for pass_ in range(2):
        for i in order:
            if picked >= config.group_per_log:
                break
            desc, group = candidates[i]
            ids = tuple(sorted(g.object_id for g in group))
            if ids in group_targets or (pass_ == 0 and (desc.family, desc.category) in used_families):
                continue
            used_families.add((desc.family, desc.category))
            group_targets.add(ids)
            raw.append((desc, "group", str(rng.choice(GROUP_STYLES)), ids, "", ""))
            picked += 1
    sources = [targets[i] for i in rng.permutation(len(targets))]
    made = 0
    for source in sources:
        if made >= config.none_per_log:
            break
        found = _none_query(source, all_facts, rng)
        if found is None:
            continue
        desc, slot = found
        raw.append((desc, "none", str(rng.choice(SINGLE_STYLES)), (), source.object_id, slot))
        made += 1
    queries = []
    for n, (desc, kind, style, ids, source_id, slot) in enumerate(raw):
        matched = [facts[i] for i in ids] or [facts[source_id]]
        wording = desc.wording(matched)
        text = realise_group(wording, style, rng) if kind == "group" else realise(wording, style, rng)
        queries.append(
            GroundingQuery(log.seq_id, text, style, ids, kind, desc.category, desc.slots, desc.family,
                           f"{log.seq_id}/{n}", source_id, slot, desc)
        )
    logger.info("%s: %d queries (%d single, %d group, %d none) over %d well-visible objects", log.seq_id,
                len(queries), sum(q.kind == "single" for q in queries), sum(q.kind == "group" for q in queries),
                sum(q.kind == "none" for q in queries), len(targets))
    return queries


def build_benchmark(logs: Sequence[SceneLog], config: BenchmarkConfig | None = None) -> GroundingBenchmark:
    """Queries and ground-truth maps of every log (each log needs images with instance masks)."""
    config = config or BenchmarkConfig()
    queries: list[GroundingQuery] = []
    truth: dict[str, SceneGroundTruth] = {}
    for log in logs:
        if log.seq_id in truth:
            raise ValueError(f"duplicate sequence {log.seq_id!r} in the benchmark logs")
        truth[log.seq_id] = SceneGroundTruth.from_log(log)
        queries += generate_queries(log, config)
    return GroundingBenchmark(tuple(queries), truth, config)


__all__ = [
    "BenchmarkConfig",
    "Description",
    "FAMILIES",
    "GroundingBenchmark",
    "GroundingQuery",
    "ObjectFacts",
    "QUERY_CATEGORIES",
    "QUERY_KINDS",
    "SceneGroundTruth",
    "build_benchmark",
    "candidate_descriptions",
    "generate_queries",
    "group_candidates",
    "matching",
    "object_facts",
    "plausible_readings",
    "query_counts",
    "unambiguous_targets",
]
