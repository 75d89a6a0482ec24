"""Task: evaluate free-form grounding on the stored language scenes of synthetic logs (SIMSplat Tables 2, 3).

Builds the benchmark from the logs' ground truth (paraphrased queries per target, group and no-match
queries, instance masks), runs every method of ``grounding_methods`` on the stored language scenes
(whose node-id maps were rendered from the reconstructed Gaussians) and writes the tables into the
run directory: ``tables/grounding.{parquet,md}`` (Table 2), ``tables/grounding_ablation.{parquet,md}``
(Table 3) and ``tables/grounding_outcomes.parquet`` (every method's answer to every query).
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass

from prefect import task
from prefect.cache_policies import NO_CACHE

from simsplat_core.eval.grounding.benchmark import BenchmarkConfig, build_benchmark
from simsplat_core.eval.grounding.methods import ABLATION_ROW_METHODS, COMPARISON_ROWS, grounding_methods
from simsplat_core.eval.grounding.metrics import evaluate_grounding
from simsplat_core.eval.grounding.tables import (
    ABLATION_SPEC,
    GROUNDING_SPEC,
    OUTCOMES_SPEC,
    ablation_table,
    grounding_outcomes_table,
    grounding_table,
)
from simsplat_core.language.grounding.engine import QueryEngine
from simsplat_core.language.text import default_text_encoder
from storage import ArtifactStore, read_scene_log
from storage.language_scenes import read_language_scene
from storage.runs import run_table, write_run_tables
from tasks.retry_policy import STAGE_RETRIES

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class GroundingEvaluation:
    """What ``evaluate_grounding_run`` returns (small).

    Attributes:
        seq_ids: the evaluated sequences.
        queries: benchmark queries (all methods answer each).
        scores: ``{method: {category: {"acc", "viou", "queries"}}}``.
        tables: ``name -> Parquet URI``.
        seconds: wall time.
    """

    seq_ids: tuple[str, ...]
    queries: int
    scores: dict[str, dict[str, dict[str, float]]]
    tables: dict[str, str]
    seconds: float


@task(name="evaluate-grounding", cache_policy=NO_CACHE, **STAGE_RETRIES.task_options())
def evaluate_grounding_run(store_root: str, seq_ids: list[str], out_root: str, out_relpath: str = "",
                           benchmark: BenchmarkConfig | None = None) -> GroundingEvaluation:
    """Evaluate grounding on the newest language scene of each of ``seq_ids`` and write the run's tables.

    Args:
        store_root: the store holding ``logs/`` (with ground-truth instance masks) and ``alignment/``.
        out_root, out_relpath: the run directory (``ArtifactStore(out_root)`` / ``out_relpath``).

    Raises:
        FileNotFoundError: a log or language scene is missing (named).
        ValueError: no sequence given, or none has ground-truth instance masks.
    """
    if not seq_ids:
        raise ValueError("evaluate_grounding_run: no sequences to evaluate")
    started = time.perf_counter()
    store = ArtifactStore(store_root)
    logs = {seq_id: read_scene_log(store, seq_id) for seq_id in seq_ids}
    without_truth = [s for s, log in logs.items() if not any(img.instance is not None for img in log.images)]
    if len(without_truth) == len(logs):
        raise ValueError(f"no ground-truth instance masks in {sorted(logs)}: grounding needs synthetic logs")
    logs = {s: log for s, log in logs.items() if s not in without_truth}
    scenes = [read_language_scene(store, seq_id, with_records=False).scene for seq_id in logs]
    bench = build_benchmark(list(logs.values()), benchmark or BenchmarkConfig())
    encoder = default_text_encoder()
    engine = QueryEngine(encoder)
    embedded = engine.prepare([q.text for q in bench.queries])  # batched: ~4x faster than one by one
    logger.info("embedded %d query texts and parts for %d queries", embedded, len(bench.queries))
    results = evaluate_grounding(scenes, bench, grounding_methods(encoder, logs, engine=engine))
    summary = results.summary()
    table2 = grounding_table(summary, COMPARISON_ROWS)
    table3 = ablation_table(summary, ABLATION_ROW_METHODS)
    outcomes = grounding_outcomes_table(results)
    latency = results.latency("ours")
    tables = {
        spec.name: run_table(spec, table)
        for spec, table in ((GROUNDING_SPEC, table2), (ABLATION_SPEC, table3), (OUTCOMES_SPEC, outcomes))
    }
    manifest = {"stage": "grounding", "sequences": sorted(logs), "skipped_without_ground_truth": without_truth,
                "queries": len(bench.queries), "query_counts": bench.counts(), "latency_ours_s": latency}
    uris = write_run_tables(ArtifactStore(out_root), out_relpath, tables, manifest)
    scores = {m: {c: {"acc": s.accuracy, "viou": s.viou, "queries": float(s.queries)} for c, s in per.items()}
              for m, per in summary.items()}
    seconds = time.perf_counter() - started
    ours = summary["ours"]["total"]
    logger.info("grounding on %d sequences, %d queries: ours acc %.3f vIoU %.3f (%.1f s)", len(logs),
                len(bench.queries), ours.accuracy, ours.viou, seconds)
    return GroundingEvaluation(tuple(sorted(logs)), len(bench.queries), scores, uris, round(seconds, 3))
