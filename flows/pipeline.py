"""Prefect flows. Each reads like the pipeline: fan out one task per sequence, gather, publish."""

from __future__ import annotations

import dataclasses
import inspect
import logging
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from prefect import flow
from prefect.artifacts import create_markdown_artifact, create_table_artifact
from prefect.futures import as_completed

from flows.cpu_shares import reserving_cpus, task_cpu_share
from flows.dashboard.links import run_link, scenario_link
from flows.dashboard.settings import dashboard_url
from flows.progress import FlowProgress
from flows.runtime import flow_resubmits_crashed_tasks
from simsplat_core.eval.grounding.metrics import CATEGORIES
from simsplat_core.language.alignment.motion_training import MotionAlignerConfig
from simsplat_core.language.alignment.scene_builder import AlignmentConfig
from simsplat_core.mining.rule_proposals import Proposal
from simsplat_core.scene import ReconstructionConfig
from simsplat_core.vlm.openai_chat import OpenAIChatConfig
from simsplat_core.world import WorldConfig, default_seq_id
from storage.runs import new_run_id, run_dir
from tasks.align import StoredAligner, StoredLanguageScene, align_scene, train_motion_aligner
from tasks.assets import BuiltBank, build_asset_bank
from tasks.export import ExportConfig, ExportResult, export_dataset_task
from tasks.grounding_eval import GroundingEvaluation, evaluate_grounding_run
from tasks.landing import LandingOutcome, land_log, scan_landing
from tasks.logs import StoredLog, generate_synthetic_log, ingest_real_log, stored_log
from tasks.mine import MiningSummary, compact_mining_run, mine_sequence_task, saved_search_seeds_task
from tasks.mining_config import ConfigSource, LoadedMiningConfig, load_mining_config
from tasks.mining_ledger import LedgerSettings, ledger_settings, mined_reason, not_exported_reason, split_by_ledger
from tasks.reconstruct import StoredScene, reconstruct_scene
from tasks.run_plan import IN_STORE, RunAsked, minable_sequences, plan_run, record_idle_run
from tasks.run_record import StageRecorder, recorded_run
from tasks.stages import STAGES, LogStages, decide_stages, plan_alignment, plan_stages, resolve_seq_ids

logger = logging.getLogger(__name__)


def _log_label(result: StoredLog) -> str:
    return result.summary.seq_id


#: Flows that record no run (their tasks are submitted and gathered as they are).
UNRECORDED = StageRecorder()


def _gather(futures: list, stage: str, label: Callable = _log_label, run: StageRecorder = UNRECORDED) -> list:
    """Wait for every one of ``futures`` as they finish, reporting progress and recording each outcome with ``run``;
    results in submission order. The first failure is raised once every future has finished."""
    order = {id(f): i for i, f in enumerate(futures)}
    results: list = [None] * len(futures)
    failures: list[BaseException] = []
    with FlowProgress(stage, total=len(futures)) as progress:
        for future in as_completed(futures):
            try:
                result = run.result(future)
            except Exception as exc:
                failures.append(exc)
                continue
            results[order[id(future)]] = result
            progress.advance(label(result))
    if failures:
        raise failures[0]
    return [r for r in results if r is not None]


def _publish_logs_table(logs: list[StoredLog]) -> None:
    rows = [
        {
            "seq_id": s.summary.seq_id,
            "source": s.summary.source,
            "frames": s.summary.num_frames,
            "cameras": len(s.summary.cameras),
            "objects": sum(s.summary.objects_by_category.values()),
            "MB": round(s.bytes_on_disk / 1e6, 2),
            "seconds": s.seconds,
            "skipped": s.skipped,
        }
        for s in logs
    ]
    create_table_artifact(rows, key="logs", description="Driving logs in the store")


def generate_logs(store_root: str, seeds: list[int], config: WorldConfig,
                  run: StageRecorder = UNRECORDED) -> list[StoredLog]:
    """Fan out one generation task per seed on the flow's task runner; publish the logs table."""
    futures = [run.submit(generate_synthetic_log, "ingest", [default_seq_id(seed)], store_root, seed, config)
               for seed in seeds]
    logs = _gather(futures, "generate", run=run)
    _publish_logs_table(logs)
    return logs


def land_logs(store_root: str, landing: str, run: StageRecorder = UNRECORDED) -> list[StoredLog]:
    """Ingest the new logs of the landing location (``tasks.landing``: one task per log, a log that fails to load
    quarantined with its reason); the logs stored now. Counted in the run as ``landed`` and ``quarantined``."""
    plan = scan_landing(store_root, landing)
    futures = [run.submit(land_log, "ingest", (), store_root, log) for log in plan.new]
    outcomes: list[LandingOutcome] = _gather(futures, "landing", label=lambda outcome: outcome.label, run=run)
    stored = [o.stored for o in outcomes if o.stored is not None]
    run.count(landed=len(stored), quarantined=len(outcomes) - len(stored) + len(plan.quarantined_known))
    return stored


def _report_stages(plans: list[LogStages], stages: tuple[str, ...] = STAGES) -> None:
    """Log the ``stages`` (those this flow runs) each log skips, and publish them as the stages table."""
    for plan in plans:
        for stage, reason in plan.skipped(stages).items():
            logger.info("%s: %s skipped: %s", plan.seq_id, stage, reason)
    rows = [{"seq_id": p.seq_id, "source": p.source, "images": p.images,
             **{stage: f"skipped: {reason}" if reason else "yes"
                for stage, reason in p.reasons().items() if stage in stages}}
            for p in plans]
    create_table_artifact(rows, key="stages", description="Stages per stored log (and why one is skipped)")


def store_logs(store_root: str, generated: list[StoredLog]) -> tuple[list[StoredLog], list[LogStages]]:
    """Every complete log in the store (``generated`` ones as produced now, the others as found) and the
    stages each goes through; publishes the stages table.

    Raises:
        MissingInputError: the store holds no log (the message says how to add one).
    """
    seq_ids = resolve_seq_ids(store_root)
    produced = {s.summary.seq_id: s for s in generated}
    logs = [produced.get(seq_id) or stored_log(store_root, seq_id) for seq_id in seq_ids]
    plans = [decide_stages(s.summary.seq_id, s.summary.source, s.summary.num_images) for s in logs]
    _report_stages(plans)
    return logs, plans


def _rounded(value: float | None, digits: int = 4) -> float | None:
    """``value`` rounded, ``None`` for missing or non-finite values (artifacts are strict JSON)."""
    return round(float(value), digits) if value is not None and math.isfinite(value) else None


def _publish_scenes_table(scenes: list[StoredScene]) -> None:
    names = (
        "psnr_test",
        "ssim_test",
        "psnr_test_dynamic",
        "ssim_test_dynamic",
        "psnr_train",
        "num_gaussians",
        "iterations",
    )
    rows = [
        {
            "seq_id": s.seq_id,
            "scene": s.scene_hash[:12],
            **{name: _rounded(s.metrics.get(name)) for name in names},
            "seconds": s.seconds,
            "skipped": s.skipped,
        }
        for s in scenes
    ]
    create_table_artifact(rows, key="reconstruction", description="Reconstruction metrics per sequence (test frames)")


def reconstruction_config(
    iterations: int | None = None, base: ReconstructionConfig | None = None
) -> ReconstructionConfig:
    """``base`` (default ``ReconstructionConfig()``) with the iteration count overridden when given."""
    base = base or ReconstructionConfig()
    return base if iterations is None else dataclasses.replace(base, iterations=iterations)


def reconstruct_scenes(store_root: str, seq_ids: list[str], config: ReconstructionConfig,
                       run: StageRecorder = UNRECORDED) -> list[StoredScene]:
    """Fan out one reconstruction task per sequence, each with its share of the cores; publish the metrics
    table. ``config.num_threads`` set by the caller wins over the computed share."""
    threads = config.num_threads or task_cpu_share(len(seq_ids))
    config = dataclasses.replace(config, num_threads=threads)
    with reserving_cpus(threads):
        futures = [run.submit(reconstruct_scene, "reconstruct", [seq_id], store_root, seq_id, config)
                   for seq_id in seq_ids]
    scenes = _gather(futures, "reconstruct", label=lambda s: s.seq_id, run=run)
    _publish_scenes_table(scenes)
    return scenes


def _publish_language_table(aligner: StoredAligner, scenes: list[StoredLanguageScene]) -> None:
    names = ("object_nodes", "nodes_with_f_app", "nodes_with_motion", "mask_pooled_iou", "fit_object_accuracy_after")
    rows = [
        {"seq_id": s.seq_id, "scene": s.scene_hash[:12], "aligner": aligner.model_hash[:12],
         **{name: _rounded(s.metrics.get(name)) for name in names}, "seconds": s.seconds, "skipped": s.skipped}
        for s in scenes
    ]
    create_table_artifact(rows, key="language-alignment", description="Language-aligned scenes per sequence")


def _publish_grounding_table(result: GroundingEvaluation) -> None:
    rows = [{"method": method, **{f"{c}_{m}": _rounded(per[c][m]) for c in CATEGORIES for m in ("acc", "viou")}}
            for method, per in result.scores.items()]
    create_table_artifact(rows, key="grounding", description=f"Grounding benchmark: {result.queries} queries on "
                          f"{len(result.seq_ids)} sequences (accuracy / vIoU)")


def align_targets(plans: list[LogStages], scenes: list[StoredScene]) -> list[tuple[str, str | None]]:
    """``(seq_id, scene_hash)`` to align per planned log: its reconstructed scene, or ``None`` for a log
    without camera images (aligned from its tracks and map). Logs that reconstruct but have no scene in
    ``scenes`` are left out."""
    by_seq = {s.seq_id: s.scene_hash for s in scenes}
    return [(p.seq_id, by_seq[p.seq_id] if p.reconstructs else None) for p in plans
            if not p.reconstructs or p.seq_id in by_seq]


def align_scenes(store_root: str, targets: list[tuple[str, str | None]], training_seq_ids: list[str],
                 config: AlignmentConfig, aligner_config: MotionAlignerConfig | None = None,
                 run: StageRecorder = UNRECORDED) -> tuple[StoredAligner, list[StoredLanguageScene]]:
    """Train the motion/location aligner on ``training_seq_ids`` (one task), then align every
    ``(seq_id, scene_hash)`` target (one task per sequence, each with its share of the cores; a ``None``
    scene hash aligns an image-less log from its tracks); publish the alignment table. The aligner's training is
    recorded as the align stage of the targets until their own alignment starts."""
    aligner = run.result(run.submit(train_motion_aligner, "align", [seq_id for seq_id, _ in targets], store_root,
                                    training_seq_ids, aligner_config))
    threads = task_cpu_share(len(targets))
    with reserving_cpus(threads):
        futures = [run.submit(align_scene, "align", [seq_id], store_root, seq_id, scene_hash, aligner.model_hash,
                              config, threads)
                   for seq_id, scene_hash in targets]
    aligned = _gather(futures, "align", label=lambda s: s.seq_id, run=run)
    _publish_language_table(aligner, aligned)
    return aligner, aligned


@dataclass(frozen=True)
class MiningPlan:
    """Mining settings of a flow run (:func:`plans_from_config` makes them from a mining configuration file).

    Attributes:
        per_sequence: accepted scenarios wanted per sequence (K).
        max_attempts: attempts per proposal (the first plus adjusted retries).
        vlm: client, ``"rule"`` (built-in, offline) or ``"openai"``.
        seed: the rule-based client's seed (scenarios are deterministic per seed).
        categories: the edit categories wanted (empty: all six).
        chat: the ``"openai"`` client's endpoint, model and API-key variable name (``None``: from the environment).
        searches: saved searches whose hits seed the loop (``tasks.mine.saved_search_seeds_task``).
        variants_per_hit: seed proposals per search-hit subject.
        only_hits: mine only the sequences where a saved search holds.
        config: the mining configuration file these settings came from (``None``: none), kept in the run record.
    """

    per_sequence: int = 3
    max_attempts: int = 3
    vlm: str = "rule"
    seed: int = 0
    categories: tuple[str, ...] = ()
    chat: OpenAIChatConfig | None = None
    searches: tuple[str, ...] = ()
    variants_per_hit: int = 2
    only_hits: bool = False
    config: ConfigSource | None = None

    def ledger(self) -> LedgerSettings:
        """The settings the mining ledger keys its records by: a sequence is mined once per log and settings (the
        mining configuration's content key among them, so any change to the file mines again)."""
        return ledger_settings(self, self.config.key if self.config is not None else "")


@dataclass(frozen=True)
class ExportPlan:
    """The main job's export stage: the run's accepted scenarios as a dataset.

    Attributes:
        out: the folder the dataset goes in (``<out>/<name>/``); ``None``: the store's ``datasets/``.
        name: the dataset's name; ``None``: the run id (so every run is a dataset of its own). A named dataset
            grows by one increment per run: every accepted scenario of the store not yet in it.
        formats: export formats (default: every one).
    """

    out: str | None = None
    name: str | None = None
    formats: tuple[str, ...] = ()

    def config(self, run_id: str) -> ExportConfig:
        """The export's configuration for run ``run_id``: its accepted scenarios into a dataset of its own, or into the
        named dataset every accepted scenario not yet there (the same filters every run, so each adds to it)."""
        from tasks.export_inputs import ExportFilters

        base = ExportConfig()
        runs = () if self.name else (run_id,)
        return dataclasses.replace(base, name=self.name or run_id, formats=self.formats or base.formats,
                                   filters=ExportFilters(include="accepted", runs=runs))


def plans_from_config(loaded: LoadedMiningConfig, *, per_sequence: int | None = None, vlm: str | None = None,
                      export_out: str | None = None) -> tuple[MiningPlan, ExportPlan | None]:
    """The run's mining and export from a mining configuration file (``tasks.mining_config``), with the command
    line's overrides: ``per_sequence`` (``--mine K``), ``vlm`` (``--vlm``: another client than the file's drops its
    endpoint) and ``export_out`` (``--export DIR``: the dataset's folder). No export when the file names no dataset
    and no ``export_out`` is given."""
    config = loaded.config
    client = vlm or config.vlm.client
    mining = MiningPlan(per_sequence or config.mining.scenarios_per_log, config.mining.max_attempts, client,
                        config.mining.seed, config.mining.categories,
                        config.vlm.chat_config() if client == config.vlm.client else None,
                        config.searches.queries, config.searches.variants_per_hit, config.searches.only_hits,
                        loaded.source)
    dataset = config.dataset
    if dataset is None:
        return mining, ExportPlan(out=export_out) if export_out is not None else None
    return mining, ExportPlan(out=export_out or dataset.out, name=dataset.name, formats=dataset.formats)


def _publish_mining_table(summaries: list[MiningSummary], run_id: str) -> None:
    """The accepted scenarios, each with its dashboard card's address when a dashboard is configured."""
    base = dashboard_url()
    rows = [{"seq_id": s.seq_id, "prompt": sc.prompt, "category": sc.category, "attempts": sc.attempts,
             "plausibility": sc.plausibility, "edit_dir": sc.edit_dir,
             **({"dashboard": scenario_link(base, run_id, sc.seq_id, sc.edit_id)} if base else {})}
            for s in summaries for sc in s.scenarios]
    accepted = sum(s.accepted for s in summaries)
    attempts = sum(s.attempts for s in summaries)
    create_table_artifact(rows, key="mined-scenarios", description=f"Mined scenarios: {accepted} accepted in "
                          f"{attempts} attempts over {len(summaries)} sequence(s)")


def mine_scenarios(store_root: str, seq_ids: list[str], run_id: str, plan: MiningPlan,  # noqa: PLR0913
                   run: StageRecorder = UNRECORDED, positions: list[int] | None = None,
                   rendered: list[str] | None = None, seeds: dict[str, list[Proposal]] | None = None
                   ) -> list[MiningSummary]:
    """Build the asset bank of the store's reconstructed scenes when the store has none for them (one task; a stored
    bank is reused), recorded as the mine stage of ``seq_ids`` until their mining starts -- unless none of
    ``seq_ids`` is among the ``rendered`` ones (those with a reconstructed scene; ``None``: all of them): logs without
    camera images insert boxes and need no bank. Then fan out one mining task per sequence, each with its share of
    the cores and its ``seeds`` (seed proposals, e.g. saved-search hits), each recorded in the mining ledger once
    stored; publish the accepted scenarios' table. ``positions``: each sequence's place among the run's minable ones
    (default: its index in ``seq_ids``): the sequences take the edit categories in turn from there."""
    if rendered is None or set(rendered) & set(seq_ids):
        bank: BuiltBank = run.result(run.submit(build_asset_bank, "mine", seq_ids, store_root))
        logger.info("asset bank %s: %d assets%s", bank.bank_hash[:12], bank.assets,
                    " (stored)" if bank.skipped else "")
    threads = task_cpu_share(len(seq_ids))
    with reserving_cpus(threads):
        futures = [run.submit(mine_sequence_task, "mine", [seq_id], store_root, seq_id, run_id,
                              per_sequence=plan.per_sequence, max_attempts=plan.max_attempts, vlm=plan.vlm,
                              seed=plan.seed, seed_prompts=(seeds or {}).get(seq_id, ()),
                              category_offset=i * plan.per_sequence, categories=plan.categories, chat=plan.chat,
                              threads=threads, ledger=plan.ledger())
                   for i, seq_id in zip(positions or range(len(seq_ids)), seq_ids)]
    summaries = _gather(futures, "mine", label=lambda s: s.seq_id, run=run)
    compact_mining_run(store_root, run_id)
    _publish_mining_table(summaries, run_id)
    return summaries


@flow(name="simsplat-generate-world")
def generate_world_flow(store_root: str, seeds: list[int], config: WorldConfig) -> list[StoredLog]:
    """Generate one synthetic sequence per seed into the store, in parallel."""
    with flow_resubmits_crashed_tasks():
        return generate_logs(store_root, seeds, config, StageRecorder())


@flow(name="simsplat-ingest")
def ingest_flow(store_root: str, source: str, paths: list[str], image_scale: float = 1.0) -> list[StoredLog]:
    """Decode real driving logs (one task per file or log directory) into the store."""
    run = StageRecorder()
    with flow_resubmits_crashed_tasks():
        futures = [run.submit(ingest_real_log, "ingest", (), store_root, source, path, image_scale) for path in paths]
        logs = _gather(futures, f"ingest {source}", run=run)
    _publish_logs_table(logs)
    return logs


@dataclass(frozen=True)
class MainResult:
    """What the main job produced: every stored log, a scene per log with images, a language scene per
    log, the aligner, and the stages each log went through (with the reasons for those it skipped)."""

    logs: list[StoredLog]
    scenes: list[StoredScene]
    aligner: StoredAligner | None = None
    language: list[StoredLanguageScene] = dataclasses.field(default_factory=list)
    grounding: GroundingEvaluation | None = None
    run_id: str = ""
    stages: list[LogStages] = dataclasses.field(default_factory=list)
    mining: list[MiningSummary] = dataclasses.field(default_factory=list)
    export: ExportResult | None = None


def _summary_markdown(result: MainResult) -> str:
    lines = [
        "| sequence | frames | objects | MB | PSNR test (dB) | SSIM test | PSNR dynamic (dB) | Gaussians "
        "| reconstruct s |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    scenes = {s.seq_id: s for s in result.scenes}
    skipped = {p.seq_id: p.skip_reconstruct for p in result.stages}
    for log in result.logs:
        seq_id = log.summary.seq_id
        objects = ", ".join(f"{n} {c}" for c, n in log.summary.objects_by_category.items())
        row = f"| {seq_id} | {log.summary.num_frames} | {objects} | {log.bytes_on_disk / 1e6:.1f} "
        scene = scenes.get(seq_id)
        if scene is None:
            lines.append(row + f"| skipped: {skipped.get(seq_id) or 'not reconstructed'} | | | | |")
            continue
        m = scene.metrics
        lines.append(
            row + f"| {m.get('psnr_test', float('nan')):.2f} | {m.get('ssim_test', float('nan')):.3f} "
            f"| {m.get('psnr_test_dynamic', float('nan')):.2f} | {int(m.get('num_gaussians', 0))} "
            f"| {scene.seconds:.1f} |"
        )
    base = dashboard_url()
    for summary in result.mining:
        lines.append(f"\nMined {summary.seq_id}: {summary.accepted} scenario(s) accepted in {summary.attempts} "
                     f"attempt(s) ({summary.client}; {summary.seconds.get('total', 0.0):.0f} s)")
        if base:
            lines.extend(f"- [{sc.prompt}]({scenario_link(base, result.run_id, sc.seq_id, sc.edit_id)})"
                         for sc in summary.scenarios)
    if result.export is not None:
        lines.append(f"\nExported {result.export.written} scenario(s) to {result.export.dataset_uri}")
    if base:
        lines.append(f"\n[Run {result.run_id} on the dashboard]({run_link(base, result.run_id)})")
    return "\n".join(lines)


@flow(name="simsplat-main")
def main_flow(  # noqa: PLR0913 -- Prefect flow: its parameters are the run's inputs, shown and set in the UI
    store_root: str,
    seeds: list[int],
    config: WorldConfig,
    reconstruction: ReconstructionConfig | None = None,
    alignment: AlignmentConfig | None = None,
    align: bool = True,
    aligner: MotionAlignerConfig | None = None,
    evaluate: bool = True,
    run_id: str | None = None,
    mining: MiningPlan | None = None,
    export: ExportPlan | None = None,
    landing: str | None = None,
) -> MainResult:
    """The main job over every log in the store: ``seeds`` synthetic logs generated first (none: only the
    stored ones, ingested real logs included), one reconstructed scene per log with camera images, language
    alignment (aligner trained on every stored log, one language scene per log: image-less logs get motion
    and location language from their tracks and map), the grounding benchmark on the synthetic logs, scenario
    mining when asked (``mining``), a summary. The run is recorded as it goes under ``runs/<run_id>/``
    (``tasks.run_record``: the run's status, parameters and counts, each sequence's stages).

    Args:
        seeds: synthetic sequences to generate into the store first (may be empty).
        reconstruction: scene reconstruction settings (default ``ReconstructionConfig()``).
        alignment: language-scene settings (default ``AlignmentConfig()``).
        align: run the language-alignment stage.
        aligner: motion/location aligner training settings (default ``MotionAlignerConfig()``).
        evaluate: after alignment, run the grounding benchmark on the synthetic logs and write its
            tables under ``runs/<run_id>/tables/``.
        run_id: names the run directory (default: ``main-<UTC time>``); mined scenarios go to ``edits/<run_id>/``.
        mining: after alignment, mine every aligned sequence for scenarios (an asset bank built first from the
            reconstructed scenes when missing; a log without camera images is mined on its tracks with box-only
            inserts; ``None``: no mining).
        export: after mining, export this run's accepted scenarios as a dataset (``None``: no export).
        landing: a folder (path or ``file://`` URI) scanned first for new logs of any registered source
            (``tasks.landing``: ingested once, a log that fails to load quarantined); ``None``: no scan.

    Raises:
        MissingInputError: the store holds no log, ``seeds`` is empty and the landing location added none.
    """
    run_id = run_id or new_run_id("main")
    with recorded_run(store_root, run_id) as run, flow_resubmits_crashed_tasks():
        generated = generate_logs(store_root, seeds, config, run) if seeds else []
        generated += land_logs(store_root, landing, run) if landing else []
        logs, plans = store_logs(store_root, generated)
        record_planned_skips(run, plans, generated, align=align, evaluate=evaluate)
        run.count(logs=len(logs))
        seq_ids = [p.seq_id for p in plans]
        scenes = reconstruct_scenes(store_root, [p.seq_id for p in plans if p.reconstructs],
                                    reconstruction or ReconstructionConfig(), run)
        run.count(scenes=len(scenes))
        stored_aligner: StoredAligner | None = None
        language: list[StoredLanguageScene] = []
        grounding: GroundingEvaluation | None = None
        if align:
            stored_aligner, language = align_scenes(store_root, align_targets(plans, scenes), seq_ids,
                                                    alignment or AlignmentConfig(), aligner, run)
            run.count(language_scenes=len(language))
            evaluated = [p.seq_id for p in plans if p.evaluates]
            if evaluate and evaluated:
                grounding = run.result(run.submit(evaluate_grounding_run, "evaluate", evaluated, store_root,
                                                  evaluated, store_root, run_dir(run_id)))
                _publish_grounding_table(grounding)
        mined = _mine_and_export(store_root, language, run_id, mining, export, run)
        result = MainResult(logs, scenes, stored_aligner, language, grounding, run_id, plans, *mined)
        create_markdown_artifact(_summary_markdown(result), key="main-summary", description="SIMSplat main job")
    return result


def idle_main_run(params: Mapping[str, Any]) -> MainResult | None:
    """A main run with ``params`` (``main_flow``'s parameters) when it has nothing new to do (``tasks.run_plan``):
    recorded now as a completed run whose stages are all skipped, without Prefect or Ray, and returned as its result;
    ``None`` when the flow has work to do."""
    bound = inspect.signature(main_flow.fn).bind(**params)
    bound.apply_defaults()
    args = bound.arguments
    mining: MiningPlan | None = args["mining"]
    asked = RunAsked(tuple(args["seeds"]), args["config"], args["landing"],
                     args["reconstruction"] or ReconstructionConfig(), args["alignment"] or AlignmentConfig(),
                     args["aligner"], args["align"], mining.ledger() if mining is not None else None)
    plan = plan_run(args["store_root"], asked)
    if not plan.nothing_new:
        logger.info("work to do: %s", "; ".join(plan.pending))
        return None
    run_id = args["run_id"] or new_run_id("main")
    record_idle_run(args["store_root"], run_id, plan, args, evaluate=args["evaluate"],
                    export=args["export"] is not None)
    return MainResult(list(plan.logs), list(plan.scenes), plan.aligner, list(plan.language), None, run_id,
                      list(plan.stages))


def record_planned_skips(run: StageRecorder, plans: list[LogStages], generated: list[StoredLog], *, align: bool,
                         evaluate: bool) -> None:
    """Record the stages each log skips by plan (``tasks.stages``' reasons; logs stored before this run skip
    ingest), among those the main job was asked to run."""
    produced = {s.summary.seq_id for s in generated}
    run.skip("ingest", [p.seq_id for p in plans if p.seq_id not in produced], IN_STORE)
    for plan in plans:
        for stage, reason in plan.skipped().items():
            if stage == "reconstruct" or (align and evaluate):
                run.skip(stage, [plan.seq_id], reason)


def _mine_and_export(store_root: str, language: list[StoredLanguageScene], run_id: str, mining: MiningPlan | None,
                     export: ExportPlan | None, run: StageRecorder
                     ) -> tuple[list[MiningSummary], ExportResult | None]:
    """The main job's mining (``mining``: every aligned sequence not in the mining ledger for these settings, logs
    without images on their tracks; seeded by the plan's saved searches) and export (``export``: this run's accepted
    scenarios), each recorded per sequence with the reason of a skip."""
    to_mine = minable_sequences(language) if mining is not None else []
    positions = {seq_id: i for i, seq_id in enumerate(to_mine)}
    seeds: dict[str, list[Proposal]] = {}
    if mining is not None:
        ledgered = split_by_ledger(store_root, [s for s in language if s.seq_id in positions], mining.ledger().key)
        for record in ledgered.mined:
            run.skip("mine", [record.seq_id], mined_reason(record))
            if export is not None:
                run.skip("export", [record.seq_id], not_exported_reason(record))
        to_mine = list(ledgered.to_mine)
    if mining is not None and mining.searches and to_mine:
        seeds = run.result(run.submit(saved_search_seeds_task, "mine", to_mine, store_root, list(mining.searches),
                                      sequences=to_mine, per_hit=mining.variants_per_hit))
        if mining.only_hits:
            run.skip("mine", [s for s in to_mine if s not in seeds], "no saved search holds in it")
            to_mine = [s for s in to_mine if s in seeds]
    rendered = [s.seq_id for s in language if s.scene_hash]
    mined = mine_scenarios(store_root, to_mine, run_id, mining, run, [positions[s] for s in to_mine], rendered,
                           seeds) if mining is not None and to_mine else []
    run.count(accepted_scenarios=sum(s.accepted for s in mined))
    if export is None:
        return mined, None
    with_accepted = [s.seq_id for s in mined if s.accepted]
    run.skip("export", [s.seq_id for s in mined if not s.accepted], "no accepted scenario")
    if not with_accepted:
        return mined, None
    exported: ExportResult = run.result(run.submit(export_dataset_task, "export", with_accepted, store_root,
                                                   export.out, export.config(run_id)))
    run.count(exported=exported.written)
    return mined, exported


@dataclass(frozen=True)
class AlignResult:
    """What the alignment flow produced: the aligner (trained on every stored log), the language scenes
    of the chosen logs, and their stages."""

    aligner: StoredAligner
    language: list[StoredLanguageScene]
    stages: list[LogStages]


@flow(name="simsplat-align")
def align_flow(store_root: str, seq_ids: list[str] | None = None, alignment: AlignmentConfig | None = None,
               aligner: MotionAlignerConfig | None = None) -> AlignResult:
    """Language alignment over stored logs: train (or reuse) the motion/location aligner on every log in
    the store, real ones included (their auto-labels), then align ``seq_ids`` (default: every log): a log
    with camera images through its newest reconstructed scene, a log without from its tracks and map. Recorded as
    run ``align-<UTC time>``.

    Raises:
        MissingInputError: see ``tasks.stages.plan_alignment``.
    """
    plan = plan_alignment(store_root, seq_ids)
    _report_stages(plan.stages, ("reconstruct",))  # a log without a reconstruction is aligned from its tracks
    with recorded_run(store_root, new_run_id("align")) as run, flow_resubmits_crashed_tasks():
        model, language = align_scenes(store_root, plan.targets, plan.training_seq_ids,
                                       alignment or AlignmentConfig(), aligner, run)
        run.count(language_scenes=len(language))
    return AlignResult(model, language, plan.stages)


@flow(name="simsplat-reconstruct")
def reconstruct_flow(store_root: str, seq_ids: list[str], config: ReconstructionConfig) -> list[StoredScene]:
    """Reconstruct stored logs (one task per sequence) into scene-graph Gaussian scenes, recorded as run
    ``reconstruct-<UTC time>``; logs without camera images are skipped (logged, in the stages table and the run
    record: they cannot be reconstructed)."""
    plans = plan_stages(store_root, seq_ids)
    _report_stages(plans, ("reconstruct",))
    with recorded_run(store_root, new_run_id("reconstruct")) as run, flow_resubmits_crashed_tasks():
        for plan in plans:
            if plan.skip_reconstruct:
                run.skip("reconstruct", [plan.seq_id], plan.skip_reconstruct)
        scenes = reconstruct_scenes(store_root, [p.seq_id for p in plans if p.reconstructs], config, run)
        run.count(scenes=len(scenes))
    return scenes


@flow(name="simsplat-scheduled-main")
def scheduled_main_flow(  # noqa: PLR0913 -- Prefect flow: its parameters are the deployment's inputs
    store_root: str,
    sequences: int = 2,
    seed: int = 0,
    frames: int = 40,
    width: int = 240,
    height: int = 160,
    runner: str = "ray",
    iterations: int | None = None,
    landing: str | None = None,
    mine: int = 0,
    export: str | None = None,
    mining_config: str | None = None,
) -> MainResult:
    """Deployment entry point (``deploy/prefect.yaml``): JSON parameters in, the main flow on ``runner``.

    A deployment cannot choose a task runner per run, so this parent flow picks it and runs
    ``main_flow`` as a subflow, unless the run has nothing new to do (``idle_main_run``: no new landing log, the
    synthetic sequences already stored alike, every stored log reconstructed, aligned and mined for these
    settings), which is recorded without starting the task runner.

    ``iterations`` overrides the reconstruction iteration count; ``landing`` is the folder scanned for new logs
    first (see ``main_flow``); ``mine`` accepted scenarios are mined per sequence (0: no mining; the rule-based
    client with ``seed``) and, with ``mine``, ``export`` is the folder the run's accepted scenarios go in as a
    dataset (``ExportPlan.out``; ``None``: no export).
    ``mining_config`` is a mining configuration file (``tasks.mining_config``; a path relative to the working
    directory, the repository's root in a deployment): the run mines and exports as it says, ``mine`` (when not 0)
    and ``export`` overriding its scenarios per log and its dataset folder.

    Raises:
        MiningConfigError: ``mining_config`` cannot be read or is not valid (naming the file and the field).
    """
    from flows.runtime import RunnerKind, make_task_runner

    config = WorldConfig(num_frames=frames, width=width, height=height)
    seeds = list(range(seed, seed + sequences))
    mining: MiningPlan | None = MiningPlan(mine, seed=seed) if mine else None
    export_plan = ExportPlan(out=export) if export is not None and mining is not None else None
    if mining_config is not None:
        mining, export_plan = plans_from_config(load_mining_config(mining_config), per_sequence=mine or None,
                                                export_out=export)
    params: dict[str, Any] = dict(store_root=store_root, seeds=seeds, config=config, landing=landing, mining=mining,
                                  reconstruction=reconstruction_config(iterations), export=export_plan)
    idle = idle_main_run(params)
    if idle is not None:  # nothing new: recorded as such, and no task runner (no Ray) started
        return idle
    return main_flow.with_options(task_runner=make_task_runner(RunnerKind(runner)))(**params)
