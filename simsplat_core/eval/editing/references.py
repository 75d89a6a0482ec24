"""Referring expressions for the editing prompts, from ground truth.

Scene objects are named the way the grounding benchmark names them (``eval.grounding.benchmark``): a
combination of the object's own attributes -- body style, colour, clothing, motion, location -- that no
other object of the scene satisfies under any plausible reading, put into words by its paraphraser.
Editing prompts prefer short names ("the white van") and add motion or location only when needed.

Static objects and signs have no motion or clothing: they are named by kind ("the stop sign"), with the
side of the ego they are seen on when the kind alone is not unique ("the traffic cone on the right").

Groups ("all parked cars", "every pedestrian standing on the sidewalk") come from the benchmark's group
descriptions, which fit 2 or more well visible objects and no others under any reading. Absent objects
("the purple bus") are descriptions that fit nothing: a colour the world never paints with.
"""

from __future__ import annotations

import numpy as np

from simsplat_core.eval.editing.truth import MIN_VISIBLE_FRAMES, SceneTruth
from simsplat_core.eval.editing.wording import pick
from simsplat_core.eval.grounding.benchmark import (
    BenchmarkConfig,
    Description,
    candidate_descriptions,
    group_candidates,
    unambiguous_targets,
)
from simsplat_core.eval.grounding.paraphrases import realise, realise_group
from simsplat_core.language.motion_labels import LabelThresholds, location_sector
from simsplat_core.scenario import vocabulary as voc
from simsplat_core.scenario.trajectory import to_ego_frame

#: Preference of description families for editing prompts (short names first).
FAMILY_WEIGHTS: dict[str, float] = {"app": 4.0, "app+mot": 2.0, "app+loc": 2.0, "app+mot+loc": 1.0,
                                    "mot": 0.5, "loc": 0.3, "mot+loc": 0.5}
#: Single-object styles of the paraphraser that give a noun phrase.
PHRASE_STYLES: tuple[str, ...] = ("definite", "relative")
#: Group styles that give a noun phrase.
GROUP_PHRASE_STYLES: tuple[str, ...] = ("all", "every", "plural")
#: Colours no object of the synthetic world has (absent-object prompts).
ABSENT_COLORS: tuple[str, ...] = ("purple", "pink")
_SIDE_WORDS = {voc.LEFT_OF_EGO: ("on the left", "on our left"), voc.RIGHT_OF_EGO: ("on the right", "on our right"),
               voc.IN_FRONT_OF_EGO: ("ahead of us", "in front of us"), voc.BEHIND_EGO: ("behind us",)}


def unique_descriptions(truth: SceneTruth, object_id: str) -> list[Description]:
    """Descriptions of a vehicle or pedestrian that fit it and no other object under any reading."""
    facts = list(truth.facts.values())
    out = []
    for desc in candidate_descriptions(truth.facts[object_id]):
        targets = unambiguous_targets(desc, facts)
        if targets is not None and [f.object_id for f in targets] == [object_id]:
            out.append(desc)
    return out


def object_phrase(truth: SceneTruth, object_id: str, rng: np.random.Generator) -> str | None:
    """A definite description singling out a vehicle or pedestrian (``None`` when none does)."""
    options = [d for d in unique_descriptions(truth, object_id) if d.family in FAMILY_WEIGHTS]
    if not options:
        return None
    weights = np.array([FAMILY_WEIGHTS[d.family] / sum(o.family == d.family for o in options) for d in options])
    desc = options[int(rng.choice(len(options), p=weights / weights.sum()))]
    text = realise(desc.wording([truth.facts[object_id]]), pick(rng, PHRASE_STYLES), rng)
    return text.rstrip(".")


def _best_frame(truth: SceneTruth, object_id: str) -> int:
    """The frame where the log shows the most pixels of ``object_id``."""
    counts = np.zeros(truth.log.num_frames)
    inst = truth.facts[object_id].instance_id
    for img in truth.log.images:
        if img.instance is not None:
            counts[img.frame_idx] += np.count_nonzero(img.instance == inst)
    return int(np.argmax(counts))


def _sector_at(truth: SceneTruth, object_id: str, frame: int) -> str:
    xy = truth.agent(object_id).traj["xy"][frame]
    return location_sector(to_ego_frame(xy[None], truth.world.ego_poses[frame])[0], LabelThresholds())


def static_phrase(truth: SceneTruth, object_id: str, rng: np.random.Generator) -> str | None:
    """``"the stop sign"`` / ``"the traffic cone on the right"``: a static object or sign by kind, with the side of
    the ego it is on -- the same at the first frame and where it is seen best, and no other object of its kind
    on that side at either -- when the kind alone is not unique."""
    agent = truth.agent(object_id)
    same = [a.object_id for a in truth.world.agents if a.subtype == agent.subtype and a.object_id != object_id]
    if not same:
        return f"the {agent.subtype}"
    frames = (0, _best_frame(truth, object_id))
    sectors = {_sector_at(truth, object_id, f) for f in frames}
    if len(sectors) != 1 or any(_sector_at(truth, o, f) in sectors for o in same for f in frames):
        return None
    return f"the {agent.subtype} {pick(rng, _SIDE_WORDS[sectors.pop()])}"


def group_phrases(truth: SceneTruth, rng: np.random.Generator) -> list[tuple[str, tuple[str, ...]]]:
    """``(words, object ids)`` of group descriptions of vehicles and pedestrians, all members well visible."""
    facts = list(truth.facts.values())
    out = []
    for desc, members in group_candidates(facts, BenchmarkConfig(min_visible_frames=MIN_VISIBLE_FRAMES)):
        ids = tuple(sorted(m.object_id for m in members))
        if not all(truth.well_visible(i) for i in ids):
            continue
        text = realise_group(desc.wording(members), pick(rng, GROUP_PHRASE_STYLES), rng)
        out.append((text, ids))
    return out


def static_groups(truth: SceneTruth) -> list[tuple[str, tuple[str, ...]]]:
    """``("all the traffic cones", ids)`` for static kinds with several members, one of them well visible."""
    by_kind: dict[str, list[str]] = {}
    for agent in truth.world.agents:
        if agent.category in ("static", "sign"):
            by_kind.setdefault(agent.subtype, []).append(agent.object_id)
    out = []
    for kind, ids in by_kind.items():
        if len(ids) >= 2 and any(truth.well_visible(i) for i in ids):
            out.append((f"all the {kind}s", tuple(sorted(ids))))
    return out


def absent_vehicle_phrase(truth: SceneTruth, rng: np.random.Generator) -> str:
    """``"the purple bus"``: a vehicle no object of the scene could be."""
    subtype = pick(rng, ("bus", "SUV", "van", "truck", "sedan", "pickup truck"))
    return f"the {pick(rng, ABSENT_COLORS)} {subtype}"


def absent_pedestrian_phrase(rng: np.random.Generator) -> str:
    return f"the {pick(rng, ('person', 'pedestrian', 'man'))} in the {pick(rng, ABSENT_COLORS)} " \
           f"{pick(rng, ('coat', 'jacket', 'dress'))}"


__all__ = ["ABSENT_COLORS", "absent_pedestrian_phrase", "absent_vehicle_phrase", "group_phrases", "object_phrase",
           "static_groups", "static_phrase", "unique_descriptions"]
