"""Task: every evaluation table the store's contents allow, into one run directory (``runs/<run_id>/`` or ``OUT``).

Thin: read what the store holds (:func:`store_contents`), let ``simsplat_core.eval.plan`` choose the evaluations
(a skipped one is logged with what the store lacks), run each through its own task (``tasks.*_eval``; the
reconstruction and throughput tables from the figures the stages recorded), publish each table as a Prefect table
artifact (inside a flow or task run) and write

    <run>/tables/<name>.{parquet,md}     every table (declared in simsplat_core.eval.table_registry)
    <run>/summary.md                     every table with its title, and the skipped evaluations with reasons
    <run>/manifest.json                  code version, config, the store's content keys used, wall time per table

    result = evaluate_all(store_root)                 # runs/<run_id>/ inside the store
    result = evaluate_all(store_root, out_root=OUT)   # OUT itself
"""

from __future__ import annotations

import dataclasses
import datetime
import logging
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import pyarrow as pa

from simsplat_core.eval.plan import EvalStep, StoreContents, plan_evaluation
from simsplat_core.eval.store_tables import (
    RECONSTRUCTION_SPEC,
    THROUGHPUT_SPEC,
    SceneMetrics,
    StageTiming,
    reconstruction_table,
    throughput_table,
)
from simsplat_core.eval.table_registry import summary_markdown, table_spec
from simsplat_core.types import SYNTHETIC_SOURCE
from storage import ArtifactStore, list_logs, list_scenes, read_scene_manifest, require_log_manifest
from storage.alignment import list_aligner_models, read_aligner_manifest
from storage.assets import list_asset_banks
from storage.edits import edit_run_ids, read_edit_records
from storage.language_scenes import list_language_scenes
from storage.runs import new_run_id, read_run_table, run_dir, run_table, write_run_tables
from storage.scenes import metrics_from_json
from storage.store import join_relpath
from tasks.code_version import code_version
from tasks.progress import publish_table

logger = logging.getLogger(__name__)

SUMMARY_NAME = "summary.md"


@dataclass(frozen=True)
class EvalAllConfig:
    """Settings handed to the evaluations (their own defaults; smaller values make a quick run).

    Attributes:
        groups: the evaluations to consider (default: all of ``simsplat_core.eval.plan.EVAL_GROUPS``).
        per_category, infeasible: editing prompts per category / infeasible prompts (motion uses ``per_category``).
        per_kind: interaction prompts of each kind per scene (motion).
        per_sequence, max_attempts, clients: the mining evaluation's.
        seed: seed of the prompt sets and the mining loop.
    """

    groups: tuple[str, ...] | None = None
    per_category: int = 30
    infeasible: int = 20
    per_kind: int = 3
    per_sequence: int = 3
    max_attempts: int = 3
    clients: tuple[str, ...] = ("rule", "openai")
    seed: int = 0


@dataclass(frozen=True)
class EvalAllResult:
    """What :func:`evaluate_all` returns (small).

    Attributes:
        run_id: the run's id.
        run_dir: URI of the run directory.
        tables: table name -> Parquet URI, in the order written.
        skipped: evaluation -> why it was skipped.
        seconds: evaluation -> wall time.
        summary: URI of ``summary.md``.
        out_root, out_relpath: where the run directory is (``tasks.run_tables.load_run_tables(out_root,
            out_relpath)`` reads its tables back).
    """

    run_id: str
    run_dir: str
    tables: dict[str, str]
    skipped: dict[str, str]
    seconds: dict[str, float] = field(default_factory=dict)
    summary: str = ""
    out_root: str = ""
    out_relpath: str = ""


def store_contents(store: ArtifactStore) -> StoreContents:
    """What ``store`` holds (logs by kind, scenes, language scenes, an asset bank, runs with stage timings)."""
    logs = list_logs(store)
    manifests = {s: require_log_manifest(store, s) for s in logs}
    synthetic = tuple(s for s, m in manifests.items() if m.get("source") == SYNTHETIC_SOURCE)
    truth = tuple(s for s in synthetic if int(manifests[s].get("images", {}).get("count", 0)) > 0)
    return StoreContents(
        logs=tuple(logs), synthetic=synthetic, ground_truth=truth,
        scenes=tuple(s for s in logs if list_scenes(store, s)),
        aligned=tuple(s for s in logs if list_language_scenes(store, s)),
        asset_bank=bool(list_asset_banks(store)), timed_runs=tuple(edit_run_ids(store)))


def content_keys(store: ArtifactStore, contents: StoreContents) -> dict[str, Any]:
    """The content keys of what the evaluations read: logs, newest scenes, language scenes, the newest asset bank."""
    keys: dict[str, Any] = {"logs": {s: require_log_manifest(store, s)["key"] for s in contents.logs}}
    keys["scenes"] = {s: list_scenes(store, s)[0] for s in contents.scenes}
    keys["language_scenes"] = {s: "/".join(list_language_scenes(store, s)[0]) for s in contents.aligned}
    banks = list_asset_banks(store)
    keys["asset_bank"] = banks[0] if banks else ""
    return keys


def reconstruction_rows(store: ArtifactStore, seq_ids: Sequence[str]) -> list[SceneMetrics]:
    """Every stored scene's recorded metrics (``_SUCCESS.json``), newest scene first within a sequence."""
    scenes = []
    for seq_id in seq_ids:
        for scene_hash in list_scenes(store, seq_id):
            manifest = read_scene_manifest(store, seq_id, scene_hash) or {}
            scenes.append(SceneMetrics(seq_id, scene_hash, metrics_from_json(manifest.get("metrics", {}))))
    return scenes


def stage_timings(store: ArtifactStore, seq_ids: Sequence[str], edit_runs: Sequence[str]) -> list[StageTiming]:
    """Recorded stage timings: each scene's ``wall_time_s``, each aligner's ``train_seconds``, and the
    ``seconds_<stage>`` of every mined attempt of ``edit_runs``."""
    timings = []
    for scene in reconstruction_rows(store, seq_ids):
        seconds = scene.metrics.get("wall_time_s", math.nan)
        if math.isfinite(seconds):
            timings.append(StageTiming("reconstruct", 1, seconds))
    for model_hash in list_aligner_models(store):
        seconds = float((read_aligner_manifest(store, model_hash) or {}).get("metrics", {}).get("train_seconds", -1))
        if seconds >= 0:
            timings.append(StageTiming("align", 1, seconds))
    for run_id in edit_runs:
        for record in read_edit_records(store, run_id):
            for column, value in record.mining.items():
                if column.startswith("seconds_") and value is not None:
                    timings.append(StageTiming(f"mine:{column[len('seconds_'):]}", 1, float(value)))
    return timings


Runner = Callable[[EvalStep], None]


def _runners(store_root: str, out_root: str, rel: str, config: EvalAllConfig,
             contents: StoreContents) -> dict[str, Runner]:
    """One callable per evaluation group: runs its task, writing its tables under ``rel`` of ``out_root``."""
    from tasks.editing_eval import evaluate_editing_run
    from tasks.grounding_eval import evaluate_grounding_run
    from tasks.mining_eval import evaluate_mining_run
    from tasks.motion_eval import RealOptions, evaluate_motion_run
    from tasks.search_eval import search_run_table

    store = ArtifactStore(store_root)
    out = ArtifactStore(out_root)

    def reconstruction(step: EvalStep) -> None:
        table = reconstruction_table(reconstruction_rows(store, step.seq_ids))
        write_run_tables(out, rel, {RECONSTRUCTION_SPEC.name: run_table(RECONSTRUCTION_SPEC, table)})

    def throughput(step: EvalStep) -> None:
        table = throughput_table(stage_timings(store, step.seq_ids, contents.timed_runs))
        write_run_tables(out, rel, {THROUGHPUT_SPEC.name: run_table(THROUGHPUT_SPEC, table)})

    def grounding(step: EvalStep) -> None:
        evaluate_grounding_run.fn(store_root, list(step.seq_ids), out_root, rel)

    def editing(step: EvalStep) -> None:
        evaluate_editing_run.fn(store_root, step.seq_ids, out_root, rel, per_category=config.per_category,
                                infeasible=config.infeasible, seed=config.seed)

    def motion(step: EvalStep) -> None:
        evaluate_motion_run.fn(out_root, [], [], store_root=store_root, out_relpath=rel, seq_ids=step.seq_ids,
                               options=RealOptions(edits=False), per_category=config.per_category,
                               per_kind=config.per_kind)

    def mining(step: EvalStep) -> None:
        evaluate_mining_run.fn(store_root, step.seq_ids, out_root, rel, clients=config.clients,
                               per_sequence=config.per_sequence, max_attempts=config.max_attempts, seed=config.seed)

    def search(step: EvalStep) -> None:
        table = search_run_table(store_root, step.seq_ids)
        if table is not None:
            write_run_tables(out, rel, {"search": table})

    return {"reconstruction": reconstruction, "throughput": throughput, "grounding": grounding, "editing": editing,
            "motion": motion, "mining": mining, "search": search}


def evaluate_all(store_root: str, out_root: str | None = None, run_id: str | None = None,
                 config: EvalAllConfig | None = None) -> EvalAllResult:
    """Compute every table the store allows into one run directory (module docstring).

    Args:
        out_root: the run directory itself (``None``: ``runs/<run_id>/`` inside the store).
        run_id: the run's id (default: a new ``eval-<time>`` id).

    Raises:
        ValueError: the store holds no log.
        KeyError: an unknown evaluation group in ``config.groups``.
    """
    config = config or EvalAllConfig()
    store = ArtifactStore(store_root)
    contents = store_contents(store)
    if not contents.logs:
        raise ValueError(f"no driving log in {store.uri('logs')}: nothing to evaluate")
    run_id = run_id or new_run_id("eval")
    out_root_used, rel = (out_root, "") if out_root is not None else (store_root, run_dir(run_id))
    out = ArtifactStore(out_root_used)
    runners = _runners(store_root, out_root_used, rel, config, contents)
    skipped: dict[str, str] = {}
    seconds: dict[str, float] = {}
    parts: dict[str, Any] = {}
    written: dict[str, pa.Table] = {}
    for step in plan_evaluation(contents, config.groups):
        if not step.runs:
            logger.info("eval all: %s skipped: %s", step.group, step.skip)
            skipped[step.group] = step.skip
            continue
        started = time.perf_counter()
        runners[step.group](step)
        seconds[step.group] = round(time.perf_counter() - started, 3)
        parts[step.group] = out.read_json(join_relpath(rel, "manifest.json"))
        for name in step.tables:
            try:
                written[name] = read_run_table(out, rel, table_spec(name))
            except FileNotFoundError:
                logger.info("eval all: %s wrote no %s table", step.group, name)
                continue
            publish_table(table_spec(name), written[name])
        logger.info("eval all: %s done in %.1f s", step.group, seconds[step.group])
    summary = join_relpath(rel, SUMMARY_NAME)
    out.write_bytes(summary, summary_markdown(run_id, written, skipped, seconds).encode("utf-8"))
    manifest = {
        "written_at": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "stage": "eval-all", "run_id": run_id, "code_version": code_version(), "store": store.uri(),
        "config": dataclasses.asdict(config), "content_keys": content_keys(store, contents),
        "tables": list(written), "skipped": skipped, "seconds": seconds,
        "table_seconds": {name: seconds[g] for g, m in parts.items() for name in m.get("tables", ())
                          if name in written},
        "evaluations": parts,
    }
    out.write_json(join_relpath(rel, "manifest.json"), manifest)
    return EvalAllResult(run_id, out.uri(rel), {name: out.uri(join_relpath(rel, "tables", f"{name}.parquet"))
                                                for name in written}, skipped, seconds, out.uri(summary),
                         out_root_used, rel)


__all__ = ["EvalAllConfig", "EvalAllResult", "content_keys", "evaluate_all", "reconstruction_rows",
           "stage_timings", "store_contents"]
