"""The editing prompt set (SIMSplat Table 3) over synthetic scenes, written from each world's ground truth.

    prompts = build_prompt_set(truths, PromptConfig(per_category=30))
    prompts[0].text          # "Put a red SUV 8 m behind the white van."
    prompts[0].intent        # EditIntent(op="insert", placement=PlacementIntent("behind", "veh_02", 8.0), ...)
    prompts[0].structured    # the same edit naming node ids (the OmniRe-like baseline's input)

Categories (:data:`CATEGORIES`): add_vehicle, add_static, add_pedestrian, modify_vehicle,
modify_pedestrian, remove -- ``per_category`` prompts each, spread over the scenes as evenly as they
allow -- plus ``infeasible`` prompts that a correct editor must refuse (:data:`INFEASIBLE`).

Variety: each category mixes intent kinds (``plans.py``: in-lane / side-lane / oncoming / relative to a
scene object; absolute and relative speeds in km/h, m/s and mph, stops, lane changes, turns, delays,
reversing, replacing; single objects and groups), taken round-robin in a seeded order; each kind has
several sentence forms (``wording.FORMS``), used in turn; targets and anchors are named by colour, type,
motion or location, whichever singles them out. Generation is deterministic for
``(config.seed, seq_id, category)``.
"""

from __future__ import annotations

import dataclasses
import logging
import zlib
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from simsplat_core.editing.commands import EditProgram
from simsplat_core.eval.editing.intents import EditIntent, intent_program
from simsplat_core.eval.editing.plans import PLANNERS, AssetPools, Draft
from simsplat_core.eval.editing.truth import SceneTruth
from simsplat_core.eval.editing.wording import FORMS

logger = logging.getLogger(__name__)

#: Prompt categories of SIMSplat Table 3.
CATEGORIES: tuple[str, ...] = ("add_vehicle", "add_static", "add_pedestrian", "modify_vehicle",
                               "modify_pedestrian", "remove")
#: The category of prompts that must be refused.
INFEASIBLE = "infeasible"


@dataclass(frozen=True)
class EditPrompt:
    """One prompt of the set.

    Attributes:
        prompt_id: ``"<seq_id>/<category>/<n>"``.
        seq_id: the scene it is about.
        category: a :data:`CATEGORIES` entry or :data:`INFEASIBLE`.
        kind: the intent kind (``wording.FORMS`` key); form: index of its sentence form.
        text: the words.
        intent: the edit in ground-truth terms (object ids, SI quantities).
        structured: the edit as commands naming node ids (``None`` when it names no existing object).
    """

    prompt_id: str
    seq_id: str
    category: str
    kind: str
    form: int
    text: str
    intent: EditIntent
    structured: EditProgram | None

    @property
    def infeasible(self) -> bool:
        return self.category == INFEASIBLE


@dataclass(frozen=True)
class PromptConfig:
    """Size and seed of the prompt set.

    Attributes:
        per_category: prompts per category over all scenes (the paper's Table 3 uses 30 or more).
        infeasible: prompts that must be refused, over all scenes.
        seed: combined with each scene's id and the category.
    """

    per_category: int = 30
    infeasible: int = 20
    seed: int = 0

    def __post_init__(self) -> None:
        if self.per_category < 1 or self.infeasible < 0:
            raise ValueError(f"PromptConfig: per_category must be >= 1 and infeasible >= 0, got "
                             f"{self.per_category} / {self.infeasible}")


def _rng(config: PromptConfig, seq_id: str, category: str) -> np.random.Generator:
    return np.random.default_rng([config.seed, zlib.crc32(seq_id.encode()), zlib.crc32(category.encode())])


def _capitalised(text: str) -> str:
    return text[:1].upper() + text[1:]


def _realised(draft: Draft, form: str) -> tuple[str, EditIntent]:
    """The words of ``draft`` in ``form`` and the intent they state (no ``{d}`` in the form: no distance)."""
    text = _capitalised(form.format(**draft.slots))
    intent = draft.intent
    if "{d}" not in form and intent.placement is not None and intent.placement.distance_m is not None:
        intent = dataclasses.replace(intent, placement=dataclasses.replace(intent.placement, distance_m=None))
    return text, intent


def quotas(total: int, scenes: int) -> list[int]:
    """``total`` split over ``scenes`` as evenly as possible (earlier scenes take the remainder)."""
    return [total // scenes + (1 if k < total % scenes else 0) for k in range(scenes)]


def scene_prompts(truth: SceneTruth, category: str, count: int, pools: AssetPools,
                  config: PromptConfig) -> list[EditPrompt]:
    """``count`` prompts of ``category`` about one scene (fewer when the scene offers no draft at all)."""
    rng = _rng(config, truth.seq_id, category)
    drafts = PLANNERS[category](truth, pools, rng)
    by_kind: dict[str, list[Draft]] = {}
    for draft in drafts:
        by_kind.setdefault(draft.kind, []).append(draft)
    if not by_kind:
        logger.warning("%s: no feasible %s edit in this scene", truth.seq_id, category)
        return []
    kinds = [sorted(by_kind)[i] for i in rng.permutation(len(by_kind))]
    form_order = {k: [int(i) for i in rng.permutation(len(FORMS[k]))] for k in kinds}
    used_forms = dict.fromkeys(kinds, 0)
    remaining = {k: [by_kind[k][int(i)] for i in rng.permutation(len(by_kind[k]))] for k in kinds}
    out = []
    for n in range(count):
        kind = kinds[n % len(kinds)]
        pool = remaining[kind] or [by_kind[kind][int(rng.integers(len(by_kind[kind])))]]
        draft = pool.pop(0)
        order = form_order[kind]
        form = order[used_forms[kind] % len(order)]
        used_forms[kind] += 1
        try:
            text, intent = _realised(draft, FORMS[kind][form])
        except KeyError as exc:
            raise KeyError(f"{kind}: {exc} {draft.slots}") from exc
        out.append(EditPrompt(f"{truth.seq_id}/{category}/{n}", truth.seq_id, category, kind, form, text, intent,
                              intent_program(intent, truth.node_of_object, text)))
    return out


def build_prompt_set(truths: Sequence[SceneTruth], config: PromptConfig | None = None,
                     pools: AssetPools | None = None) -> list[EditPrompt]:
    """Every category's prompts and the infeasible ones over ``truths`` (module docstring).

    ``pools`` (what inserts may ask for) defaults to the well-visible objects of ``truths``.

    Raises:
        ValueError: no scenes, or two scenes with the same id.
    """
    config = config or PromptConfig()
    if not truths:
        raise ValueError("build_prompt_set: no scenes")
    ids = [t.seq_id for t in truths]
    if len(set(ids)) != len(ids):
        raise ValueError(f"build_prompt_set: duplicate scenes in {ids}")
    pools = pools or AssetPools.from_truths(truths)
    out: list[EditPrompt] = []
    for category, total in [*((c, config.per_category) for c in CATEGORIES), (INFEASIBLE, config.infeasible)]:
        for truth, count in zip(truths, quotas(total, len(truths))):
            out += scene_prompts(truth, category, count, pools, config)
    logger.info("editing prompt set: %d prompts over %d scenes (%s)", len(out), len(truths),
                ", ".join(f"{c} {sum(p.category == c for p in out)}" for c in (*CATEGORIES, INFEASIBLE)))
    return out


def prompt_counts(prompts: Sequence[EditPrompt]) -> dict[str, int]:
    """Prompts per category (and ``"total"`` of the feasible ones)."""
    counts = {c: sum(p.category == c for p in prompts) for c in (*CATEGORIES, INFEASIBLE)}
    counts["total"] = sum(counts[c] for c in CATEGORIES)
    return counts


__all__ = ["CATEGORIES", "INFEASIBLE", "EditPrompt", "PromptConfig", "build_prompt_set", "prompt_counts", "quotas",
           "scene_prompts"]
