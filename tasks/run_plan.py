"""Whether a main run has anything new to do, decided before Prefect or Ray start, and the short record of one that
has not.

``plan_run`` asks the same questions the run's tasks ask before they work, through the same functions (content keys
and stored manifests, no decoding, no training):

1. ingest: does the landing location hold a log not yet ingested (``tasks.landing.scan_landing``)? is a synthetic
   sequence asked for that the store does not hold as it would be generated now
   (``tasks.logs.reusable_synthetic_log``: same seed and world settings)?
2. reconstruct: does every stored log with camera images have its scene for this configuration
   (``tasks.reconstruct.reusable_scene``)?
3. align: is the motion aligner of every stored log stored, and each log's language scene
   (``tasks.align.reusable_aligner`` / ``reusable_language_scene``)?
4. mine: has the mining ledger every minable sequence for these settings (``tasks.mining_ledger.split_by_ledger``)?

It stops at the first stage with work (the run will do it anyway) and names that work in ``RunPlan.pending``. A run
with nothing pending is recorded by ``record_idle_run`` as completed, every sequence's stages skipped with their
reasons, so the dashboard shows that the scheduled run ran and found nothing new. The grounding benchmark is not work
that makes a run: it measures stored language scenes, which are unchanged when nothing is new (``simsplat eval
grounding`` measures them on demand).
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from simsplat_core.language.alignment.motion_training import MotionAlignerConfig
from simsplat_core.language.alignment.scene_builder import AlignmentConfig
from simsplat_core.scene import ReconstructionConfig
from simsplat_core.world import WorldConfig
from storage import ArtifactStore
from storage.errors import MissingInputError
from tasks.align import StoredAligner, StoredLanguageScene, reusable_aligner, reusable_language_scene
from tasks.landing import LandingPlan, scan_landing
from tasks.logs import StoredLog, reusable_synthetic_log, stored_log
from tasks.mining_ledger import LedgerSettings, LedgerSplit, mined_reason, not_exported_reason, split_by_ledger
from tasks.reconstruct import StoredScene, reusable_scene
from tasks.run_record import recorded_run
from tasks.stages import LogStages, decide_stages, resolve_seq_ids

logger = logging.getLogger(__name__)

IN_STORE = "in the store before this run"
NOT_MINABLE = "not among the sequences this run mines"


def minable_sequences(language: list[StoredLanguageScene]) -> list[str]:
    """Sequences a main run mines: every aligned one (a log without camera images is mined on its tracks: box-only
    inserts, judged on the bird's-eye view and the trajectories)."""
    return [s.seq_id for s in language]


@dataclass(frozen=True)
class RunPlan:
    """What a main run would find (module docstring); filled up to the first stage with work.

    Attributes:
        pending: the work the run has to do, one line each (empty: nothing new).
        landing: the landing scan (``None``: no landing location).
        logs, stages: every stored log and its stages.
        scenes: the stored scenes the run would reuse; aligner, language: the stored aligner and language scenes.
        minable: the sequences the run mines; mining: the ledger's split of them (``None``: no mining asked).
    """

    pending: tuple[str, ...]
    landing: LandingPlan | None = None
    logs: tuple[StoredLog, ...] = ()
    stages: tuple[LogStages, ...] = ()
    scenes: tuple[StoredScene, ...] = ()
    aligner: StoredAligner | None = None
    language: tuple[StoredLanguageScene, ...] = ()
    minable: tuple[str, ...] = ()
    mining: LedgerSplit | None = None

    @property
    def nothing_new(self) -> bool:
        return not self.pending


@dataclass(frozen=True)
class RunAsked:
    """What a main run is asked to do (the main flow's parameters that decide its work).

    Attributes:
        seeds, world: synthetic sequences to generate and their world settings.
        landing: the landing location (``None``: none).
        reconstruction, alignment, aligner: the stages' configurations (``aligner`` ``None``: the default).
        align: whether the run aligns; mining: the ledger settings of its mining (``None``: no mining).
    """

    seeds: tuple[int, ...] = ()
    world: WorldConfig = field(default_factory=WorldConfig)
    landing: str | None = None
    reconstruction: ReconstructionConfig = field(default_factory=ReconstructionConfig)
    alignment: AlignmentConfig = field(default_factory=AlignmentConfig)
    aligner: MotionAlignerConfig | None = None
    align: bool = True
    mining: LedgerSettings | None = None


def plan_run(store_root: str, asked: RunAsked) -> RunPlan:
    """What a main run asked ``asked`` would do in the store at ``store_root`` (module docstring).

    Raises:
        ValueError, FileNotFoundError: the landing location cannot be scanned (``tasks.landing.landing_folder``).
    """
    landing = scan_landing(store_root, asked.landing) if asked.landing is not None else None
    if landing is not None and landing.new:
        return RunPlan((f"{len(landing.new)} new log(s) in the landing location",), landing)
    unstored = [seed for seed in asked.seeds if reusable_synthetic_log(store_root, seed, asked.world) is None]
    if unstored:
        return RunPlan((f"generate the synthetic sequence(s) of seed(s) {unstored}",), landing)
    try:
        logs = tuple(stored_log(store_root, seq_id) for seq_id in resolve_seq_ids(store_root))
    except MissingInputError:
        return RunPlan(("no log in the store yet",), landing)
    stages = tuple(decide_stages(s.summary.seq_id, s.summary.source, s.summary.num_images) for s in logs)
    store = ArtifactStore(store_root)
    found = RunPlan((), landing, logs, stages)
    scenes = {p.seq_id: reusable_scene(store, p.seq_id, asked.reconstruction) for p in stages if p.reconstructs}
    missing = [seq_id for seq_id, scene in scenes.items() if scene is None]
    if missing:
        return _pending(found, f"reconstruct {', '.join(missing)}")
    found = _with(found, scenes=tuple(s for s in scenes.values() if s is not None))
    if not asked.align:
        return found
    return _plan_alignment(store_root, store, asked, found)


def _with(plan: RunPlan, **changes: Any) -> RunPlan:
    return dataclasses.replace(plan, **changes)


def _pending(plan: RunPlan, work: str) -> RunPlan:
    return _with(plan, pending=(*plan.pending, work))


def _plan_alignment(store_root: str, store: ArtifactStore, asked: RunAsked, found: RunPlan) -> RunPlan:
    """``found`` with the stored aligner and language scenes, then the mining ledger's split; pending work named."""
    from simsplat_core.language.appearance.embedders import appearance_embedder
    from simsplat_core.language.text import default_text_encoder

    encoder = default_text_encoder()
    embedder = appearance_embedder(asked.alignment.captioner, encoder)
    aligner = reusable_aligner(store, [p.seq_id for p in found.stages], asked.aligner or MotionAlignerConfig(),
                               encoder.name)
    if aligner is None:
        return _pending(found, "train the motion aligner")
    by_seq = {s.seq_id: s.scene_hash for s in found.scenes}
    config = asked.alignment.validate()
    language = {p.seq_id: reusable_language_scene(store, p.seq_id, by_seq.get(p.seq_id), aligner.model_hash, config,
                                                  encoder.name, embedder.name) for p in found.stages}
    missing = [seq_id for seq_id, scene in language.items() if scene is None]
    if missing:
        return _pending(_with(found, aligner=aligner), f"align {', '.join(missing)}")
    aligned = [s for s in language.values() if s is not None]
    found = _with(found, aligner=aligner, language=tuple(aligned))
    if asked.mining is None:
        return found
    minable = tuple(minable_sequences(aligned))
    split = split_by_ledger(store_root, [s for s in aligned if s.seq_id in minable], asked.mining.key)
    found = _with(found, minable=minable, mining=split)
    return _pending(found, f"mine {', '.join(split.to_mine)}") if split.to_mine else found


def skip_reasons(plan: RunPlan, *, evaluate: bool, export: bool) -> dict[tuple[str, str], str]:
    """``(seq_id, stage) -> reason`` of every stage an idle run skips, among those it was asked to run
    (``evaluate``: the grounding benchmark, ``export``: an export)."""
    scenes = {s.seq_id: s for s in plan.scenes}
    language = {s.seq_id: s for s in plan.language}
    mined = {r.seq_id: r for r in plan.mining.mined} if plan.mining is not None else {}
    reasons: dict[tuple[str, str], str] = {}
    for stages in plan.stages:
        seq_id = stages.seq_id
        reasons[seq_id, "ingest"] = IN_STORE
        scene = scenes.get(seq_id)
        reasons[seq_id, "reconstruct"] = f"scene {scene.scene_hash[:12]} stored" if scene else stages.skip_reconstruct
        if seq_id in language:
            reasons[seq_id, "align"] = f"language scene {language[seq_id].language_hash[:12]} stored"
            if evaluate:
                reasons[seq_id, "evaluate"] = stages.skip_evaluate or "nothing new: its language scene is unchanged"
        if plan.mining is not None:
            record = mined.get(seq_id)
            reasons[seq_id, "mine"] = mined_reason(record) if record is not None else NOT_MINABLE
            if export:
                reasons[seq_id, "export"] = not_exported_reason(record) if record is not None else NOT_MINABLE
    return {cell: reason for cell, reason in reasons.items() if reason}


def idle_counts(plan: RunPlan) -> dict[str, int]:
    """The counts of an idle run's record, named as a main run names them."""
    counts = {"logs": len(plan.logs), "scenes": len(plan.scenes)}
    if plan.landing is not None:
        counts.update(landed=0, quarantined=len(plan.landing.quarantined_known))
    if plan.aligner is not None:
        counts["language_scenes"] = len(plan.language)
    if plan.mining is not None:
        counts.update(accepted_scenarios=0, mined_before=len(plan.mining.mined))
    return counts


def record_idle_run(store_root: str, run_id: str, plan: RunPlan, parameters: Mapping[str, Any], *,  # noqa: PLR0913
                    evaluate: bool, export: bool, flow: str = "simsplat-main") -> None:
    """Record run ``run_id`` of ``flow`` that found nothing new (``plan.nothing_new``): completed, with
    ``idle_counts`` and every sequence's stages skipped with ``skip_reasons``. Needs no Prefect run."""
    if not plan.nothing_new:
        raise ValueError(f"run {run_id} has work to do ({'; '.join(plan.pending)}): it is not idle")
    with recorded_run(store_root, run_id, flow=flow, parameters=parameters) as run:
        for (seq_id, stage), reason in skip_reasons(plan, evaluate=evaluate, export=export).items():
            run.skip(stage, [seq_id], reason)
        run.count(**idle_counts(plan))
    logger.info("nothing new in %s: %s; recorded as run %s", store_root, describe_idle(plan), run_id)


def describe_idle(plan: RunPlan) -> str:
    """One line of an idle run's counts (``"2 logs, 2 scenes, 2 language scenes, 2 mined before"``)."""
    parts = [f"{len(plan.logs)} log(s)", f"{len(plan.scenes)} scene(s) stored"]
    if plan.landing is not None:
        parts.append(f"no new landing log ({len(plan.landing.already)} ingested before, "
                     f"{len(plan.landing.quarantined_known)} quarantined)")
    if plan.aligner is not None:
        parts.append(f"{len(plan.language)} language scene(s) stored")
    if plan.mining is not None:
        parts.append(f"{len(plan.mining.mined)} sequence(s) mined before with these settings")
    return ", ".join(parts)
